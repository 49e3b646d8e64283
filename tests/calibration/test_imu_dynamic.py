"""Dynamic identification from the sensor's IMU (no joints): recovery from MuJoCo, what a moving
recording cannot separate, and the Jacobian against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.calibration.imu_dynamic import calibrate_imu_dynamic
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import body_from_parameters
from ftkin.exceptions import InvalidInput, UnobservableParameters

IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
IMU_POSITION = np.array([0.021, -0.012, 0.027])
BIAS = np.array([0.76, -0.30, 0.20])
SCALE = np.array([0.005, -0.003, 0.002])
WRENCH_BIAS = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])
RATE = 250.0
NOISE = np.array([0.05] * 3 + [0.003] * 3)  # wrench noise per reading [N, N·m]


def tool_recorder():
    """The bundled arm in MuJoCo with a 1.5 kg tool and the IMU on a turned, offset site."""
    pytest.importorskip("mujoco")
    from ftkin import Arm
    from ftkin.sim.mujoco.imu_recording import MujocoImuRecorder
    from ftkin.sim.mujoco.tool_inertia import ToolInertia

    arm = Arm.default()
    turn = Rotation.from_euler("xyz", [0.4, -0.3, 0.2]).as_matrix()
    tool = ToolInertia(
        1.5, [0.006, -0.012, 0.072], turn @ np.diag([0.0060, 0.0052, 0.0021]) @ turn.T
    )
    recorder = MujocoImuRecorder(
        imu_rotation=IMU_ROTATION, imu_position=IMU_POSITION, joint_names=arm.joint_names, tool=tool
    )
    return arm, recorder


def motion(arm, recorder, seed, frequencies=(0.11, 0.23, 0.37), seconds=12.0):
    """``seconds`` of a multi-sine motion at 250 Hz (MuJoCo inverse dynamics) with the
    accelerometer's bias and scale, and noise, added: ``(t, wrench, accel, gyro)``."""
    times = np.arange(0.0, seconds, 1.0 / RATE)
    rng = np.random.default_rng(seed)
    amplitude = rng.uniform(0.3, 0.9, (arm.nq, 3))
    offset = rng.uniform(-0.5, 0.5, arm.nq)
    omega = 2 * np.pi * np.array([frequencies])  # [rad/s]
    phase = omega * times[:, None, None]  # (N, 1, 3)
    q = offset + np.sum(amplitude * np.sin(phase), axis=2)
    dq = np.sum(amplitude * omega * np.cos(phase), axis=2)
    ddq = -np.sum(amplitude * omega**2 * np.sin(phase), axis=2)
    wrench, accel, gyro = recorder.readings(q, dq, ddq)
    accel = (1.0 + SCALE) * accel + BIAS + rng.normal(0.0, 0.02, accel.shape)
    gyro = gyro + rng.normal(0.0, 0.003, gyro.shape)
    wrench = wrench + WRENCH_BIAS + rng.normal(0.0, 1.0, wrench.shape) * NOISE
    return times, wrench, accel, gyro


@pytest.fixture(scope="module")
def recording():
    """12 s of a multi-sine motion of the bundled arm in MuJoCo at 250 Hz, with its accelerometer
    and gyro; biases and noise added here."""
    arm, recorder = tool_recorder()
    times, wrench, accel, gyro = motion(arm, recorder, 3)
    samples = ImuSamples(accel, wrench, angular_velocity=gyro, times=times)
    return samples, recorder.true_parameters()


def test_recovers_mass_com_inertia_rotation_and_position(recording):
    samples, theta = recording
    result = calibrate_imu_dynamic(samples, accel_bias=BIAS, accel_scale=SCALE)
    mass, com, inertia = body_from_parameters(theta)
    assert result.method == "imu-dynamic"
    assert abs(result.tool_mass - mass) / mass < 0.01
    assert np.linalg.norm(result.center_of_mass - com) < 2e-3
    largest = np.linalg.eigvalsh(inertia)[-1]
    assert np.abs(result.inertia_about_com_in_sensor - inertia).max() < 0.1 * largest
    assert np.linalg.norm(result.imu_position - IMU_POSITION) < 3e-3
    assert result.imu_position_source == "estimated"
    turn = Rotation.from_matrix(result.imu_rotation.T @ IMU_ROTATION).magnitude()
    assert np.rad2deg(turn) < 0.3
    np.testing.assert_allclose(result.force_offset, WRENCH_BIAS[:3], atol=0.05)
    np.testing.assert_allclose(result.torque_offset, WRENCH_BIAS[3:], atol=5e-3)
    assert result.has_inertia and result.inertia_std_errors is not None
    # the standard errors cover the COM error
    sigma = result.std_error_of(["center_of_mass[x]", "center_of_mass[y]", "center_of_mass[z]"])
    assert np.all(np.abs(result.center_of_mass - com) < 6 * sigma)
    # the same through ftkin.calibrate_dynamic
    through = ftkin.calibrate_dynamic(samples, accel_bias=BIAS, accel_scale=SCALE)
    np.testing.assert_allclose(through.tool_mass, result.tool_mass, rtol=1e-9)


