"""Are the reported standard errors honest? ``z = (estimate − truth) / std error`` against MuJoCo.

The three cheapest kinds of ``benchmarks/bench_standard_errors.py`` (static from rotations, from
joints, with the mount estimated) on a smaller Monte Carlo; and the dynamic IMU fit's
covariance with a prior, whose accelerometer bias is itself an estimate.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from scipy.spatial.transform import Rotation
from scipy.stats import chi2

from ftkin import Samples, calibrate
from ftkin.calibration.imu_dynamic import calibrate_imu_dynamic
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import body_from_parameters
from ftkin.calibration.model import skew
from ftkin.planning.constraints import PoseConstraints
from ftkin.planning.excitation import plan_excitation

from .test_imu_dynamic import BIAS, SCALE, WRENCH_BIAS, motion, tool_recorder

POSES, READINGS, TRIALS = 12, 40, 60
WRENCH_STD = np.array([0.05] * 3 + [0.003] * 3)  # per reading [N, N·m]
MOUNT = Rotation.from_euler("xyz", [3.0, -2.0, 35.0], degrees=True).as_matrix()  # R_M
P_VALUE = 1e-4  # two-sided chance that honest standard errors fall outside the band
# The 10 z values of one trial (mass, COM, F0, M0) are correlated; the mean of their squares
# varies at most as one χ²₁ does, so the TRIALS trials hold at least TRIALS independent values:
# with honest errors RMS z² · TRIALS ~ χ²(TRIALS) at worst. 60 trials: RMS z in [0.66, 1.37].
BAND = tuple(np.sqrt(chi2.ppf([P_VALUE / 2, 1 - P_VALUE / 2], TRIALS) / TRIALS))


@pytest.fixture(scope="module")
def static_recording():
    """12 random poses of the bundled arm in MuJoCo with a 1.5 kg tool, noise-free: the joint
    angles, MuJoCo's ``R_BS``, the readings and the truth ``[m, c, F0, M0]``."""
    arm, recorder = tool_recorder()
    q = arm.random_configurations(POSES, np.random.default_rng(7), margin=0.3)
    wrench = recorder.wrenches(q)
    rotations = np.array([recorder.sensor_rotation(row) for row in q])
    mass, com, _ = body_from_parameters(recorder.true_parameters())
    return arm, q, rotations, wrench, mass, com


def _values(result) -> tuple[np.ndarray, np.ndarray]:
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


@pytest.mark.parametrize("kind", ["rotations", "joints", "mount"])
def test_static_standard_errors_are_honest(static_recording, kind):
    arm, q, rotations, wrench, mass, com = static_recording
    ids = np.repeat(np.arange(POSES), READINGS)
    if kind == "mount":  # the sensor turned by R_M on its flange: its readings in its own axes
        wrench = wrench @ np.kron(np.eye(2), MOUNT).T
        com = MOUNT @ com
    truth = np.concatenate([[mass], com, WRENCH_BIAS])
    rng = np.random.default_rng(["rotations", "joints", "mount"].index(kind))
    z = np.empty((TRIALS, 10))
    for trial in range(TRIALS):
        noisy = wrench[ids] + WRENCH_BIAS + rng.normal(size=(len(ids), 6)) * WRENCH_STD
        if kind == "rotations":
            result = calibrate(Samples(noisy, rotations[ids], ids))
        else:
            samples = Samples.from_joint_positions(arm, q[ids], noisy, ids)
            result = calibrate(samples, **({"estimate_mount": "full"} if kind == "mount" else {}))
        estimate, sigma = _values(result)
        z[trial] = (estimate - truth) / sigma
    rms = float(np.sqrt(np.mean(z**2)))
    assert BAND[0] <= rms <= BAND[1], f"{kind}: RMS z {rms:.3f} outside {BAND}"


def test_a_priors_accelerometer_bias_error_reaches_the_dynamic_offsets():
    """A prior's accelerometer bias ``b`` is an estimate: held at it, the moving fit's offsets
    absorb its error exactly (a constant ``δb`` adds the constant force ``m R_SI δb`` and moment
    ``h × R_SI δb``, ``h = m c``), so their covariance grows by ``m² R Σ_b Rᵀ`` and
    ``[h]× R Σ_b Rᵀ [h]×ᵀ`` over the fit with ``b`` given as exact."""
    arm, recorder = tool_recorder()
    rng = np.random.default_rng(11)
    poses = arm.random_configurations(8, rng, margin=0.3)
    wrench, accel, _ = recorder.readings(poses)
    ids = np.repeat(np.arange(8), 20)
    accel = (1.0 + SCALE) * accel[ids] + BIAS + rng.normal(0.0, 0.02, (len(ids), 3))
    noisy = wrench[ids] + WRENCH_BIAS + rng.normal(size=(len(ids), 6)) * WRENCH_STD
    prior = calibrate(ImuSamples.from_arrays(accel, noisy, ids))
    names = list(prior.parameter_names)
    keep = [names.index(f"accel_bias[{axis}]") for axis in "xyz"]
    bias_only = np.zeros_like(prior.parameter_covariance)  # the scale's errors are left out
    bias_only[np.ix_(keep, keep)] = prior.parameter_covariance[np.ix_(keep, keep)]
    prior = replace(prior, parameter_covariance=bias_only)
    times, moving_wrench, moving_accel, gyro = motion(arm, recorder, 4, seconds=4.0)
    samples = ImuSamples(moving_accel, moving_wrench, angular_velocity=gyro, times=times)

    exact = calibrate_imu_dynamic(
        samples, accel_bias=prior.accel_bias, accel_scale=prior.accel_scale
    )
    held = calibrate_imu_dynamic(samples, prior=prior)

    def block(result, prefix):
        index = [list(result.parameter_names).index(f"{prefix}[{axis}]") for axis in "xyz"]
        return result.parameter_covariance[np.ix_(index, index)]

    rotated = held.imu_rotation @ bias_only[np.ix_(keep, keep)] @ held.imu_rotation.T
    first_moment = skew(held.tool_mass * held.center_of_mass)
    expected_force = held.tool_mass**2 * rotated
    expected_torque = first_moment @ rotated @ first_moment.T
    added_force = block(held, "force_offset") - block(exact, "force_offset")
    added_torque = block(held, "torque_offset") - block(exact, "torque_offset")
    np.testing.assert_allclose(added_force, expected_force, rtol=0.02, atol=1e-9)
    np.testing.assert_allclose(added_torque, expected_torque, rtol=0.02, atol=1e-11)


