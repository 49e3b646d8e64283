"""A calibration is a declared type: no code probes it for optional parts with ``getattr``."""

from __future__ import annotations

import ast
import pathlib

import ftkin

PROBED = ("calibration", "result", "compensator")
"""Names of objects whose optional parts are declared fields (never looked up with a default)."""


def _probes(path: pathlib.Path) -> list[str]:
    found = []
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if not (
            isinstance(node, ast.Call) and getattr(node.func, "id", None) in ("getattr", "hasattr")
        ):
            continue
        target = ast.unparse(node.args[0])
        literal = len(node.args) > 1 and isinstance(node.args[1], ast.Constant)
        if literal and target.split(".")[-1] in PROBED:
            found.append(f"{path}:{node.lineno} {ast.unparse(node)}")
    return found


def test_no_getattr_probes_on_calibrations():
    root = pathlib.Path(ftkin.__file__).parent
    probes = [probe for path in sorted(root.rglob("*.py")) for probe in _probes(path)]
    assert probes == []
