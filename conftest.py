"""Every code block of README.md and docs/*.md runs as a test (Sybil), in a scratch folder.

* ```` ```python ```` blocks run in one namespace per page, in order;
* ```` ```bash ```` blocks run with ``bash -euo pipefail`` and ```` ```console ```` blocks run
  their ``$ `` lines (a line ending in ``\\`` continues on the next), with this checkout's
  ``ftkin`` first on the ``PATH``;
* each page runs in its own empty folder (its tour makes its inputs with
  ``ftkin simulate ...``).

Printed output is checked, so that it cannot go stale:

* the lines of a ```` ```console ```` block that do not start with ``$ `` are the output of the
  command above them;
* a ```` ```text ```` block is the output of the ```` ```bash ```` or ```` ```console ```` block
  before it when nothing but blank lines separates them, or when it is a transcript (its first
  line starts with ``$ ``) and no other code block comes between; a transcript's ``$ `` lines
  must be commands of that block (comments and spacing aside). A transcript anywhere else
  fails: mark it as a fragment. Any other ```` ```text ```` block (a layout, a formula, the
  output of Python) is not checked.

The rule of the comparison: every expected line (``$ `` lines and blank lines aside) must be a
line of what the block printed (stdout and stderr together), in the same order; lines of the
output in between are allowed (so a lone ``...`` line is only a reminder that some were left
out). In a line, spacing is free; ``...`` stands for any text (a time, a path, a figure that
depends on the machine); a number is compared as a number: an integer exactly, a decimal within
one unit of its last printed digit (the last digit of a float can differ between CPUs).
A command of a ```` ```console ```` block may fail only where its expected output shows
``ftkin: error:`` (then it must fail, with that message) or a line ``(exit code N)`` (then it
must exit with N: ``ftkin doctor`` exits 1 when it names a mistake).

Markers, in HTML comments right before a block (Sybil's skip directive):

* ``<!-- skip: next "fragment: <the context it needs>" -->``: a fragment, not run (its output,
  if any, is not checked);
* ``<!-- skip: next if(not SLOW, "slow: <why>") -->``: run only by ``make docs-test``
  (``FTKIN_DOCS_SLOW=1``): a browser, a server, or a long run.

The summary line of ``pytest`` says how many blocks ran and how many are fragments.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from sybil import Sybil
from sybil.parsers.markdown import CodeBlockParser, PythonCodeBlockParser, SkipParser

ROOT = Path(__file__).resolve().parent
SLOW = os.environ.get("FTKIN_DOCS_SLOW", "") not in ("", "0")
SHELL_TIMEOUT = 600.0  # [s] one block


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{env.get('PATH', '')}"
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH", "")]))
    env["MPLBACKEND"] = "Agg"
    env["FTKIN_REPO"] = str(ROOT)
    env["PYTHONUNBUFFERED"] = "1"  # stdout and stderr interleaved as a terminal shows them
    return env


def _run_shell(script: str, example) -> str:
    """Run ``script`` in the page's folder; its stdout and stderr, interleaved as printed."""
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", script],
        cwd=example.namespace["_scratch"],
        env=_environment(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=SHELL_TIMEOUT,
    )
    if done.returncode != 0:
        raise AssertionError(
            f"exit code {done.returncode} of\n{script}\n--- output\n{done.stdout[-6000:]}"
        )
    return done.stdout


NUMBER = re.compile(r"[-+]?\d+(?:\.\d+)?(?:[eE][-+]?\d+)?")
MARK = "@@ftkin-docs-command-done"
EXIT_CODE = re.compile(r"\(exit code (\d+)\)")


def _line_pattern(expected: str) -> tuple[re.Pattern, list[str]]:
    """A regex for one expected output line and the numbers it holds (see the module's rule)."""
    parts, numbers = [], []
    for k, piece in enumerate(expected.strip().split("...")):
        if k:
            parts.append(".*?")
        position = 0
        for match in NUMBER.finditer(piece):
            parts.append(_text_pattern(piece[position : match.start()]))
            parts.append(f"({NUMBER.pattern})")
            numbers.append(match.group())
            position = match.end()
        parts.append(_text_pattern(piece[position:]))
    return re.compile("".join(parts)), numbers


def _text_pattern(text: str) -> str:
    return r"\s*".join(re.escape(word) for word in text.split(" ")) if text else ""


def _same_number(expected: str, actual: str) -> bool:
    if not re.search(r"[.eE]", expected):
        return re.search(r"[.eE]", actual) is None and int(expected) == int(actual)
    decimals = len(expected.split(".")[1]) if "." in expected.split("e")[0].split("E")[0] else 0
    exponent = re.search(r"[eE]([-+]?\d+)", expected)
    unit = 10.0 ** (-decimals + (int(exponent[1]) if exponent else 0))
    return abs(float(actual) - float(expected)) <= unit * (1 + 1e-9)


def line_matches(expected: str, actual: str) -> bool:
    """Whether the output line ``actual`` is the expected line (see the module's rule)."""
    pattern, numbers = _line_pattern(re.sub(r"\s+", " ", expected))
    match = pattern.fullmatch(actual.strip())
    return match is not None and all(map(_same_number, numbers, match.groups()))


def check_output(expected_lines: list[str], output: str, where: str) -> None:
    """Every expected line is a line of ``output``, in order (lines in between allowed)."""
    actual = output.splitlines()
    position = 0
    for line in expected_lines:
        if not line.strip() or line.strip() == "...":
            continue
        found = next(
            (k for k in range(position, len(actual)) if line_matches(line, actual[k])), None
        )
        if found is None:
            raise AssertionError(
                f"{where}: the docs show the line\n  {line.strip()}\nwhich is not in what the "
                "command printed (after the lines matched before it; numbers: integers exact, "
                "decimals to their last printed digit; '...' for what varies). It printed:\n"
                + "\n".join(actual[position:][:60])
            )
        position = found + 1


