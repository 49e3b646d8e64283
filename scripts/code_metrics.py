"""Code metrics for the consolidation targets: AST statements and lines of ftkin/ (without the
robot stage), and every function body over 60 lines. Usage: python scripts/code_metrics.py [ROOT]
"""

import ast
import pathlib
import sys

root = sys.argv[1] if len(sys.argv) > 1 else "ftkin"
n = 0
lines = 0
longf = []
for p in sorted(pathlib.Path(root).rglob("*.py")):
    if "/robot/" in str(p):
        continue
    src = p.read_text()
    t = ast.parse(src)
    lines += len(src.splitlines())
    n += sum(isinstance(x, ast.stmt) for x in ast.walk(t))
    for f in ast.walk(t):
        if isinstance(f, (ast.FunctionDef, ast.AsyncFunctionDef)):
            body = f.body
            if (
                body
                and isinstance(body[0], ast.Expr)
                and isinstance(getattr(body[0], "value", None), ast.Constant)
                and isinstance(body[0].value.value, str)
            ):
                body = body[1:]
            if not body:
                continue
            ln = body[-1].end_lineno - body[0].lineno + 1
            if ln > 60:
                longf.append((ln, f"{p}:{f.lineno} {f.name}"))
print("statements", n, "lines", lines)
for x in sorted(longf, reverse=True):
    print(*x)
