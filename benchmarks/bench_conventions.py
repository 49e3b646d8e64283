"""Convention diagnosis: false alarms on clean data, mistakes named, cost per check.

Draws seeded data sets on the bundled arm and UR5 (random tool, bias, tilt,
4-20 poses, 1-3 readings per pose, noise 0.1-20 x the paper's, orientation as
joints, Euler angles or quaternions) and runs :func:`ftkin.io.conventions.diagnose_table`:

* clean sets: no verdict may be "mistake" or "suspect" (target: 0 false alarms in 1,000);
* each mistake written into clean sets: the share named correctly;
* time per diagnosis beside one ``calibrate(method="ml")`` of the same set (the fit it guards).

Run: ``.venv/bin/python benchmarks/bench_conventions.py [SETS]``
"""

from __future__ import annotations

import logging
import sys
import time

import numpy as np

from ftkin import Arm, SensorModel, calibrate
from ftkin.io.conventions import diagnose_table
from ftkin.io.csv_table import Table
from ftkin.io.samples_csv import samples_from_table
from ftkin.kinematics.robots import load_robot
from ftkin.kinematics.rotations import matrix_to_euler_zyx, matrix_to_quaternion

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
NOISE = np.array([0.02, 0.02, 0.02, 0.002, 0.002, 0.002])


def table(header, rows) -> Table:
    return Table(
        "sim.csv",
        list(header),
        [[repr(float(v)) for v in row] for row in rows],
        list(range(2, 2 + len(rows))),
        1,
    )


def draw(rng, arms):
    """A clean set: (arm, q, rotations, wrenches, pose ids, kind)."""
    arm = arms[rng.choice(list(arms))]
    truth = SensorModel.from_tool(
        tool_mass=rng.uniform(0.05, 5.0),
        center_of_mass=rng.uniform(-0.15, 0.15, 3),
        force_offset=rng.normal(scale=2.0, size=3),
        torque_offset=rng.normal(scale=0.1, size=3),
        base_tilt=rng.normal(scale=np.deg2rad(0.5), size=2),
    )
    count, repeats = int(rng.integers(4, 21)), int(rng.integers(1, 4))
    q = np.repeat(arm.random_configurations(count, rng, margin=0.2), repeats, axis=0)
    rotations = arm.rotation_sensor_to_base(q)
    wrenches = truth.predict(rotations) + rng.normal(
        scale=NOISE * 10 ** rng.uniform(-1, 1.3), size=(len(q), 6)
    )
    pose = np.repeat(np.arange(count), repeats)[:, None].astype(float)
    return arm, q, rotations, wrenches, pose, rng.choice(["joints", "euler", "quaternion"])


def as_table(arm, q, rotations, wrenches, pose, kind):
    if kind == "joints":
        return arm, table(
            ["pose", *[f"q{i + 1}" for i in range(arm.nq)], *WRENCH], np.hstack([pose, q, wrenches])
        )
    if kind == "euler":
        angles = np.rad2deg(matrix_to_euler_zyx(rotations))
        return None, table(
            ["pose", "alpha", "beta", "gamma", *WRENCH], np.hstack([pose, angles, wrenches])
        )
    return None, table(
        ["pose", "qw", "qx", "qy", "qz", *WRENCH],
        np.hstack([pose, matrix_to_quaternion(rotations), wrenches]),
    )


def base_frame(rotations, wrenches):
    return np.hstack(
        [
            np.einsum("nij,nj->ni", rotations, wrenches[:, :3]),
            np.einsum("nij,nj->ni", rotations, wrenches[:, 3:]),
        ]
    )


MISTAKES = {
    "Euler angles in radians": lambda a, q, r, w, p: (
        None,
        table(
            ["pose", "alpha", "beta", "gamma", *WRENCH], np.hstack([p, matrix_to_euler_zyx(r), w])
        ),
    ),
    "the quaternion as x,y,z,w": lambda a, q, r, w, p: (
        None,
        table(
            ["pose", "qw", "qx", "qy", "qz", *WRENCH],
            np.hstack([p, matrix_to_quaternion(r)[:, [1, 2, 3, 0]], w]),
        ),
    ),
    "the wrench in the base frame": lambda a, q, r, w, p: as_table(
        a, q, r, base_frame(r, w), p, "joints"
    ),
    "the readings negated (the reaction)": lambda a, q, r, w, p: as_table(a, q, r, -w, p, "joints"),
    "the sensor's y axis reversed": lambda a, q, r, w, p: as_table(
        a, q, r, w * [1, -1, 1, -1, 1, -1], p, "joints"
    ),
    "joint angles in degrees": lambda a, q, r, w, p: as_table(a, np.rad2deg(q), r, w, p, "joints"),
    "torques in N·mm": lambda a, q, r, w, p: as_table(
        a, q, r, w * [1, 1, 1, 1e3, 1e3, 1e3], p, "joints"
    ),
}


def main(sets: int = 1000) -> None:
    logging.disable(
        logging.WARNING
    )  # the fit's own warnings about few poses are not what is measured here
    arms = {"bundled": Arm.default(), "ur5": load_robot("ur5", [0.0, 0.0, 0.05])}
    rng = np.random.default_rng(2026)
    alarms, seconds, fit_seconds = 0, [], []
    for k in range(sets):
        drawn = draw(rng, arms)
        arm, clean = as_table(*drawn)
        start = time.perf_counter()
        report = diagnose_table(clean, arm)
        seconds.append(time.perf_counter() - start)
        alarms += report.verdict in ("mistake", "suspect")
        if k < 100:
            samples = samples_from_table(clean, arm).samples
            start = time.perf_counter()
            calibrate(samples)
            fit_seconds.append(time.perf_counter() - start)
    print(f"{'case':<40}{'sets':>6}{'result':>22}")
    print(
        f"{'clean (false alarms)':<40}{sets:>6}{alarms:>14} alarms  target 0 "
        f"{'PASS' if alarms == 0 else 'FAIL'}"
    )
    per_mistake = max(sets // 10, 20)
    for name, write in MISTAKES.items():
        named = 0
        for _ in range(per_mistake):
            arm, q, rotations, wrenches, pose, _kind = draw(rng, arms)
            report = diagnose_table(
                write(arm, q, rotations, wrenches, pose)[1],
                write(arm, q, rotations, wrenches, pose)[0],
            )
            named += report.culprit is not None and report.culprit.reading.name == name
        print(f"{name:<40}{per_mistake:>6}{named / per_mistake:>16.1%} named")
    print(
        f"\nmedian time per diagnosis {np.median(seconds) * 1e3:.2f} ms; "
        f"one calibrate(method='ml') of the same sets {np.median(fit_seconds) * 1e3:.2f} ms"
    )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main, int(sys.argv[1]) if len(sys.argv) > 1 else 1000))
