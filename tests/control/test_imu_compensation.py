"""Compensation from the sensor's IMU: the formula against MuJoCo's inverse dynamics, the fast
tick paths against the formula, the stream against the offline recording, and bad inputs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin import SensorModel
from ftkin.calibration.imu_result import ImuCalibrationResult
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import body_from_parameters
from ftkin.control.imu_compensation import ImuCompensator
from ftkin.exceptions import InvalidInput

IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
IMU_POSITION = np.array([0.021, -0.012, 0.027])


def calibration(theta, bias=None, accel_bias=(0.0, 0.0, 0.0), scale=(0.0, 0.0, 0.0)):
    bias = np.zeros(6) if bias is None else bias
    mass, com, inertia = body_from_parameters(theta)
    return ImuCalibrationResult(
        force_offset=bias[:3],
        torque_offset=bias[3:],
        gravity_in_base=[0.0, 0.0, -mass * 9.80665],
        center_of_mass=com,
        inertia_about_com_in_sensor=inertia,
        inertial_parameters=theta,
        imu_rotation=IMU_ROTATION,
        accel_bias=accel_bias,
        accel_scale=scale,
        imu_position=IMU_POSITION,
        imu_position_source="given",
    )


@pytest.fixture(scope="module")
def mujoco_motion():
    """A fast motion of the bundled arm in MuJoCo: wrench, accelerometer, gyro and the IMU's
    angular acceleration (MuJoCo's own ``mj_objectAcceleration``), all ideal."""
    mujoco = pytest.importorskip("mujoco")
    from ftkin import Arm
    from ftkin.sim.mujoco.imu_recording import MujocoImuRecorder
    from ftkin.sim.mujoco.tool_inertia import ToolInertia

    arm = Arm.default()
    turn = Rotation.from_euler("xyz", [0.4, -0.3, 0.2]).as_matrix()
    tool = ToolInertia(
        1.7, [0.006, -0.012, 0.072], turn @ np.diag([0.006, 0.0052, 0.0021]) @ turn.T
    )
    recorder = MujocoImuRecorder(
        imu_rotation=IMU_ROTATION,
        imu_position=IMU_POSITION,
        joint_names=arm.joint_names,
        tool=tool,
    )
    times = np.arange(0.0, 2.0, 0.002)
    phase = 2 * np.pi * 0.7 * times[:, None] + np.arange(arm.nq)
    amplitude = np.array([0.8, 0.5, 0.6, 1.2, 1.0, 1.5])
    q, dq = amplitude * np.sin(phase), amplitude * 2 * np.pi * 0.7 * np.cos(phase)
    ddq = -amplitude * (2 * np.pi * 0.7) ** 2 * np.sin(phase)
    wrench, accel, gyro = recorder.readings(q, dq, ddq)
    site = recorder.model.site("ftkin_imu_site").id
    rates = np.empty((len(q), 3))
    out = np.empty(6)
    for i in range(len(q)):  # angular acceleration of the IMU site, in its own axes
        recorder.data.qpos[recorder._qpos] = q[i]
        recorder.data.qvel[recorder._dof] = dq[i]
        recorder.data.qacc[recorder._dof] = ddq[i]
        mujoco.mj_inverse(recorder.model, recorder.data)
        mujoco.mj_objectAcceleration(
            recorder.model, recorder.data, mujoco.mjtObj.mjOBJ_SITE, site, out, 1
        )
        rates[i] = out[:3]
    return times, wrench, accel, gyro, rates, recorder.true_parameters()


def test_the_formula_removes_mujocos_wrench(mujoco_motion):
    """With the true tool, IMU rotation and position, the IMU formula explains MuJoCo's wrench
    during a fast motion (peak 5 rad/s): the contact is zero."""
    _, wrench, accel, gyro, rates, theta = mujoco_motion
    assert np.abs(gyro).max() > 3.0
    compensator = ImuCompensator(calibration(theta))
    contact = compensator.compensate_batch(wrench, accel, gyro, rates)
    np.testing.assert_allclose(contact, 0.0, atol=1e-9)
    # each term matters on this motion (α up to ~100 rad/s²): the IMU's 3 cm lever arm alone, and
    # the tool's rotation (α × c, ω × (ω × c) and the inertia), leave newtons
    no_lever = ImuCompensator(calibration(theta), imu_position=np.zeros(3))
    lever_error = np.abs(no_lever.compensate_batch(wrench, accel, gyro, rates)[:, :3]).max()
    rotation_error = np.abs(compensator.compensate_batch(wrench, accel)[:, :3]).max()
    assert lever_error > 1.0 and rotation_error > 1.0


def test_fast_paths_match_the_formula(rng):
    theta = np.array([1.7, 0.01, -0.02, 0.12, 0.02, 1e-4, 0.018, -2e-4, 3e-4, 0.004])
    compensator = ImuCompensator(
        calibration(
            theta,
            bias=rng.normal(size=6),
            accel_bias=np.array([0.7, -0.3, 0.2]),
            scale=np.array([0.005, -0.003, 0.002]),
        )
    )
    for _ in range(50):
        raw, accel = rng.normal(0, 10, 6), rng.normal(0, 10, 3)
        gyro, rate = rng.normal(0, 2, 3), rng.normal(0, 10, 3)
        formula = compensator.compensate_batch(raw[None], accel[None], gyro[None], rate[None])[0]
        np.testing.assert_allclose(
            compensator.compensate_moving(raw, accel, gyro, rate), formula, rtol=1e-12, atol=1e-12
        )
        at_rest = compensator.compensate_batch(raw[None], accel[None])[0]
        np.testing.assert_allclose(
            compensator.compensate(raw, accel), at_rest, rtol=1e-12, atol=1e-12
        )
        # lists and other dtypes take the checked path to the same numbers
        np.testing.assert_allclose(
            compensator.compensate_moving(raw.tolist(), accel.astype(np.float32), gyro, rate),
            compensator.compensate_moving(raw, accel.astype(np.float32).astype(float), gyro, rate),
            rtol=1e-12,
        )


def test_stream_matches_the_recording(mujoco_motion):
    """The causal stream's output for a sample equals the zero-phase recording's (the causal
    Savitzky–Golay estimate at the window's centre is the offline one), delayed."""
    times, wrench, accel, gyro, _, theta = mujoco_motion
    compensator = ImuCompensator(calibration(theta))
    samples = ImuSamples(accel, wrench, angular_velocity=gyro, times=times)
    offline = compensator.compensate_recording(samples, window=21)
    delay = compensator.start_stream(0.002, window=21)
    assert delay == pytest.approx(0.02)
    online = [compensator.compensate_stream(w, a, g) for w, a, g in zip(wrench, accel, gyro)]
    assert all(value is None for value in online[:20])
    lag = 10  # (window − 1) / 2 samples
    stacked = np.array(online[20:])
    np.testing.assert_allclose(stacked, offline[lag:-lag], atol=1e-9)
    assert np.abs(offline[lag:-lag]).max() < 0.05  # the filtered α explains the motion


def test_bad_inputs():
    theta = np.array([1.0, 0.0, 0.0, 0.05, 0.01, 0.0, 0.01, 0.0, 0.0, 0.01])
    compensator = ImuCompensator(calibration(theta))
    raw, accel = np.zeros(6), np.array([0.0, 0.0, 9.8])
    with pytest.raises(InvalidInput, match="finite"):
        compensator.compensate(raw, [np.nan, 0.0, 9.8])
    with pytest.raises(InvalidInput, match="shape"):
        compensator.compensate(raw, [0.0, 9.8])
    with pytest.raises(InvalidInput, match="unit mistake"):
        compensator.compensate(raw, [0.0, 0.0, 1e5])
    with pytest.raises(InvalidInput, match="raw_wrench"):
        compensator.compensate(np.full(6, 2e6), accel)
    with pytest.raises(InvalidInput, match="shape"):
        compensator.compensate_moving(raw, accel, np.zeros((3, 1)), np.zeros(3))
    with pytest.raises(InvalidInput, match="finite"):
        compensator.compensate_moving(raw, accel, np.array([0.0, np.inf, 0.0]), np.zeros(3))
    with pytest.raises(InvalidInput, match="start_stream"):
        compensator.compensate_stream(raw, accel, np.zeros(3))
    with pytest.raises(InvalidInput, match="both"):
        compensator.compensate_batch(raw[None], accel[None], np.zeros((1, 3)))
    with pytest.raises(InvalidInput, match="Compensator"):
        ImuCompensator(SensorModel([0, 0, 0], [0, 0, 0], [0, 0, -9.8], [0, 0, 0.05]))
    compensator.set_bias(np.ones(6))
    np.testing.assert_allclose(compensator.bias, np.ones(6))
    np.testing.assert_allclose(
        compensator.compensate(raw, accel), compensator.compensate_batch(raw[None], accel[None])[0]
    )