@pytest.fixture(scope="module")
def moving_recording():
    """``benchmarks/bench_standard_errors.py``'s motion (6 s at 250 Hz) in MuJoCo, noise-free:
    ``(times, wrench, specific force, gyro, truth [m, c, F0, M0])``."""
    arm, recorder = tool_recorder()
    plan = plan_excitation(
        arm,
        6.0,
        rate=250.0,
        period=3.0,
        constraints=PoseConstraints(floor_height=0.15),
        seed=0,
        candidates=20,
        optimize=False,
    )
    wrench, accel, gyro = recorder.readings(
        plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
    )
    mass, com, _ = body_from_parameters(recorder.true_parameters())
    return plan.times, wrench, accel, gyro, np.concatenate([[mass], com, WRENCH_BIAS])


def _dynamic_imu_z(recording, rng, trials, accel_std, gyro_std, wrench_scale) -> np.ndarray:
    """``(trials, 10)`` z of [m, c, F0, M0] of ``calibrate_imu_dynamic`` with ``b``, ``s`` given
    exactly, on the recording with fresh white noise [m/s², rad/s; × WRENCH_STD]."""
    times, wrench, accel, gyro, truth = recording
    names = ["tool_mass"] + [
        f"{block}[{axis}]"
        for block in ("center_of_mass", "force_offset", "torque_offset")
        for axis in "xyz"
    ]
    z = np.empty((trials, 10))
    for trial in range(trials):
        samples = ImuSamples(
            (1.0 + SCALE) * accel + BIAS + rng.normal(0.0, accel_std, accel.shape),
            wrench + WRENCH_BIAS + rng.normal(size=wrench.shape) * WRENCH_STD * wrench_scale,
            angular_velocity=gyro + rng.normal(0.0, gyro_std, gyro.shape),
            times=times,
        )
        result = calibrate_imu_dynamic(samples, accel_bias=BIAS, accel_scale=SCALE)
        estimate = np.concatenate(
            [[result.tool_mass], result.center_of_mass, result.force_offset, result.torque_offset]
        )
        z[trial] = (estimate - truth) / result.std_error_of(names)
    return z


def test_the_gyros_noise_does_not_bias_the_dynamic_imu_fit(moving_recording):
    """The gyro's derivative sits in the regressor: with the default window too short its noise
    biased mass, COM and offsets by several standard errors (errors in the variables). Six
    seeded recordings, gyro 0.005 rad/s, accelerometer 0.02 m/s², wrench 0.05 N / 0.003 N·m per
    reading: unbiased and honest, each component's mean z over the six has standard deviation
    1/√6 ≈ 0.41; |mean z| ≤ 2 is 4.9 of them (the 51 ms window gave mean z up to 4.0 here)."""
    z = _dynamic_imu_z(moving_recording, np.random.default_rng(12), 6, 0.02, 0.005, 1.0)
    mean = np.mean(z, axis=0)
    assert np.all(np.abs(mean) <= 2.0), f"mean z {np.round(mean, 2)}"


def test_the_smoothed_accelerometer_noise_is_counted_at_its_full_variance(moving_recording):
    """The accelerometer's noise dominating (0.05 m/s² per reading, the wrench's a thousandth of
    its usual): the smoothed signal shows the residuals ``σ² Σ c_k²`` (0.14 of it at 25
    samples) but the constant parameters see ``σ²`` (the filter's gain at zero frequency is 1).
    Counted at the smoothed variance the standard errors were ``1/√0.14 ≈ 2.7`` times too small.
    Ten trials: the 100 z values hold at least 10 independent ones, so with honest errors
    RMS z² · 10 ~ χ²(10) at worst: RMS z within [0.28, 1.93] (two-sided 1e-4)."""
    z = _dynamic_imu_z(moving_recording, np.random.default_rng(21), 10, 0.05, 1e-6, 1e-3)
    band = np.sqrt(chi2.ppf([5e-5, 1 - 5e-5], 10) / 10)
    rms = float(np.sqrt(np.mean(z**2)))
    assert band[0] <= rms <= band[1], f"RMS z {rms:.3f} outside {np.round(band, 2)}"
