"""Per-tick cost of compensation and of the joint-space admittance step.

Prints median and 99th-percentile time per call, each beside the bare
Pinocchio forward kinematics (``forwardKinematics`` + ``updateFramePlacement``,
the floor) as a ratio, and batch compensation throughput.

The step is fed noisy readings (paper noise): a constant reading would be a
stuck sensor and time the held path, which has its own row (a NaN sample).

Targets (2-core machine): compensation from q <= 15 µs median, full step
<= 60 µs median, batch from rotations >= 5 million samples/s.

Run: ``.venv/bin/python benchmarks/bench_control.py``
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from ftkin import Arm, Compensator
from ftkin.control.admittance import Admittance
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.sim.sensor import paper_like_truth

CALLS = 20000
"""Timed calls per single-sample entry (each timed on its own)."""


def per_call(function, calls: int = CALLS) -> np.ndarray:
    """Seconds per call, one timing per call (after a warm-up)."""
    for _ in range(500):
        function()
    clock = time.perf_counter
    out = np.empty(calls)
    for i in range(calls):
        start = clock()
        function()
        out[i] = clock() - start
    return out


def throughput(function, samples: int, repeats: int = 7) -> float:
    """Samples per second (best of ``repeats``) of a batch call."""
    function()
    best = min(_timed(function) for _ in range(repeats))
    return samples / best


def _timed(function) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def main() -> None:
    rng = np.random.default_rng(0)
    arm = Arm.default()
    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    q = np.array([0.1, 0.2, -0.6, 0.3, -1.0, 0.2])
    raw = truth.predict(arm.rotation_sensor_to_base(q)) + np.array([0.0, 0.0, 2.0, 0.0, 0.0, 0.0])
    model, data, frame = arm.model, arm.data, arm.sensor_frame_id
    admittance = Admittance(k1=1e-4, k2=1e-3, selection=[0, 0, 1, 0, 0, 0], frame="tool", force_deadband=0.02)
    controller = JointAdmittance(arm, admittance, compensator)
    noisy = raw + rng.standard_normal((CALLS + 500, 6)) * np.array([0.02, 0.02, 0.02, 0.002, 0.002, 0.002])
    noisy_rows = iter(np.tile(noisy, (2, 1)))
    nan_raw = raw.copy()
    nan_raw[2] = np.nan
    held = JointAdmittance(arm, Admittance(k1=1e-4, k2=1e-3, frame="tool"), compensator)

    def floor():
        pin.forwardKinematics(model, data, q)
        pin.updateFramePlacement(model, data, frame)

    rows = [
        ("pin FK + updateFramePlacement (floor)", per_call(floor)),
        ("Compensator.compensate(q, raw)", per_call(lambda: compensator.compensate(q, raw))),
        ("JointAdmittance.step(q, raw, dt)", per_call(lambda: controller.step(q, next(noisy_rows), 1e-3))),
        ("step on a NaN sample (held)", per_call(lambda: held.step(q, nan_raw, 1e-3))),
    ]
    floor_median = float(np.median(rows[0][1]))
    print(f"single sample ({CALLS} calls each)")
    print(f"{'call':<40}{'median [µs]':>12}{'p99 [µs]':>10}{'x floor':>9}  target")
    targets = {1: "<= 15 µs", 2: "<= 60 µs"}
    for index, (name, seconds) in enumerate(rows):
        median, p99 = np.median(seconds) * 1e6, np.percentile(seconds, 99) * 1e6
        print(f"{name:<40}{median:>12.2f}{p99:>10.2f}{median / (floor_median * 1e6):>9.1f}  {targets.get(index, '')}")

    count = 200_000
    configurations = arm.random_configurations(count // 10, rng, margin=0.1)
    rotations = np.repeat(arm.rotation_sensor_to_base(configurations), 10, axis=0)
    raws = truth.predict(rotations).reshape(-1, 6) + rng.standard_normal((count, 6)) * 0.02
    joint_count = 20_000
    joint_q, joint_raw = configurations[:joint_count], raws[:joint_count]
    print("\nbatch compensation")
    print(f"{'call':<50}{'samples':>9}{'Msamples/s':>12}  target")
    for name, samples, function, target in (
        ("compensate_batch_unchecked(R, raw)", count, lambda: compensator.compensate_batch_unchecked(rotations, raws), ">= 5"),
        ("compensate_batch(R, raw) (validated)", count, lambda: compensator.compensate_batch(rotations, raws), ""),
        ("compensate_joint_positions(q, raw) (FK per row)", joint_count,
         lambda: compensator.compensate_joint_positions(joint_q, joint_raw), ""),
    ):
        print(f"{name:<50}{samples:>9}{throughput(function, samples) / 1e6:>12.2f}  {target}")


if __name__ == "__main__":
    main()
