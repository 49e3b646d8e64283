"""Dynamic calibration and compensation during motion, against MuJoCo as the truth.

Setup: the bundled arm in MuJoCo (``ftkin.sim.mujoco.recording``) carrying a
1.5 kg tool of known, non-diagonal inertia; base tilted by (0.3°, −0.2°);
sensor bias [2, −1.5, 3] N, [0.1, −0.05, 0.02] N·m; white sensor noise
0.05 N / 0.003 N·m per reading and encoder noise 1e-5 rad, at 1 kHz. The
calibration sees only the noisy joint positions: velocities and accelerations
come from the zero-phase Savitzky–Golay differentiator, as on a real log.

Rows:

1. identification from a 30 s planned excitation (``plan_excitation``): mass,
   COM and inertia errors against the targets (≤ 0.5 %, ≤ 1 mm, every
   inertia element within 5 % of the largest principal moment);
2. a fast validation motion not used for identification (peak joint speed
   ≥ 1.5 rad/s, acceleration ≥ 8 rad/s²): RMS of the compensated wrench
   (no contact, so all of it is error) with static and with dynamic
   compensation, beside the noise floor (target: dynamic ≥ 10× lower);
3. planned excitation against a random Fourier trajectory with the same
   limits: standard errors of the six inertia elements (delta method, and a
   Monte-Carlo spread over noise seeds);
4. cost per tick of ``DynamicCompensator.compensate_moving`` against
   ``Compensator.compensate`` with the identified tool, timed as
   ``bench_control.py`` does (alternating blocks, CPU time, the median of
   the per-repeat ratios; target ≤ 2×; ``bench_control.py`` has the same row).

Run: ``.venv/bin/python benchmarks/bench_dynamic.py``
"""

from __future__ import annotations

import os
import sys
import time

import numpy as np

from ftkin import Arm, Compensator
from ftkin.calibration.derivatives import joint_derivatives
from ftkin.calibration.dynamic import calibrate_dynamic
from ftkin.calibration.log_cholesky import is_physically_consistent
from ftkin.calibration.regressor import MotionSamples
from ftkin.control.dynamic_compensation import DynamicCompensator
from ftkin.kinematics.rotations import euler_zyx_to_matrix
from ftkin.planning.constraints import PoseConstraints
from ftkin.planning.excitation import plan_excitation
from ftkin.sim.mujoco.recording import MujocoRecorder, ToolInertia

RATE = 1000.0
FORCE_STD, TORQUE_STD, ENCODER_STD = 0.05, 0.003, 1e-5
BIAS = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])
TILT = np.deg2rad([0.3, -0.2])
MONTE_CARLO = 4


def make_tool() -> ToolInertia:
    rotation = euler_zyx_to_matrix([0.4, -0.3, 0.2])
    inertia = rotation @ np.diag([0.0060, 0.0052, 0.0021]) @ rotation.T
    return ToolInertia(1.5, [0.006, -0.012, 0.072], inertia)


def record(recorder, arm, plan, rng):
    """Noisy readings and noisy joint positions along a plan; derivatives from the noisy
    positions.
    """
    q, dq, ddq = plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
    wrenches = recorder.wrenches(q, dq, ddq) + BIAS
    wrenches += rng.normal(0.0, [FORCE_STD] * 3 + [TORQUE_STD] * 3, wrenches.shape)
    measured_q = q + rng.normal(0.0, ENCODER_STD, q.shape)
    return MotionSamples.from_joint_trajectory(
        arm, *joint_derivatives(plan.times, measured_q), wrenches, plan.times
    )


def errors(result, tool: ToolInertia):
    largest = np.linalg.eigvalsh(tool.inertia_about_com)[-1]
    mass = abs(result.tool_mass - tool.mass) / tool.mass
    com = np.linalg.norm(result.center_of_mass - tool.center_of_mass)
    inertia = np.abs(result.inertia_about_com_in_sensor - tool.inertia_about_com).max() / largest
    return mass, com, inertia


def inertia_entries(result) -> np.ndarray:
    matrix = result.inertia_about_com_in_sensor
    return np.array(
        [matrix[0, 0], matrix[1, 1], matrix[2, 2], matrix[0, 1], matrix[0, 2], matrix[1, 2]]
    )


def tick_costs(arm, result, repeats: int = 21):
    """Median seconds per tick, static and dynamic, and the median ratio
    (``bench_control.paired``).
    """
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from bench_control import paired

    rng = np.random.default_rng(1)
    static, dynamic = Compensator(result, arm), DynamicCompensator(result, arm)
    q, dq, ddq, raw = (
        rng.normal(size=arm.nq) * 0.5,
        rng.normal(size=arm.nq),
        rng.normal(size=arm.nq) * 5,
        rng.normal(size=6),
    )
    return paired(
        lambda: static.compensate(q, raw),
        lambda: dynamic.compensate_moving(q, dq, ddq, raw),
        repeats,
    )


