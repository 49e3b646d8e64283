"""Estimating the sensor's mount R_M: efficiency against the Cramér–Rao bound, cost, planned poses.

Monte-Carlo on two arms, the bundled one and UR5 (``ftkin.load_robot("ur5")``,
sensor 3 cm out of tool0): a fixed set of N = 12 random poses per arm (only
the noise is redrawn in each trial), a 15 N tool with its centre of mass a few
cm off the sensor axis, a base tilted by a fraction of a degree, noise
0.03 N / 0.0015 N·m per reading and 10 readings per pose, and the sensor
turned on its flange by ``R_M = Rz(35°) Ry(-2°) Rx(3°)`` (URDF rpy 3°, -2°, 35°).

Per arm the table prints, for every parameter of ``θ = [a, F0, M0, P]`` and
the three mount angles (rotation about the real sensor's x, y, z axes, error
``log(R_Mᵀ R̂_M)``):

* ``CRLB``: the Cramér–Rao standard deviation from the (12 + 3) Fisher information;
* ``RMSE``: the RMS error of ``calibrate(..., estimate_mount="full")``'s ML fit;
* ``eff``: the efficiency ``CRLB² / RMSE²`` (target ≥ 0.9);
* ``std/known``: RMSE with the mount estimated over RMSE with the mount known
  (the same data, rotations ``R_BS_urdf R_Mᵀ``): the cost of not knowing it.

Then planned poses (``plan_poses(..., estimate_mount="full")``) against random
poses of the same arm and count: predicted standard errors of the mount angles
and the geometric mean over θ, and the RMS error achieved on the planned poses.

The fits call :func:`ftkin.calibration.ml.fit_ml` on per-pose means with the
noise given (the maximum-likelihood core of ``calibrate``; the means of 10
readings are sufficient statistics for Gaussian noise).

Run: ``python benchmarks/bench_mount.py [--trials 1000] [--seed 0]`` (trials per
arm; the default 1000 × 2 arms = 2000 trials, about two minutes).
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np
from scipy.spatial.transform import Rotation

from ftkin import Arm, SensorModel, SensorNoise, load_robot, plan_poses
from ftkin.calibration import fisher_information
from ftkin.calibration.ml import fit_ml
from ftkin.calibration.samples import PoseAverages

POSES = 12
READINGS_PER_POSE = 10
MARGIN = 0.3  # [rad] kept from each joint limit
NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
TRUTH = SensorModel.from_tool(
    tool_mass=15.0 / 9.80665,  # 15 N tool [kg]
    center_of_mass=[0.03, -0.02, 0.08],  # [m] real sensor frame
    force_offset=[2.0, -1.5, 3.0],  # [N]
    torque_offset=[0.10, -0.05, 0.02],  # [N·m]
    base_tilt=np.deg2rad([0.3, -0.2]),  # U, V [rad]
)
MOUNT = Rotation.from_euler(
    "xyz", [3.0, -2.0, 35.0], degrees=True
).as_matrix()  # URDF rpy: Rz(35°) Ry(-2°) Rx(3°)
LABELS = [f"{block}[{axis}]" for block in ("a", "F0", "M0", "P") for axis in "xyz"] + [
    f"mount[{axis}]" for axis in "xyz"
]
UNITS = ["N"] * 6 + ["N·m"] * 3 + ["m"] * 3 + ["deg"] * 3


def crlb(rotations_urdf: np.ndarray) -> np.ndarray:
    """``(15,)`` Cramér–Rao standard deviations of ``[θ, mount angles]`` [SI units, rad]."""
    information = fisher_information(TRUTH, rotations_urdf, NOISE, READINGS_PER_POSE, "full", MOUNT)
    return np.sqrt(np.diag(np.linalg.inv(information)))


def pose_means(rotations: np.ndarray, real: np.ndarray, rng: np.random.Generator) -> PoseAverages:
    """Per-pose means of ``READINGS_PER_POSE`` noisy readings of the real sensor, stored with
    ``rotations``.
    """
    count = len(rotations)
    means = TRUTH.predict(real) + rng.normal(size=(count, 6)) * NOISE.channel_std / np.sqrt(
        READINGS_PER_POSE
    )
    return PoseAverages(
        np.arange(count),
        rotations,
        means,
        np.full(count, READINGS_PER_POSE),
        np.full((count, 6), np.nan),
    )


def errors_of(fit) -> np.ndarray:
    """``(15,)`` error of ``[θ, mount angles]``; the mount error as a rotation vector about the real
    sensor's axes.
    """
    mount_error = Rotation.from_matrix(MOUNT.T @ fit.mount_rotation).as_rotvec()
    return np.concatenate([fit.model.to_vector() - TRUTH.to_vector(), mount_error])


def monte_carlo(
    rotations_urdf: np.ndarray,
    trials: int,
    rng: np.random.Generator,
    label: str,
    known: bool = True,
):
    """RMS errors with the mount estimated (and known), and the seconds per estimated fit."""
    real = rotations_urdf @ MOUNT.T
    estimated, fixed = np.empty((trials, 15)), np.empty((trials, 12))
    seconds = 0.0
    for trial in range(trials):
        poses = pose_means(rotations_urdf, real, rng)
        start = time.perf_counter()
        estimated[trial] = errors_of(fit_ml(poses, noise=NOISE, estimate_mount="full"))
        seconds += time.perf_counter() - start
        if known:
            mounted = PoseAverages(poses.pose_ids, real, poses.wrenches, poses.counts, poses.spread)
            fixed[trial] = fit_ml(mounted, noise=NOISE).model.to_vector() - TRUTH.to_vector()
        if (trial + 1) % 100 == 0 or trial + 1 == trials:
            print(f"  {label}: {trial + 1}/{trials} trials", file=sys.stderr, flush=True)
    rmse = np.sqrt(np.mean(estimated**2, axis=0))
    rmse_known = np.sqrt(np.mean(fixed**2, axis=0)) if known else None
    return rmse, rmse_known, seconds / trials


def _scaled(values: np.ndarray) -> np.ndarray:
    """Mount angles from rad to deg for printing."""
    out = np.array(values, dtype=float)
    out[12:15] = np.rad2deg(out[12:15])
    return out


def table(name: str, bound: np.ndarray, rmse: np.ndarray, rmse_known: np.ndarray) -> list[str]:
    lines = [
        f"{name}: mount rpy (3, -2, 35) deg, {POSES} random poses x {READINGS_PER_POSE} readings",
        f"  {'parameter':<10}{'unit':<5}{'CRLB':>11}{'RMSE':>11}{'eff':>7}{'std/known':>11}",
    ]
    bound_s, rmse_s = _scaled(bound), _scaled(rmse)
    for k, (label, unit) in enumerate(zip(LABELS, UNITS)):
        ratio = f"{rmse[k] / rmse_known[k]:>11.3f}" if k < 12 else f"{'-':>11}"
        lines.append(
            "  "
            f"{label:<10}{unit:<5}{bound_s[k]:>11.3e}{rmse_s[k]:>11.3e}"
            f"{bound[k] ** 2 / rmse[k] ** 2:>7.3f}{ratio}"
        )
    efficiency = bound**2 / rmse**2
    lines.append(
        f"  efficiency min {efficiency.min():.3f} (target >= 0.9 "
        f"{'PASS' if efficiency.min() >= 0.9 else 'FAIL'}), median "
        f"{np.median(efficiency):.3f}; "
        f"std/known median {np.median(rmse[:12] / rmse_known):.3f}, max "
        f"{np.max(rmse[:12] / rmse_known):.3f}"
    )
    return lines


def planned_vs_random(
    arm: Arm, name: str, random_rotations: np.ndarray, trials: int, rng
) -> list[str]:
    plan = plan_poses(
        arm,
        POSES,
        estimate_mount="full",
        tool_weight=TRUTH.tool_weight,
        center_of_mass=TRUTH.center_of_mass,
        noise=NOISE,
        readings_per_pose=READINGS_PER_POSE,
        candidates=1500,
        progress=False,
        seed=1,
    )
    planned_rotations = arm.rotation_sensor_to_base(plan.joint_positions)
    lines = [
        f"{name}: planned (estimate_mount='full') vs random poses, {POSES} each",
        "  "
        f"{'poses':<8}{'sigma mount x, y, z [deg] (CRLB)':>36}{'geo-mean theta CRLB ratio':>28}"
        f"{'mount RMSE [deg]':>24}",
    ]
    random_bound, planned_bound = crlb(random_rotations), crlb(planned_rotations)
    rmse, _, _ = monte_carlo(planned_rotations, trials, rng, f"{name} planned", known=False)
    for label, bound in (("random", random_bound), ("planned", planned_bound)):
        mount = ", ".join(f"{value:.4f}" for value in np.rad2deg(bound[12:]))
        ratio = float(np.exp(np.mean(np.log(bound[:12] / random_bound[:12]))))
        achieved = (
            ", ".join(f"{value:.4f}" for value in np.rad2deg(rmse[12:]))
            if label == "planned"
            else "(above)"
        )
        lines.append(f"  {label:<8}{mount:>36}{ratio:>28.3f}{achieved:>24}")
    return lines


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--trials", type=int, default=1000, help="Monte-Carlo trials per arm (default: %(default)s)"
    )
    parser.add_argument(
        "--plan-trials",
        type=int,
        default=200,
        help="trials on the planned poses (default: %(default)s)",
    )
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    arms = (("bundled arm", Arm.default()), ("UR5", load_robot("ur5", [0.0, 0.0, 0.03])))
    output, started = [], time.perf_counter()
    for name, arm in arms:
        rotations = arm.rotation_sensor_to_base(
            arm.random_configurations(POSES, rng, margin=MARGIN)
        )
        rmse, rmse_known, seconds = monte_carlo(rotations, args.trials, rng, name)
        output += table(name, crlb(rotations), rmse, rmse_known)
        output.append(
            f"  {args.trials} trials; mean time per full-mount fit {1000 * seconds:.1f} ms"
        )
        output += planned_vs_random(arm, name, rotations, args.plan_trials, rng)
        output.append("")
    output.append(
        f"total {time.perf_counter() - started:.0f} s, {2 * args.trials} trials (+ "
        f"{2 * args.plan_trials} on planned poses)"
    )
    print("\n".join(output))
    return 0


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
