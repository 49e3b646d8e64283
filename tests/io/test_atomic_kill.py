"""A writer killed midway (SIGKILL) leaves the old file intact, for every ftkin writer."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from ftkin.io.calibration_file import load_calibration, save_calibration
from ftkin.io.csv_table import read_table
from ftkin.sim.paper import paper_calibration

# The child slows fsync down, so it is killed after writing the temporary file
# and before the rename: exactly the window an atomic write must survive.
CHILD = textwrap.dedent(
    """
    import os, sys, time
    real_fsync = os.fsync
    def slow_fsync(fd):
        print("writing", flush=True)
        time.sleep(60)
        real_fsync(fd)
    os.fsync = slow_fsync
    kind, target = sys.argv[1], sys.argv[2]
    if kind == "calibration":
        from ftkin.io.calibration_file import save_calibration
        from ftkin.sim.sensor import paper_like_truth
        from ftkin.sim.paper import paper_calibration
        result = paper_calibration()
        import dataclasses
        save_calibration(dataclasses.replace(result, g=9.81), target)
    elif kind == "csv":
        from ftkin.io.csv_table import write_csv
        write_csv(target, ["a", "b"], [[float(i), "x"] for i in range(100000)])
    """
)


@pytest.mark.skipif(sys.platform == "win32", reason="SIGKILL is POSIX")
@pytest.mark.parametrize("kind", ["calibration", "csv"])
def test_killed_writer_leaves_old_file_intact(tmp_path, kind):
    target = tmp_path / ("calib.json" if kind == "calibration" else "out.csv")
    if kind == "calibration":
        save_calibration(paper_calibration(), target)
    else:
        target.write_text("a,b\n1.0,old\n")
    before = target.read_bytes()
    child = subprocess.Popen(
        [sys.executable, "-c", CHILD, kind, str(target)], stdout=subprocess.PIPE, text=True
    )
    try:
        assert child.stdout.readline().strip() == "writing"
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait(timeout=10)
    assert child.returncode == -signal.SIGKILL
    assert target.read_bytes() == before
    if kind == "calibration":
        assert load_calibration(target).g == 9.8
    else:
        assert read_table(target).rows == [["1.0", "old"]]
    leftovers = [p.name for p in tmp_path.iterdir() if p.name != target.name]
    assert all(name.startswith(f".{target.name}.") and name.endswith(".tmp") for name in leftovers)
