"""Targets that mean something: a benchmark exits non-zero when a target row fails.

Every script ends with ``raise SystemExit(run_benchmark(main, ...))``:

* the script's output is printed as it comes and kept;
* the run **fails** (exit code 1) when ``main`` returns a non-zero code or
  raises, or when a line of the output says a target failed: the word
  ``FAIL`` or ``MISSED`` (:data:`FAILED_TARGET`). Scripts print their target
  rows with :func:`verdict` (``PASS``/``FAIL``);
* with ``FTKIN_BENCH_RECORD=1`` (``make bench``) the output is recorded in
  ``benchmarks/results/<script>.txt`` under a header naming the date, the
  command, the machine (``nproc``, CPU model, Python) and the load average at
  start and end, and the exit code. The docs quote figures from these files
  (``tests/test_docs_reference.py`` checks it, see docs/benchmarks.md).
"""

from __future__ import annotations

import datetime
import io
import os
import platform
import re
import sys
import time
from pathlib import Path

FAILED_TARGET = re.compile(r"\b(FAIL|MISSED)\b")
"""A printed line matching this reports a failed target."""

RESULTS = Path(__file__).resolve().parent / "results"
"""Where ``make bench`` records each script's output."""


def verdict(ok: bool) -> str:
    """``"PASS"`` or ``"FAIL"``, the word a target row prints."""
    return "PASS" if ok else "FAIL"


class _Tee(io.TextIOBase):
    def __init__(self, stream):
        self.stream, self.buffer_ = stream, io.StringIO()

    def write(self, text: str) -> int:
        self.stream.write(text)
        return self.buffer_.write(text)

    def flush(self) -> None:
        self.stream.flush()


def cpu_model() -> str:
    """The CPU model name (``/proc/cpuinfo``), or the platform's processor string."""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown CPU"


def _load() -> str:
    try:
        return " ".join(f"{value:.2f}" for value in os.getloadavg())
    except OSError:
        return "unknown"


def header(script: str, argv: list[str], load_at_start: str, seconds: float, code: int) -> str:
    """The header of a recorded result: date, command, machine, load, duration, exit code."""
    date = datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC")
    return "\n".join(
        [
            f"# benchmark: {script} {' '.join(argv)}".rstrip(),
            f"# date: {date}",
            f"# machine: nproc {os.cpu_count()}, {cpu_model()}, Python {platform.python_version()}",
            f"# load average (1, 5, 15 min): {load_at_start} at start, {_load()} at end",
            f"# duration: {seconds:.0f} s, exit code {code}",
            "",
        ]
    )


def run_benchmark(main, *args, **kwargs) -> int:
    """Run ``main(*args, **kwargs)``; 1 when it fails or a target row says FAIL, else 0.

    Records the output when ``FTKIN_BENCH_RECORD`` is set (see the module docstring).
    """
    script = Path(sys.argv[0]).name
    tee, stdout = _Tee(sys.stdout), sys.stdout
    load_at_start, started = _load(), time.perf_counter()
    sys.stdout = tee
    code = 1
    try:
        returned = main(*args, **kwargs)
        code = int(returned) if isinstance(returned, int) else 0
    finally:
        sys.stdout = stdout
        output = tee.buffer_.getvalue()
        failed = [line for line in output.splitlines() if FAILED_TARGET.search(line)]
        if failed and code == 0:
            code = 1
        if os.environ.get("FTKIN_BENCH_RECORD", "") not in ("", "0"):
            RESULTS.mkdir(exist_ok=True)
            text = header(script, sys.argv[1:], load_at_start, time.perf_counter() - started, code)
            (RESULTS / f"{Path(script).stem}.txt").write_text(text + output)
    if failed:
        print(f"{script}: {len(failed)} target row(s) failed:", file=sys.stderr)
        for line in failed:
            print(f"  {line.strip()}", file=sys.stderr)
    return code
