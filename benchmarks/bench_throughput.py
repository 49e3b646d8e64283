"""Batch throughput, import time and planning time, each beside its floor measured in the same run.

Rows (medians over repeats; floor and ftkin alternate so a load change hits both):

* public ``compensate_batch`` (validated rotations) vs the numpy einsum floor
  (same arithmetic, no checks): target >= 0.5x the floor's samples/s;
* compensating a log from joint angles (``compensate_batch``, batched
  numpy FK) for the bundled arm and the UR5: target >= 5 M samples/s; the
  floor column is the old path (Pinocchio FK per row + einsum), for reference;
* ``import ftkin`` and ``import ftkin`` + every public name vs
  ``import numpy, pinocchio`` in fresh interpreters: target <= 1.5x;
* ``ftkin --version`` vs an empty interpreter: target < 0.4 s;
* ``ftkin plan --n 12`` and ``--n 200`` (fresh interpreter each): targets 1 s and 5 s.

Batch rows use process CPU time; interpreter rows wall time (what a user
waits) and, in brackets, the children's CPU time (less sensitive to a shared
machine's load). The children cache their compiled modules like an installed
ftkin (``PYTHONDONTWRITEBYTECODE`` is ignored; the cache, warmed by an untimed
first run, lives in the temporary folder). The load average is printed.

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/bench_throughput.py [--quick]``
"""

from __future__ import annotations

import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pinocchio as pin

import ftkin
from ftkin import Arm, Compensator
from ftkin.sim.sensor import paper_like_truth

ROOT = Path(__file__).resolve().parent.parent


def _cpu(function) -> float:
    start = time.process_time()
    function()
    return time.process_time() - start


def paired_rate(floor, function, samples: int, repeats: int) -> tuple[float, float, float]:
    """Median samples/s of ``floor`` and ``function`` and the median ratio ftkin / floor
    (alternating).
    """
    floor()
    function()
    floors, values = [], []
    for repeat in range(repeats):
        order = (floor, function) if repeat % 2 == 0 else (function, floor)
        times = [_cpu(timed) for timed in order]
        floor_time, time_ = times if repeat % 2 == 0 else times[::-1]
        floors.append(samples / floor_time)
        values.append(samples / time_)
    return (
        float(np.median(floors)),
        float(np.median(values)),
        float(np.median(np.array(values) / np.array(floors))),
    )


BYTECODE_CACHE = Path(tempfile.gettempdir()) / "ftkin-bench-pycache"
"""Where the child interpreters keep their compiled modules (outside the checkout)."""


