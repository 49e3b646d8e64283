"""Time of ``calibrate()`` on 12 poses of one reading each, beside a numpy two-step floor.

What a robot session and ``ftkin calibrate`` run: ``calibrate(Samples(...))`` with the default
options (``method="ml"``, noise estimated from the residuals, every check on: the orientation
conventions, the sign and axes, the tilt, the goodness of fit). The bundled arm, 12 random poses
(joint limits shrunk by a margin), the estimator benchmark's 15 N tool and noise
(``bench_estimator.py``), one reading per pose, orientations given as rotation matrices.

Rows (median over rounds; in each round every row runs once, in turn, so a change of load on the
machine hits every row alike):

* ``numpy two-step (floor)``: the paper's two-step least squares written in plain numpy (force
  regression for ``a, F0``, then torque regression on the measured forces for ``P, b``), no
  checks, no model object: the least any calibration of these readings costs;
* ``calibrate, ml (default)``: the target row, ≤ 5 ms (issue 38);
* ``calibrate, method="linear"``: the same checks around the two-step fit.

Each row prints the median wall time and the median CPU time of the thread (the latter less
sensitive to other processes on a loaded machine) and its ratio to the floor's.

Run: ``python benchmarks/bench_calibrate.py [--rounds 400] [--seed 0]``.
"""

from __future__ import annotations

import argparse
import logging
import time

import numpy as np
from _targets import verdict

from ftkin import Arm, SensorModel, SensorNoise, SimulatedSensor, calibrate

POSES = 12
MARGIN = 0.3  # [rad] kept from each joint limit
NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
TRUTH = SensorModel.from_tool(
    tool_mass=15.0 / 9.80665,  # 15 N tool [kg]
    center_of_mass=[0.03, -0.02, 0.08],  # [m] sensor frame
    force_offset=[2.0, -1.5, 3.0],  # [N]
    torque_offset=[0.10, -0.05, 0.02],  # [N·m]
    base_tilt=np.deg2rad([0.3, -0.2]),  # U, V [rad]
)
TARGET_MS = 5.0
"""Median wall time [ms] of the default ``calibrate`` on 12 poses × 1 reading (issue 38)."""


def two_step_floor(rotations: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """The paper's two-step least squares in plain numpy: ``[a, F0, P, M0]`` (12,)."""
    count = len(rotations)
    forces, torques = wrenches[:, :3], wrenches[:, 3:]
    identity = np.broadcast_to(np.eye(3), (count, 3, 3))
    force_regressor = np.concatenate([np.transpose(rotations, (0, 2, 1)), identity], axis=2)
    step1, *_ = np.linalg.lstsq(force_regressor.reshape(-1, 6), forces.reshape(-1), rcond=None)
    fx, fy, fz = forces.T
    zero = np.zeros(count)
    minus_skew = -np.stack(
        [
            np.stack([zero, -fz, fy], axis=1),
            np.stack([fz, zero, -fx], axis=1),
            np.stack([-fy, fx, zero], axis=1),
        ],
        axis=1,
    )
    torque_regressor = np.concatenate([minus_skew, identity], axis=2).reshape(-1, 6)
    step2, *_ = np.linalg.lstsq(torque_regressor, torques.reshape(-1), rcond=None)
    force_offset, center_of_mass, auxiliary = step1[3:], step2[:3], step2[3:]
    torque_offset = auxiliary - np.cross(force_offset, center_of_mass)  # M0 = b − F0 × P
    return np.concatenate([step1[:3], force_offset, center_of_mass, torque_offset])


def interleaved(rows: dict, rounds: int) -> dict:
    """``{label: (wall [s] per call, CPU [s] per call)}``: medians, the rows run in turn."""
    wall = {label: [] for label in rows}
    cpu = {label: [] for label in rows}
    for _ in range(rounds):
        for label, function in rows.items():
            wall_start, cpu_start = time.perf_counter(), time.thread_time()
            function()
            cpu[label].append(time.thread_time() - cpu_start)
            wall[label].append(time.perf_counter() - wall_start)
    return {label: (float(np.median(wall[label])), float(np.median(cpu[label]))) for label in rows}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--rounds", type=int, default=400, help="timed rounds (default: %(default)s)"
    )
    parser.add_argument("--seed", type=int, default=0, help="random seed (default: %(default)s)")
    args = parser.parse_args(argv)
    logging.getLogger("ftkin").setLevel(logging.ERROR)
    rng = np.random.default_rng(args.seed)
    arm = Arm.default()
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(POSES, rng, margin=MARGIN))
    samples = SimulatedSensor(TRUTH, NOISE).samples(rotations, rng, 1)
    floor = two_step_floor(samples.rotations, samples.wrenches)
    linear = calibrate(samples, method="linear")
    expected = np.concatenate(
        [linear.gravity_in_base, linear.force_offset, linear.center_of_mass, linear.torque_offset]
    )
    if not np.allclose(floor, expected, rtol=1e-9, atol=1e-12):
        print("the numpy floor and method='linear' disagree: FAIL")
        return 1
    rows = {
        "numpy two-step (floor)": lambda: two_step_floor(samples.rotations, samples.wrenches),
        "calibrate, ml (default)": lambda: calibrate(samples),
        'calibrate, method="linear"': lambda: calibrate(samples, method="linear"),
    }
    for function in rows.values():  # warm up: imports, caches
        for _ in range(20):
            function()
    times = interleaved(rows, args.rounds)
    floor_wall, floor_cpu = times["numpy two-step (floor)"]
    print(
        f"{POSES} poses x 1 reading, {args.rounds} interleaved rounds (median per call); "
        f"target: default calibrate <= {TARGET_MS:g} ms wall"
    )
    print(f"{'row':<30}{'wall [ms]':>11}{'x floor':>9}{'CPU [ms]':>10}{'x floor':>9}")
    for label, (wall, cpu) in times.items():
        print(
            f"{label:<30}{1e3 * wall:>11.3f}{wall / floor_wall:>9.1f}"
            f"{1e3 * cpu:>10.3f}{cpu / floor_cpu:>9.1f}"
        )
    wall = times["calibrate, ml (default)"][0]
    print(
        f"default calibrate {1e3 * wall:.2f} ms (target <= {TARGET_MS:g} ms) "
        f"{verdict(1e3 * wall <= TARGET_MS)}"
    )
    return 0


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