def console_commands(source: str) -> list[tuple[str, list[str]]]:
    """``(command, expected output lines)`` of a console block (``\\`` continues a command)."""
    commands: list[tuple[str, list[str]]] = []
    continued = False
    for line in source.splitlines():
        if continued:
            commands[-1] = (f"{commands[-1][0]}\n{line}", commands[-1][1])
        elif line.startswith("$ "):
            commands.append((line[2:], []))
        elif commands:
            commands[-1][1].append(line)
        continued = (line.startswith("$ ") or continued) and line.endswith("\\")
    return commands


def _normal_command(command: str) -> str:
    """A command without its trailing comment, continuations and spacing."""
    command = re.sub(r"\\\n", " ", command)
    command = re.sub(r"\s+#[^'\"]*$", "", command.strip())
    return " ".join(command.split())


def _remember(example, output: str, commands: list[str]) -> None:
    example.namespace["_shell"] = {
        "end": example.region.end,
        "output": output,
        "commands": {_normal_command(c) for c in commands},
    }


def evaluate_bash(example) -> None:
    output = _run_shell(example.parsed, example)
    commands = [line for line in example.parsed.splitlines() if line.strip()]
    _remember(example, output, commands)


def evaluate_console(example) -> None:
    """Each command in turn; its output checked; a failure allowed only where shown."""
    script, commands = [], console_commands(example.parsed)
    for k, (command, _) in enumerate(commands):
        script.append(f'set +e\n{{\n{command}\n}}\necho "{MARK} {k} $?"\nset -e')
    output = _run_shell("\n".join(script), example)
    pieces = re.split(rf"^{MARK} (\d+) (\d+)$", output, flags=re.MULTILINE)
    for k, (command, expected) in enumerate(commands):
        printed, code = pieces[3 * k], int(pieces[3 * k + 2])
        stated = [int(m[1]) for m in map(EXIT_CODE.fullmatch, expected) if m]
        shows_error = any(line.startswith("ftkin: error:") for line in expected)
        if stated and code != stated[0] or not stated and bool(code) != shows_error:
            shown = f"exit code {stated[0]}" if stated else "an error" if shows_error else "success"
            raise AssertionError(
                f"the docs show {shown}, but exit code {code} of\n{command}\n--- output\n"
                + printed[-6000:]
            )
        expected = [line for line in expected if not EXIT_CODE.fullmatch(line)]
        check_output(expected, printed, f"{example.path}, line {example.line}: {command}")
    _remember(example, output, [command for command, _ in commands])


def evaluate_text(example) -> None:
    """A text block that is the output of the shell block before it is compared to it."""
    text = example.document.text
    lines = example.parsed.splitlines()
    transcript = bool(lines) and lines[0].startswith("$ ")
    shell = example.namespace.get("_shell")
    between = text[shell["end"] : example.region.start] if shell else None
    if between is not None and (not between.strip() or (transcript and "```" not in between)):
        where = f"{example.path}, line {example.line}"
        for command, _ in console_commands(example.parsed):
            if _normal_command(command) not in shell["commands"]:
                raise AssertionError(
                    f"{where}: the transcript shows `{command}`, which the block before it "
                    "does not run"
                )
        check_output([line for line in lines if not line.startswith("$ ")], shell["output"], where)
    elif transcript:
        raise AssertionError(
            f"{example.path}, line {example.line}: a transcript (`$ ` lines) that no block runs: "
            "put it right after the block that runs its commands, make it a console block, "
            'or mark it <!-- skip: next "fragment: ..." -->'
        )


def setup(namespace: dict) -> None:
    scratch = tempfile.mkdtemp(prefix="ftkin-docs-")
    namespace.update(_scratch=scratch, _cwd=os.getcwd(), SLOW=SLOW, FTKIN_REPO=str(ROOT))
    os.environ.setdefault("MPLBACKEND", "Agg")
    os.chdir(scratch)


def teardown(namespace: dict) -> None:
    import shutil

    os.chdir(namespace["_cwd"])
    shutil.rmtree(namespace["_scratch"], ignore_errors=True)


pytest_collect_file = Sybil(
    parsers=[
        SkipParser(),
        PythonCodeBlockParser(),
        CodeBlockParser(language="bash", evaluator=evaluate_bash),
        CodeBlockParser(language="console", evaluator=evaluate_console),
        CodeBlockParser(language="text", evaluator=evaluate_text),
    ],
    patterns=["README.md", "docs/*.md"],
    setup=setup,
    teardown=teardown,
).pytest()

_COUNTS = {"executed": 0, "fragment": 0, "slow": 0, "failed": 0}


def pytest_runtest_logreport(report) -> None:
    if ".md" not in report.nodeid.split("::")[0]:
        return
    if report.when == "call" and report.passed:
        _COUNTS["executed"] += 1
    elif report.failed:
        _COUNTS["failed"] += 1
    elif report.skipped:
        reason = str(report.longrepr[-1]) if isinstance(report.longrepr, tuple) else ""
        reason = reason.removeprefix("Skipped: ")
        _COUNTS["slow" if reason.startswith("slow") else "fragment"] += 1


def pytest_terminal_summary(terminalreporter) -> None:
    if any(_COUNTS.values()):
        terminalreporter.write_line(
            f"docs code blocks: {_COUNTS['executed']} executed, {_COUNTS['fragment']} marked as "
            f"fragments, {_COUNTS['slow']} slow (make docs-test), {_COUNTS['failed']} failed"
        )
