"""Are each calibration kind's standard errors honest? Seeded Monte Carlo against MuJoCo's truth.

For every kind of calibration ftkin offers, the same tool is calibrated many times with fresh
noise, and each estimate's error against the truth is divided by the standard error the fit
reported for it: ``z = (estimate − truth) / std error``. Honest standard errors give z of unit
variance, so the row's target is the RMS of z, pooled over the mass, the centre of mass (3) and
the bias (6) of every trial, within [0.8, 1.25] (issue 38), from at least 200 values per kind.

Setup: the bundled arm in MuJoCo (:class:`~ftkin.sim.mujoco.imu_recording.MujocoImuRecorder`)
carrying a 1.5 kg tool of known, non-diagonal inertia; the truth (mass, centre of mass) is
MuJoCo's own bodies (``true_parameters``: the sensor body's subtree), the bias is the one added.
Base tilted (0.3°, −0.2°); sensor bias [2, −1.5, 3] N, [0.1, −0.05, 0.02] N·m; the IMU turned
by ``R_SI`` = rpy (95°, 89°, −175°) and 3.7 cm off the sensor origin, accelerometer bias
[0.76, −0.30, 0.20] m/s² and scale [+0.5, −0.3, +0.2] %. Each recording is made once noise-free
in MuJoCo and only the white noise is redrawn per trial: wrench 0.05 N / 0.003 N·m, accelerometer
0.02 m/s², gyro 0.005 rad/s per reading.

Kinds:

* ``static, rotations``: ``calibrate(Samples(wrenches, R_BS, pose_ids))``, ``R_BS`` from MuJoCo;
* ``static, joints``: ``Samples.from_joint_positions`` (ftkin's Pinocchio FK);
* ``static, mount``: the sensor turned on its flange by ``R_M`` = rpy (3°, −2°, 35°) (MuJoCo's
  readings rotated into the turned sensor's axes, the truth's COM with them),
  ``calibrate(..., estimate_mount="full")``;
* ``static, IMU only``: ``calibrate(ImuSamples.from_arrays(...))``, no joint angle;
* ``static, fused``: FK and the IMU, ``FusedSamples.from_arrays(samples, ...)`` of joint-angle
  ``Samples``;
* ``dynamic, joints``: ``calibrate_dynamic`` on an excitation's joint angles (encoder noise
  1e-5 rad, derivatives by Savitzky–Golay);
* ``dynamic, IMU``: ``calibrate_imu_dynamic`` on the same excitation's IMU readings, its prior the
  static IMU calibration of the same trial.

The static kinds use 12 planned poses × 40 readings, the noise measured from the spread of each
pose's readings (ftkin's default). The moving kinds use a short excitation (``--duration`` s at
``--rate`` Hz: 6 s at 250 Hz by default, so each finishes in a few minutes on 2 cores), the noise
the one given above; their fits estimate it from the residuals, as on a real log (no ``noise=``).

Run: ``.venv/bin/python benchmarks/bench_standard_errors.py [--trials 40] [--dynamic-trials 40]
[--seed 0]``; ``FTKIN_BENCH_RECORD=1`` records ``benchmarks/results/bench_standard_errors.txt``.
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
import time
import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from ftkin import Arm, Samples, calibrate, calibrate_dynamic, plan_poses
from ftkin.calibration.derivatives import joint_derivatives
from ftkin.calibration.fused_samples import FusedSamples
from ftkin.calibration.imu_dynamic import calibrate_imu_dynamic
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import body_from_parameters
from ftkin.calibration.regressor import MotionSamples
from ftkin.planning.constraints import PoseConstraints
from ftkin.planning.excitation import plan_excitation
from ftkin.sim.mujoco.imu_recording import MujocoImuRecorder
from ftkin.sim.mujoco.tool_inertia import ToolInertia

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from _targets import verdict  # noqa: E402

POSES, READINGS = 12, 40
TILT = np.deg2rad([0.3, -0.2])  # U, V [rad]
BIAS = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])  # [N, N·m]
WRENCH_STD = np.array([0.05] * 3 + [0.003] * 3)  # per reading [N, N·m]
ACCEL_STD, GYRO_STD, ENCODER_STD = 0.02, 0.005, 1e-5  # [m/s², rad/s, rad] per reading
IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
IMU_POSITION = np.array([0.021, -0.012, 0.027])  # [m], sensor frame
ACCEL_BIAS = np.array([0.76, -0.30, 0.20])  # [m/s², IMU frame]
ACCEL_SCALE = np.array([0.005, -0.003, 0.002])
MOUNT = Rotation.from_euler("xyz", [3.0, -2.0, 35.0], degrees=True).as_matrix()  # R_M
BAND = (0.8, 1.25)  # RMS z target (issue 38)
IMU_NAMES = ["tool_mass"] + [
    f"{block}[{axis}]"
    for block in ("center_of_mass", "force_offset", "torque_offset")
    for axis in "xyz"
]


def make_tool() -> ToolInertia:
    turn = Rotation.from_euler("xyz", [0.4, -0.3, 0.2]).as_matrix()
    return ToolInertia(
        1.5, [0.006, -0.012, 0.072], turn @ np.diag([0.0060, 0.0052, 0.0021]) @ turn.T
    )


def fk_values(result) -> tuple[np.ndarray, np.ndarray]:
    """``(10,)`` estimate and ``(10,)`` standard error of [mass, COM, F0, M0] of an FK result."""
    errors = result.std_errors
    estimate = np.concatenate(
        [[result.tool_mass], result.center_of_mass, result.force_offset, result.torque_offset]
    )
    sigma = np.concatenate(
        [
            [errors["tool_mass"]],
            errors["center_of_mass"],
            errors["force_offset"],
            errors["torque_offset"],
        ]
    )
    return estimate, sigma


def imu_values(result) -> tuple[np.ndarray, np.ndarray]:
    """The same for an IMU result (its covariance is by parameter name)."""
    estimate = np.concatenate(
        [[result.tool_mass], result.center_of_mass, result.force_offset, result.torque_offset]
    )
    return estimate, result.std_error_of(IMU_NAMES)


class Bench:
    """The recordings, made once noise-free, and the noise drawn per trial."""

    def __init__(self, duration: float, rate: float):
        self.arm = Arm.default()
        tool = make_tool()
        self.recorder = MujocoImuRecorder(
            imu_rotation=IMU_ROTATION,
            imu_position=IMU_POSITION,
            joint_names=self.arm.joint_names,
            tool=tool,
            base_tilt=TILT,
        )
        mass, com, _ = body_from_parameters(self.recorder.true_parameters())
        self.truth = np.concatenate([[mass], com, BIAS])
        self.truth_mount = np.concatenate([[mass], MOUNT @ com, BIAS])
        poses = plan_poses(self.arm, POSES, floor_height=0.15, seed=0).joint_positions
        self.ids = np.repeat(np.arange(POSES), READINGS)
        self.q = poses[self.ids]
        wrench, accel, _ = self.recorder.readings(poses)
        self.wrench, self.accel = wrench[self.ids], accel[self.ids]
        self.rotations = np.array([self.recorder.sensor_rotation(q) for q in poses])[self.ids]
        turn = np.kron(np.eye(2), MOUNT)  # readings in the turned sensor's axes
        self.wrench_mount = self.wrench @ turn.T
        self.rotations_urdf = self.arm.rotation_sensor_to_base(poses)[self.ids]
        self.rotations_mount = self.rotations_urdf  # what FK says; the real sensor is turned
        plan = plan_excitation(
            self.arm,
            duration,
            rate=rate,
            period=duration / 2,
            constraints=PoseConstraints(floor_height=0.15),
            seed=0,
            candidates=20,
            optimize=False,
        )
        self.times = plan.times
        self.moving_q = plan.joint_positions
        self.moving = self.recorder.readings(
            plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
        )

    def noisy_wrench(self, wrench, rng):
        return wrench + BIAS + rng.normal(size=wrench.shape) * WRENCH_STD

    def noisy_accel(self, accel, rng):
        return (1.0 + ACCEL_SCALE) * accel + ACCEL_BIAS + rng.normal(0.0, ACCEL_STD, accel.shape)

    def static(self, kind: str, rng):
        """One static trial of ``kind``: ``(estimate, std error, truth)``."""
        if kind == "static, mount":
            wrench = self.noisy_wrench(self.wrench_mount, rng)
            samples = Samples.from_joint_positions(
                self.arm, self.q, wrench, self.ids, rotations=self.rotations_mount
            )
            return (*fk_values(calibrate(samples, estimate_mount="full")), self.truth_mount)
        wrench = self.noisy_wrench(self.wrench, rng)
        if kind == "static, rotations":
            return (*fk_values(calibrate(Samples(wrench, self.rotations, self.ids))), self.truth)
        if kind == "static, joints":
            samples = Samples.from_joint_positions(
                self.arm, self.q, wrench, self.ids, rotations=self.rotations_urdf
            )
            return (*fk_values(calibrate(samples)), self.truth)
        accel = self.noisy_accel(self.accel, rng)
        if kind == "static, IMU only":
            return (
                *imu_values(calibrate(ImuSamples.from_arrays(accel, wrench, self.ids))),
                self.truth,
            )
        samples = FusedSamples.from_arrays(
            Samples.from_joint_positions(
                self.arm, self.q, wrench, self.ids, rotations=self.rotations_urdf
            ),
            accel,
        )
        return (*fk_values(calibrate(samples)), self.truth)  # its θ block has the FK's names

    def dynamic(self, kind: str, rng):
        """One moving trial of ``kind``: ``(estimate, std error, truth)``."""
        wrench_true, accel_true, gyro_true = self.moving
        wrench = self.noisy_wrench(wrench_true, rng)
        if kind == "dynamic, joints":
            q = self.moving_q + rng.normal(0.0, ENCODER_STD, self.moving_q.shape)
            motion = MotionSamples.from_joint_trajectory(
                self.arm, *joint_derivatives(self.times, q), wrench, self.times
            )
            return (*fk_values(calibrate_dynamic(motion)), self.truth)
        prior = calibrate(
            ImuSamples.from_arrays(
                self.noisy_accel(self.accel, rng), self.noisy_wrench(self.wrench, rng), self.ids
            )
        )
        samples = ImuSamples(
            self.noisy_accel(accel_true, rng),
            wrench,
            angular_velocity=gyro_true + rng.normal(0.0, GYRO_STD, gyro_true.shape),
            times=self.times,
        )
        return (*imu_values(calibrate_imu_dynamic(samples, prior=prior)), self.truth)


STATIC_KINDS = (
    "static, rotations",
    "static, joints",
    "static, mount",
    "static, IMU only",
    "static, fused",
)
DYNAMIC_KINDS = ("dynamic, joints", "dynamic, IMU")


def run_kind(bench: Bench, kind: str, trials: int, rng) -> tuple[np.ndarray, float]:
    """``(trials, 10)`` z values of ``kind`` and the seconds per trial."""
    z = np.empty((trials, 10))
    trial_of = bench.dynamic if kind in DYNAMIC_KINDS else bench.static
    started = time.perf_counter()
    for trial in range(trials):
        estimate, sigma, truth = trial_of(kind, rng)
        z[trial] = (estimate - truth) / sigma
    return z, (time.perf_counter() - started) / trials


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--trials", type=int, default=40, help="static trials per kind")
    parser.add_argument("--dynamic-trials", type=int, default=40, help="moving trials per kind")
    parser.add_argument("--duration", type=float, default=6.0, help="excitation length [s]")
    parser.add_argument("--rate", type=float, default=250.0, help="moving sample rate [Hz]")
    parser.add_argument("--seed", type=int, default=0, help="random seed")
    parser.add_argument("--kinds", default="", help="';'-separated subset of the kinds")
    args = parser.parse_args(argv)
    logging.getLogger("ftkin").setLevel(logging.ERROR)  # a clean trial's rare flagged pose
    warnings.simplefilter("ignore")
    started = time.perf_counter()
    bench = Bench(args.duration, args.rate)
    kinds = [k.strip() for k in args.kinds.split(";") if k.strip()] or list(
        STATIC_KINDS + DYNAMIC_KINDS
    )
    unknown = sorted(set(kinds) - set(STATIC_KINDS + DYNAMIC_KINDS))
    if unknown:
        known = "; ".join(STATIC_KINDS + DYNAMIC_KINDS)
        parser.error(f"unknown kind(s) {unknown}; the kinds: {known}")
    print(
        f"bench_standard_errors: bundled arm, MuJoCo truth, 1.5 kg tool; static {POSES} poses x "
        f"{READINGS} readings ({args.trials} trials); moving {args.duration:g} s at "
        f"{args.rate:g} Hz ({args.dynamic_trials} trials); noise {WRENCH_STD[0]} N / "
        f"{WRENCH_STD[3]} N·m, accel {ACCEL_STD} m/s², gyro {GYRO_STD} rad/s, encoder "
        f"{ENCODER_STD} rad; seed {args.seed} (set-up {time.perf_counter() - started:.0f} s)"
    )
    print()
    print(
        "| kind | values | RMS z | RMS z mass, COM, F0, M0 | max abs z | s per trial | "
        f"target RMS z in [{BAND[0]}, {BAND[1]}] |"
    )
    print("|---|---|---|---|---|---|---|")
    code = 0
    for kind in kinds:
        rng = np.random.default_rng([args.seed, (STATIC_KINDS + DYNAMIC_KINDS).index(kind)])
        trials = args.dynamic_trials if kind in DYNAMIC_KINDS else args.trials
        z, seconds = run_kind(bench, kind, trials, rng)
        rms = float(np.sqrt(np.mean(z**2)))
        parts = [z[:, 0], z[:, 1:4], z[:, 4:7], z[:, 7:10]]
        split = ", ".join(f"{np.sqrt(np.mean(part**2)):.2f}" for part in parts)
        ok = bool(np.all(np.isfinite(z))) and BAND[0] <= rms <= BAND[1]
        code |= 0 if ok else 1
        print(
            f"| {kind} | {z.size} | {rms:.3f} | {split} | {np.abs(z).max():.2f} | {seconds:.2f} | "
            f"{verdict(ok)} |",
            flush=True,
        )
    print()
    print(f"total {time.perf_counter() - started:.0f} s")
    return code


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
