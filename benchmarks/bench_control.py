"""Per-call cost of the control-rate paths, each beside its floor measured in the same run.

Rows (median time per call; ratio = ftkin / floor, the median of the per-repeat ratios):

* ``JointAdmittance.step`` with every feature on (fault monitor, oscillation
  detector, safety stop, deadband, derivative filter, saturation, joint-limit
  scaling, status) vs a minimal hand-written tick: Pinocchio FK + sensor
  Jacobian, compensation, velocity admittance, damped least squares with
  ``numpy.linalg.solve``;
* ``Compensator.compensate(q, raw)`` vs tight Pinocchio + numpy;
* ``compensate_rotation`` (validated) vs ``compensate_unchecked``;
* the dynamic compensation tick ``DynamicCompensator.compensate_moving(q, dq, ddq, raw)``
  (validated; a tool with a full inertia) vs the static tick ``Compensator.compensate(q, raw)``;
* a held step (NaN sample), for information.

Floor and ftkin are timed in alternating blocks of calls (the order flips every
repeat), so a load change on a shared machine hits both; the load average is
printed. The step is fed noisy readings (a constant reading is a stuck sensor).

Targets: step <= 1.3x, compensate <= 1.3x, validated rotation <= 2x, dynamic tick <= 2x static.

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/bench_control.py [repeats]``
"""

from __future__ import annotations

import os
import sys
import time
from itertools import cycle

import numpy as np
import pinocchio as pin

from ftkin import Admittance, Arm, Compensator, DynamicCompensator, JointAdmittance
from ftkin.calibration.model import skew
from ftkin.sim.sensor import paper_like_truth

CALLS = 2000
"""Calls per timed block."""


