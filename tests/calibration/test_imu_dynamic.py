"""Dynamic identification from the sensor's IMU (no joints): recovery from MuJoCo, what a moving
recording cannot separate, and the Jacobian against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.calibration.imu_dynamic import ImuDynamicProblem, ImuMotion, calibrate_imu_dynamic
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import body_from_parameters
from ftkin.exceptions import InvalidInput, UnobservableParameters

IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
IMU_POSITION = np.array([0.021, -0.012, 0.027])
BIAS = np.array([0.76, -0.30, 0.20])
SCALE = np.array([0.005, -0.003, 0.002])
WRENCH_BIAS = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])
RATE = 250.0


@pytest.fixture(scope="module")
def recording():
    """12 s of a multi-sine motion of the bundled arm in MuJoCo at 250 Hz, with its accelerometer
    and gyro; biases and noise added here."""
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
    times = np.arange(0.0, 12.0, 1.0 / RATE)
    frequencies = np.array([[0.11, 0.23, 0.37]])  # [Hz]
    rng = np.random.default_rng(3)
    amplitude = rng.uniform(0.3, 0.9, (arm.nq, 3))
    offset = rng.uniform(-0.5, 0.5, arm.nq)
    omega = 2 * np.pi * frequencies
    phase = omega * times[:, None, None]  # (N, 1, 3)
    q = offset + np.sum(amplitude * np.sin(phase), axis=2)
    dq = np.sum(amplitude * omega * np.cos(phase), axis=2)
    ddq = -np.sum(amplitude * omega**2 * np.sin(phase), axis=2)
    wrench, accel, gyro = recorder.readings(q, dq, ddq)
    accel = (1.0 + SCALE) * accel + BIAS + rng.normal(0.0, 0.02, accel.shape)
    gyro = gyro + rng.normal(0.0, 0.003, gyro.shape)
    wrench = wrench + WRENCH_BIAS + rng.normal(0.0, 1.0, wrench.shape) * ([0.05] * 3 + [0.003] * 3)
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


def test_without_the_accelerometer_bias_the_offsets_are_open(recording):
    samples, theta = recording
    with pytest.raises(UnobservableParameters) as caught:
        calibrate_imu_dynamic(samples)
    assert {"accel_bias", "force_offset", "torque_offset"} <= set(caught.value.names)
    # a zero bias, asked for: the offsets absorb m R_SI b, exactly as the static model says
    absorbed = calibrate_imu_dynamic(samples, accel_bias=np.zeros(3), accel_scale=SCALE)
    expected = WRENCH_BIAS[:3] + theta[0] * IMU_ROTATION @ (BIAS / (1.0 + SCALE))
    np.testing.assert_allclose(absorbed.force_offset, expected, atol=0.05)


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


def test_jacobian_matches_finite_differences(rng):
    count = 40
    motion = ImuMotion(
        rng.normal(0.0, 5.0, (count, 6)),
        rng.normal(0.0, 5.0, (count, 3)),
        rng.normal(0.0, 2.0, (count, 3)),
        rng.normal(0.0, 10.0, (count, 3)),
    )
    problem = ImuDynamicProblem(
        motion, np.array([0.05] * 3 + [0.003] * 3), IMU_ROTATION, np.zeros(3), True, True
    )
    x = np.concatenate(
        [
            WRENCH_BIAS,
            [1.5, 0.009, -0.018, 0.108, 0.0137, 2e-4, 0.0129, 1e-4, 2e-3, 2.8e-3],
            [0.2, -0.1, 0.3],  # δ
            IMU_POSITION,
        ]
    )
    analytic = problem.jacobian(x).reshape(-1, len(x))
    numeric = np.empty_like(analytic)
    for i in range(len(x)):
        step = np.zeros(len(x))
        step[i] = 1e-6
        numeric[:, i] = ((problem.predict(x + step) - problem.predict(x - step)) / 2e-6).ravel()
    np.testing.assert_allclose(analytic, numeric, atol=1e-6 * np.abs(numeric).max())