def test_without_a_bias_the_motion_gives_the_body_and_names_what_it_cannot_split(recording):
    """No prior, no bias (issue 37, item 6: was refused): mass within 1 %, COM within 2 mm of
    MuJoCo's bodies; the offsets are the combined ones the static model predicts, and the result
    names the combination and the way to split it, through either door."""
    samples, theta = recording
    result = calibrate_imu_dynamic(samples)
    mass, com, _ = body_from_parameters(theta)
    assert abs(result.tool_mass - mass) / mass < 0.01
    assert np.linalg.norm(result.center_of_mass - com) < 2e-3
    assert result.inseparable == ("accel_bias", "force_offset", "torque_offset")
    np.testing.assert_allclose(result.accel_bias, np.zeros(3), atol=0.0)
    (warning,) = result.warnings
    assert "--prior" in warning and "prior=" in warning and "accel_bias=(0" not in warning
    assert "not separated   accel_bias, force_offset, torque_offset" in result.summary()
    # the offsets absorb m R_SI b and m c × R_SI b (b corrected by the scale: given exact here)
    absorbed = calibrate_imu_dynamic(samples, accel_scale=SCALE)
    turned = IMU_ROTATION @ (BIAS / (1.0 + SCALE))
    np.testing.assert_allclose(absorbed.force_offset, WRENCH_BIAS[:3] + mass * turned, atol=0.02)
    expected_torque = WRENCH_BIAS[3:] + mass * np.cross(com, turned)
    np.testing.assert_allclose(absorbed.torque_offset, expected_torque, atol=2e-3)
    # a given bias (or a prior) separates them: nothing is named
    assert calibrate_imu_dynamic(samples, accel_bias=BIAS).inseparable == ()


def test_the_combined_offsets_compensate_another_motion_to_the_noise(recording):
    """The calibration without a bias compensates a second, different motion of the same tool
    with the same IMU (MuJoCo) to the wrench noise: nothing but noise is left."""
    from ftkin.control import ImuCompensator

    samples, _ = recording
    arm, recorder = tool_recorder()
    times, wrench, accel, gyro = motion(arm, recorder, 8, (0.07, 0.19, 0.29), 10.0)
    other = ImuSamples(accel, wrench, angular_velocity=gyro, times=times)
    contact = ImuCompensator(calibrate_imu_dynamic(samples)).compensate_recording(other)
    rms = np.sqrt(np.mean(contact**2, axis=0))
    assert np.all(rms < 2.0 * NOISE), rms  # the noise is NOISE per channel
    # the test can fail: the raw wrench less the mean is far above the noise
    assert np.all(np.sqrt(np.mean((wrench - wrench.mean(axis=0)) ** 2, axis=0)) > 10 * NOISE)


def test_a_prior_whose_bias_was_not_separated_is_refused(recording):
    samples, _ = recording
    moving = calibrate_imu_dynamic(samples)
    with pytest.raises(InvalidInput, match="did not separate the accelerometer's bias"):
        calibrate_imu_dynamic(samples, prior=moving)
    with pytest.raises(InvalidInput, match=r"prior \(prior=, --prior\) must be a static"):
        calibrate_imu_dynamic(samples, prior=_fk_calibration())


def _fk_calibration():
    return ftkin.CalibrationResult(
        force_offset=np.zeros(3),
        torque_offset=np.zeros(3),
        gravity_in_base=[0.0, 0.0, -14.7],
        center_of_mass=[0.0, 0.0, 0.05],
    )


def test_static_recording_and_missing_signals(recording):
    samples, _ = recording
    up = IMU_ROTATION.T @ np.array([0.0, 0.0, 9.80665]) + BIAS  # at rest, sensor upright
    still = ImuSamples(
        np.tile(up, (500, 1)),
        np.tile([0.0, 0.0, -14.7, 0.0, 0.0, 0.0], (500, 1)),
        angular_velocity=np.zeros((500, 3)),
        times=np.arange(500) / RATE,
    )
    with pytest.raises(UnobservableParameters, match="inertia"):
        calibrate_imu_dynamic(still, accel_bias=BIAS)
    no_gyro = ImuSamples(samples.specific_force, samples.wrenches, times=samples.times)
    with pytest.raises(InvalidInput, match="angular velocity"):
        calibrate_imu_dynamic(no_gyro, accel_bias=BIAS)
    with pytest.raises(InvalidInput, match="always estimates the inertia"):
        ftkin.calibrate_dynamic(samples, estimate_inertia=False, accel_bias=BIAS)
    with pytest.raises(InvalidInput, match="unknown calibrate_dynamic option"):
        ftkin.calibrate_dynamic(
            ftkin.calibration.MotionSamples.from_static(_fk_samples()), prior=None
        )


def _fk_samples():
    rotations = Rotation.random(4, random_state=0).as_matrix()
    return ftkin.Samples.from_rotations(rotations, np.tile([0.0, 0.0, -10.0, 0, 0, 0], (4, 1)))