def run(code: str) -> tuple[float, float]:
    """Wall and CPU seconds of ``python -c code`` in a fresh interpreter (output discarded).

    The child caches compiled modules (as an installed ftkin has its ``.pyc``):
    ``PYTHONDONTWRITEBYTECODE`` is dropped and the cache kept in
    :data:`BYTECODE_CACHE`; a first, untimed run warms it. Otherwise every run
    would time Python compiling ~100 modules, which no user waits for twice.
    """
    environment = {
        key: value for key, value in os.environ.items() if key != "PYTHONDONTWRITEBYTECODE"
    }
    environment.update(PYTHONPATH=str(ROOT), PYTHONPYCACHEPREFIX=str(BYTECODE_CACHE))
    if code not in _WARMED:
        subprocess.run(
            [sys.executable, "-c", code],
            check=True,
            env=environment,
            cwd=ROOT,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        _WARMED.add(code)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(
        [sys.executable, "-c", code],
        check=True,
        env=environment,
        cwd=ROOT,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


_WARMED: set[str] = set()


def paired_run(floor_code: str, code: str, repeats: int):
    """Median wall and CPU times of both snippets and their median ratios (alternating order)."""
    rows = {"floor": [], "ftkin": []}
    for repeat in range(repeats):
        pairs = (
            (("floor", floor_code), ("ftkin", code))
            if repeat % 2 == 0
            else (("ftkin", code), ("floor", floor_code))
        )
        for name, snippet in pairs:
            rows[name].append(run(snippet))
    floor, value = np.array(rows["floor"]), np.array(rows["ftkin"])
    return np.median(floor, axis=0), np.median(value, axis=0), np.median(value / floor, axis=0)


def joint_log_row(name: str, robot: Arm, truth, raws: np.ndarray, rng, repeats: int) -> None:
    """``compensate_batch`` samples/s beside the old path (Pinocchio FK per row +
    einsum).
    """
    count, per_row = len(raws), 5000
    joint_q = robot.random_configurations(count, rng)
    model, data, frame = robot.model, robot.model.createData(), robot.sensor_frame_id
    compensator = Compensator(truth, robot)

    def pinocchio_rows():
        out = np.empty((per_row, 3, 3))
        for i in range(per_row):
            pin.forwardKinematics(model, data, joint_q[i])
            out[i] = pin.updateFramePlacement(model, data, frame).rotation
        return compensator._batch_unchecked(out, raws[:per_row])

    pinocchio_rate = per_row / min(_cpu(pinocchio_rows) for _ in range(3))
    rate = float(
        np.median(
            [
                count / _cpu(lambda: compensator.compensate_batch(joint_q, raws))
                for _ in range(repeats)
            ]
        )
    )
    print(
        f"{'log from joint angles, ' + name:<46}{'Pinocchio FK per row + einsum':<34}"
        f"{pinocchio_rate / 1e6:>10.2f}{rate / 1e6:>10.2f}{rate / pinocchio_rate:>7.1f}  "
        f">= 5 M/s {'PASS' if rate >= 5e6 else 'FAIL'}"
    )


def main(quick: bool = False) -> None:
    repeats = 5 if quick else 15
    load = os.getloadavg()
    print(
        f"throughput and start-up; load average {load[0]:.1f} / {load[1]:.1f} on {os.cpu_count()} "
        "cores\n"
    )
    rng = np.random.default_rng(0)
    truth = paper_like_truth()
    arm = Arm.default()
    compensator = Compensator(truth, arm)

    count = 200_000
    configurations = arm.random_configurations(count, rng)
    rotations = arm.rotation_sensor_to_base(configurations)
    raws = truth.predict(rotations) + rng.standard_normal((count, 6)) * 0.02
    gravity, bias, com = truth.gravity_in_base.copy(), truth.bias, truth.center_of_mass.copy()

    def einsum_floor():
        g = np.einsum("nji,j->ni", rotations, gravity)
        out = raws - bias
        out[:, :3] -= g
        out[:, 3] -= com[1] * g[:, 2] - com[2] * g[:, 1]
        out[:, 4] -= com[2] * g[:, 0] - com[0] * g[:, 2]
        out[:, 5] -= com[0] * g[:, 1] - com[1] * g[:, 0]
        return out

    print(f"{'batch path':<46}{'floor':<34}{'floor M/s':>10}{'ftkin M/s':>10}{'ratio':>7}  target")
    floor, value, ratio = paired_rate(
        einsum_floor, lambda: compensator.compensate_batch(rotations, raws), count, repeats
    )
    print(
        f"{'compensate_batch(R, raw), validated':<46}{'numpy einsum, no checks':<34}"
        f"{floor / 1e6:>10.2f}"
        f"{value / 1e6:>10.2f}{ratio:>7.2f}  >= 0.5x {'PASS' if ratio >= 0.5 else 'FAIL'}"
    )
    floor, value, ratio = paired_rate(
        einsum_floor,
        lambda: compensator._batch_unchecked(rotations, raws),
        count,
        repeats,
    )
    print(
        f"{'batch kernel, no checks (internal)':<46}{'numpy einsum, no checks':<34}"
        f"{floor / 1e6:>10.2f}"
        f"{value / 1e6:>10.2f}{ratio:>7.2f}"
    )
    for name, robot in (("bundled arm", arm), ("UR5", ftkin.load_robot("ur5"))):
        joint_log_row(name, robot, truth, raws, rng, repeats)

    print(
        f"\n{'start-up (fresh interpreter)':<46}{'floor':<34}{'floor s':>10}{'ftkin s':>10}"
        f"{'ratio':>7}  target"
        "   [CPU: floor, ftkin, ratio]"
    )
    rows = (
        ("import ftkin", "import numpy, pinocchio", "import numpy, pinocchio", "import ftkin", 1.5),
        (
            "import ftkin + every public name",
            "import numpy, pinocchio",
            "import numpy, pinocchio",
            "import ftkin; from ftkin import *",
            1.5,
        ),
        (
            "ftkin --version",
            "python -c pass",
            "pass",
            "from ftkin.cli import main; main(['--version'])",
            None,
        ),
    )
    for name, floor_name, floor_code, code, target in rows:
        (floor_wall, floor_cpu), (wall, cpu), (ratio, cpu_ratio) = paired_run(
            floor_code, code, repeats
        )
        verdict = (
            f"<= {target}x {'PASS' if ratio <= target else 'FAIL'}"
            if target
            else f"< 0.4 s {'PASS' if wall < 0.4 else 'FAIL'}"
        )
        print(
            f"{name:<46}{floor_name:<34}{floor_wall:>10.3f}{wall:>10.3f}{ratio:>7.2f}  "
            f"{verdict:<14}"
            f"[{floor_cpu:.3f}, {cpu:.3f}, {cpu_ratio:.2f}]"
        )
    for n, target, plan_repeats in ((12, 1.0, repeats), (200, 5.0, 1 if quick else 3)):
        code = f"from ftkin.cli import main; main(['plan', '--n', '{n}'])"
        times = np.array([run(code) for _ in range(plan_repeats)])
        wall, cpu = np.median(times, axis=0)
        print(
            f"{f'ftkin plan --n {n}':<46}{'-':<34}{'':>10}{wall:>10.2f}{'':>7}  "
            f"{f'<= {target:g} s'} {'PASS' if wall <= target else 'FAIL':<6}[CPU {cpu:.2f} s]"
        )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main, "--quick" in sys.argv))