def main() -> None:
    arm = Arm.default()
    tool = make_tool()
    recorder = MujocoRecorder(joint_names=arm.joint_names, tool=tool, base_tilt=TILT)
    constraints = PoseConstraints(floor_height=0.15)
    started = time.perf_counter()
    planned = plan_excitation(arm, 30.0, rate=RATE, period=10.0, constraints=constraints, seed=0)
    random_plan = plan_excitation(
        arm,
        30.0,
        rate=RATE,
        period=10.0,
        constraints=constraints,
        seed=1,
        candidates=20,
        optimize=False,
    )
    validation = plan_excitation(
        arm,
        4.0,
        rate=RATE,
        period=2.0,
        harmonics=4,
        velocity_fraction=0.6,
        acceleration_limit=14.0,
        constraints=constraints,
        seed=7,
        candidates=20,
        optimize=False,
    )
    planning_time = time.perf_counter() - started

    rng = np.random.default_rng(2026)
    started = time.perf_counter()
    identification = record(recorder, arm, planned, rng)
    result = calibrate_dynamic(identification)
    calibration_time = time.perf_counter() - started
    mass_error, com_error, inertia_error = errors(result, tool)

    check = record(recorder, arm, validation, rng)
    static_contact = Compensator(result, arm).compensate_batch(check.rotations, check.wrenches)
    dynamic_contact = DynamicCompensator(result, arm).compensate_motion(check)
    trim = slice(50, -50)  # the differentiator's edges

    def rms(wrenches, part):
        return float(np.sqrt(np.mean(np.sum(wrenches[trim, part] ** 2, axis=1))))

    force, torque = slice(0, 3), slice(3, 6)
    noise_force, noise_torque = FORCE_STD * np.sqrt(3), TORQUE_STD * np.sqrt(3)

    spreads = {}
    for name, plan in (("planned", planned), ("random", random_plan)):
        estimates, predicted = [], []
        for seed in range(MONTE_CARLO):
            fit = calibrate_dynamic(record(recorder, arm, plan, np.random.default_rng(100 + seed)))
            estimates.append(inertia_entries(fit))
            sigma = fit.inertia_std_errors
            predicted.append(
                [sigma[0, 0], sigma[1, 1], sigma[2, 2], sigma[0, 1], sigma[0, 2], sigma[1, 2]]
            )
        spreads[name] = (
            np.std(estimates, axis=0, ddof=1),
            np.mean(predicted, axis=0),
            plan.log_det,
        )
    static_tick, dynamic_tick, tick_ratio = tick_costs(arm, result)

    peak_speed = np.abs(validation.joint_velocities).max()
    peak_acceleration = np.abs(validation.joint_accelerations).max()
    print(
        f"bench_dynamic: bundled arm, MuJoCo truth, {RATE:g} Hz, tool {tool.mass} kg, "
        f"noise {FORCE_STD} N / {TORQUE_STD} N·m, encoder {ENCODER_STD} rad "
        f"(planning {planning_time:.1f} s, calibration {calibration_time:.1f} s)"
    )
    print()
    print("| quantity | ftkin | target |")
    print("|---|---|---|")
    passed = lambda ok: "PASS" if ok else "FAIL"  # noqa: E731
    print(
        f"| mass error, 30 s planned excitation | {100 * mass_error:.3f} % | ≤ 0.5 % "
        f"{passed(mass_error <= 0.005)} |"
    )
    print(f"| COM error | {1000 * com_error:.3f} mm | ≤ 1 mm {passed(com_error <= 1e-3)} |")
    print(
        f"| worst inertia element error / largest principal moment | {100 * inertia_error:.2f} % | "
        f"≤ 5 % {passed(inertia_error <= 0.05)} |"
    )
    consistent = "yes" if is_physically_consistent(result.inertial_parameters) else "NO"
    print(
        f"| physically consistent (unconstrained LS consistent) | {consistent} "
        f"({result.unconstrained_consistent}) | yes |"
    )
    print(
        f"| validation motion: peak joint speed, acceleration | {peak_speed:.2f} rad/s, "
        f"{peak_acceleration:.1f} rad/s² | ≥ 1.5, ≥ 8 |"
    )
    print(
        "| compensated force RMS, static / dynamic (noise floor) | "
        f"{rms(static_contact, force):.4f} / "
        f"{rms(dynamic_contact, force):.4f} N ({noise_force:.4f}) | dynamic ≥ 10× lower |"
    )
    print(
        "| compensated torque RMS, static / dynamic (noise floor) | "
        f"{rms(static_contact, torque):.5f} / "
        f"{rms(dynamic_contact, torque):.5f} N·m ({noise_torque:.5f}) | |"
    )
    print(
        "| ratio static / dynamic, force, torque | "
        f"{rms(static_contact, force) / rms(dynamic_contact, force):.1f}×, "
        f"{rms(static_contact, torque) / rms(dynamic_contact, torque):.1f}× | ≥ 10× |"
    )
    for name in ("planned", "random"):
        spread, predicted, log_det = spreads[name]
        print(
            f"| {name} trajectory (log det {log_det:.1f}): inertia std, Monte Carlo ({MONTE_CARLO} "
            "runs) / predicted, "
            f"mean of 6 elements | {1e6 * spread.mean():.2f} / {1e6 * predicted.mean():.2f} ×1e-6 "
            "kg·m² | planned lower |"
        )
    print(
        f"| cost per tick: Compensator.compensate / DynamicCompensator.compensate_moving | "
        f"{1e6 * static_tick:.2f} / {1e6 * dynamic_tick:.2f} µs ({tick_ratio:.2f}×; load average "
        f"{os.getloadavg()[0]:.1f}) | ≤ 2× |"
    )


if __name__ == "__main__":
    from _targets import run_benchmark

    raise SystemExit(run_benchmark(main))
