"""Every code block of README.md and docs/*.md runs as a test (Sybil), in a scratch folder.

* ```` ```python ```` blocks run in one namespace per page, in order;
* ```` ```bash ```` blocks run with ``bash -euo pipefail`` and ```` ```console ```` blocks run
  their ``$ `` lines, with this checkout's ``ftkin`` first on the ``PATH``;
* each page runs in its own empty folder (its tour makes its inputs with
  ``ftkin simulate ...``); ```` ```text ```` blocks are output and are not run.

Markers, in HTML comments right before a block (Sybil's skip directive):

* ``<!-- skip: next "fragment: <the context it needs>" -->``: a fragment, not run;
* ``<!-- skip: next if(not SLOW, "slow: <why>") -->``: run only by ``make docs-test``
  (``FTKIN_DOCS_SLOW=1``): a browser, a server, or a long run.

The summary line of ``pytest`` says how many blocks ran and how many are fragments.
"""

from __future__ import annotations

import os
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
    return env


def _run_shell(script: str, example) -> None:
    done = subprocess.run(
        ["bash", "-euo", "pipefail", "-c", script],
        cwd=example.namespace["_scratch"],
        env=_environment(),
        capture_output=True,
        text=True,
        timeout=SHELL_TIMEOUT,
    )
    if done.returncode != 0:
        raise AssertionError(
            f"exit code {done.returncode} of\n{script}\n--- stdout\n{done.stdout[-4000:]}"
            f"\n--- stderr\n{done.stderr[-4000:]}"
        )


def evaluate_bash(example) -> None:
    _run_shell(example.parsed, example)


def evaluate_console(example) -> None:
    commands = [line[2:] for line in example.parsed.splitlines() if line.startswith("$ ")]
    _run_shell("\n".join(commands), example)


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