def paired(floor, function, repeats: int, calls: int = CALLS) -> tuple[float, float, float]:
    """Median seconds per call of ``floor`` and ``function``, and the median ratio, over alternating
    blocks.
    """
    for _ in range(calls // 4):
        floor()
        function()
    floors, values, ratios = [], [], []
    clock = time.process_time  # CPU time: waiting for a core on a shared machine does not count
    for repeat in range(repeats):
        pair = []
        for timed in (floor, function) if repeat % 2 == 0 else (function, floor):
            start = clock()
            for _ in range(calls):
                timed()
            pair.append((clock() - start) / calls)
        floor_time, time_ = pair if repeat % 2 == 0 else pair[::-1]
        floors.append(floor_time)
        values.append(time_)
        ratios.append(time_ / floor_time)
    return float(np.median(floors)), float(np.median(values)), float(np.median(ratios))


def print_row(
    name: str, floor_name: str, floor: float, value: float, ratio: float, target: float | None
) -> None:
    verdict = "" if target is None else f"<= {target:g}x {'PASS' if ratio <= target else 'FAIL'}"
    print(
        f"{name:<38}{floor_name:<42}{floor * 1e6:>10.2f}{value * 1e6:>10.2f}{ratio:>8.2f}  "
        f"{verdict}"
    )


def main(repeats: int = 41) -> None:
    rng = np.random.default_rng(0)
    arm = Arm.default()
    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    q = np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2])
    raw = truth.predict(arm.rotation_sensor_to_base(q)) + np.array([0.0, 0.0, 2.0, 0.0, 0.0, 0.0])
    rotation = arm.rotation_sensor_to_base(q)
    model, data, frame = arm.model, arm.data, arm.sensor_frame_id
    k2 = np.array([1e-3] * 3 + [1e-2] * 3)
    admittance = Admittance(
        k1=1e-4, k2=k2, selection=[0, 0, 1, 0, 0, 0], frame="tool", force_deadband=0.02
    )
    controller = JointAdmittance(arm, admittance, compensator)
    noisy = list(
        raw + rng.standard_normal((4096, 6)) * np.array([0.02, 0.02, 0.02, 0.002, 0.002, 0.002])
    )
    rows_step, rows_floor = cycle(noisy), cycle(noisy)
    nan_raw = raw.copy()
    nan_raw[2] = np.nan
    held = JointAdmittance(arm, Admittance(k1=1e-4, k2=1e-3, frame="tool"), compensator)
    # A tool of the calibration's mass and COM with a full inertia: θ = [m, m·c, I about the sensor
    # origin] (10,).
    mass, com = truth.tool_mass, truth.center_of_mass
    inertia = np.array(
        [[2.0e-3, 1e-4, -2e-4], [1e-4, 2.2e-3, 1e-4], [-2e-4, 1e-4, 1.1e-3]]
    ) + mass * skew(com).T @ skew(com)
    theta = np.concatenate([[mass], mass * com, inertia[[0, 0, 1, 0, 1, 2], [0, 1, 1, 2, 2, 2]]])
    dynamic = DynamicCompensator(truth, arm, theta)
    dq, ddq = rng.normal(size=arm.nq), 5.0 * rng.normal(size=arm.nq)

    # The floors: the same physics, hand-written tight (np.dot: less overhead than @ on small
    # arrays),
    # no checks, no features.
    gravity, bias = truth.gravity_in_base.copy(), truth.bias
    lever = np.vstack([np.eye(3), skew(truth.center_of_mass)])  # [Gs; P × Gs] = lever @ Gs
    damping = 1e-4 * np.eye(6)
    world = pin.LOCAL_WORLD_ALIGNED

    def floor_compensate():
        pin.forwardKinematics(model, data, q)
        rotation_bs = pin.updateFramePlacement(model, data, frame).rotation
        return raw - bias - np.dot(lever, np.dot(gravity, rotation_bs))  # Gs = R_BSᵀ a

    def floor_tick():
        reading = next(rows_floor)
        jacobian = pin.computeFrameJacobian(model, data, q, frame, world)
        contact = reading - bias - np.dot(lever, np.dot(gravity, data.oMf[frame].rotation))
        twist = k2 * contact
        return np.dot(np.linalg.solve(np.dot(jacobian, jacobian.T) + damping, twist), jacobian)

    def unchecked():
        return compensator.compensate_unchecked(rotation, raw)

    def step():
        return controller.step(q, next(rows_step), 1e-3)

    load = os.getloadavg()
    print(
        f"control paths: {repeats} repeats x {CALLS} calls per block; load average {load[0]:.1f} / "
        f"{load[1]:.1f} "
        f"on {os.cpu_count()} cores"
    )
    print(f"{'path':<38}{'floor':<42}{'floor µs':>10}{'ftkin µs':>10}{'ratio':>8}  target")
    print_row(
        "JointAdmittance.step (all features)",
        "minimal tick (FK+J, comp, K2, solve)",
        *paired(floor_tick, step, repeats),
        1.3,
    )
    print_row(
        "Compensator.compensate(q, raw)",
        "Pinocchio FK + numpy",
        *paired(floor_compensate, lambda: compensator.compensate(q, raw), repeats),
        1.3,
    )
    print_row(
        "compensate_rotation (validated)",
        "compensate_unchecked",
        *paired(unchecked, lambda: compensator.compensate_rotation(rotation, raw), repeats),
        2.0,
    )
    print_row(
        "step on a NaN sample (held)",
        "minimal tick",
        *paired(floor_tick, lambda: held.step(q, nan_raw, 1e-3), max(5, repeats // 4)),
        None,
    )
    print_row(
        "DynamicCompensator.compensate_moving",
        "Compensator.compensate(q, raw)",
        *paired(
            lambda: compensator.compensate(q, raw),
            lambda: dynamic.compensate_moving(q, dq, ddq, raw),
            repeats,
        ),
        2.0,
    )
    status = controller.last_status
    print(
        f"last status: limit_scale {status.limit_scale:.3f}, damping {status.damping:.3g}, "
        f"|dq| {np.linalg.norm(status.dq):.3g} rad/s"
    )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main, int(sys.argv[1]) if len(sys.argv) > 1 else 41))
