"""The admittance tick and the robot loop compensating with the sensor's IMU (issue 31 #5).

The readings are written here from Newton's law, not with ftkin's model: a tool of mass ``m``
(COM ``c``, sensor frame) accelerating at ``a`` [m/s², base frame] without turning, gravity
``[0, 0, −g]`` in the base. The load on the sensor is the contact plus ``m (g_B − a)`` in sensor
axes (its torque ``c × ...``); the accelerometer reads the specific force ``a − g_B`` in its own
axes (``R_SIᵀ R_BSᵀ (a − g_B)``) plus its bias. The IMU tick must recover the contact; the FK
tick is off by the inertial force ``m a`` it cannot see.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin import Compensator
from ftkin.calibration.fused_result import FusedCalibrationResult
from ftkin.calibration.imu_result import ImuCalibrationResult
from ftkin.control.admittance import Admittance
from ftkin.control.bias_tracker import BiasTracker
from ftkin.control.imu_compensation import ImuCompensator
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.control.sensor_faults import SensorFault
from ftkin.exceptions import InvalidInput

G = 9.80665
MASS, COM = 1.5, np.array([0.01, -0.02, 0.08])  # [kg], [m] sensor frame
BIAS = np.array([2.0, -1.0, 0.5, 0.04, -0.02, 0.01])  # [N, N·m]
R_SI = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
ACCEL_BIAS = np.array([0.3, -0.2, 0.76])  # [m/s², IMU frame]
GRAVITY_B = np.array([0.0, 0.0, -G])
Q = np.array([0.3, -0.4, -0.8, 0.5, -1.0, 0.7])
K2 = np.array([2e-3] * 3 + [2e-2] * 3)


def _calibration(kind):
    return kind(
        force_offset=BIAS[:3],
        torque_offset=BIAS[3:],
        gravity_in_base=MASS * GRAVITY_B,
        center_of_mass=COM,
        imu_rotation=R_SI,
        accel_bias=ACCEL_BIAS,
    )


def _reading(arm, q, acceleration_in_base, contact):
    """``(raw wrench (6,), specific force (3,))`` by Newton's law (module docstring)."""
    rotation = arm.rotation_sensor_to_base(q)  # R_BS
    load = MASS * rotation.T @ (GRAVITY_B - np.asarray(acceleration_in_base))
    raw = BIAS + np.concatenate([load, np.cross(COM, load)]) + contact
    accel = R_SI.T @ rotation.T @ (np.asarray(acceleration_in_base) - GRAVITY_B) + ACCEL_BIAS
    return raw, accel


def _controller(arm, calibration, imu=True, fk=True, **kwargs):
    law = Admittance(k2=K2, frame="tool", max_linear_velocity=1.0, max_angular_velocity=5.0)
    return JointAdmittance(
        arm,
        law,
        Compensator(calibration, arm) if fk else None,
        imu=ImuCompensator(calibration) if imu else None,
        **kwargs,
    )


@pytest.mark.parametrize("kind", [FusedCalibrationResult, ImuCalibrationResult])
def test_the_imu_tick_removes_the_tools_acceleration_the_fk_tick_cannot_see(arm, rng, kind):
    calibration = _calibration(kind)
    with_imu = _controller(arm, calibration, fk=kind is FusedCalibrationResult)
    fk_only = _controller(arm, calibration, imu=False)
    for _ in range(5):
        q = arm.random_configurations(1, rng, margin=0.3)[0]
        acceleration = rng.uniform(-3.0, 3.0, 3)  # [m/s², base]
        contact = np.concatenate([rng.normal(0.0, 5.0, 3), rng.normal(0.0, 0.3, 3)])
        raw, accel = _reading(arm, q, acceleration, contact)
        with_imu.step(q, raw, 1e-3, specific_force=accel)
        np.testing.assert_allclose(with_imu.last_status.contact_wrench, contact, atol=1e-9)
        fk_only.step(q, raw, 1e-3)
        error = fk_only.last_status.contact_wrench[:3] - contact[:3]
        # the FK tick sees the inertial force -m a as a push (the stated physics, by hand)
        rotation = arm.rotation_sensor_to_base(q)
        np.testing.assert_allclose(error, -MASS * rotation.T @ acceleration, atol=1e-9)


def test_a_fused_controller_without_the_imu_that_tick_uses_fk(arm):
    controller = _controller(arm, _calibration(FusedCalibrationResult))
    raw, _ = _reading(arm, Q, np.zeros(3), np.zeros(6))
    controller.step(Q, raw, 1e-3)
    np.testing.assert_allclose(controller.last_status.contact_wrench, 0.0, atol=1e-9)


def test_imu_only_controller_needs_the_specific_force_and_holds_on_a_bad_one(arm):
    controller = _controller(arm, _calibration(ImuCalibrationResult), fk=False)
    raw, accel = _reading(arm, Q, np.zeros(3), np.zeros(6))
    with pytest.raises(InvalidInput, match="give specific_force"):
        controller.step(Q, raw, 1e-3)
    for bad in ([np.nan, 0.0, 9.8], [0.0, 0.0, 1e5]):
        dq = controller.step(Q, raw, 1e-3, specific_force=bad)
        assert not dq.any() and controller.last_status.fault is SensorFault.NOT_FINITE
    with pytest.raises(InvalidInput, match=r"shape \(3,\)"):
        controller.step(Q, raw, 1e-3, specific_force=[0.0, 9.8])
    controller.step(Q, raw, 1e-3, specific_force=accel)  # recovers: no latch on a bad sample


def test_imu_compensation_is_refused_where_it_cannot_go(arm):
    calibration = _calibration(FusedCalibrationResult)
    raw, accel = _reading(arm, Q, np.zeros(3), np.zeros(6))
    with pytest.raises(InvalidInput, match="needs an IMU compensator"):
        _controller(arm, calibration, imu=False).step(Q, raw, 1e-3, specific_force=accel)
    with pytest.raises(InvalidInput, match="ImuCompensator or None"):
        JointAdmittance(arm, Admittance(frame="tool"), imu=object())
    tracked = Compensator(calibration, arm, tracker=BiasTracker([0.002, 4e-5], [0.02, 0.001]))
    with pytest.raises(InvalidInput, match="without a bias tracker"):
        JointAdmittance(arm, Admittance(frame="tool"), tracked, imu=ImuCompensator(calibration))
    with pytest.raises(InvalidInput, match="calibration from the IMU"):
        ImuCompensator(_fk_calibration())


def test_the_robot_loop_passes_each_samples_specific_force(arm):
    from ftkin.robot.guiding import hand_guiding
    from ftkin.robot.loop import run_admittance
    from ftkin.sensors.sample import SensorSample
    from tests.robot.fakes import FakeRobot

    robot = FakeRobot(nq=arm.nq)
    robot.q = Q.copy()
    seen = []

    push = np.array([8.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    dither = np.random.default_rng(4)

    class ImuSensor:  # a sensor with an IMU, still, pushed by 8 N along the sensor's x
        def __init__(self):
            self.t = 0.0

        def read_sample(self):  # a dither of 1e-6 N: identical readings are a stuck sensor
            self.t += 0.001
            self.contact = push + 1e-6 * dither.standard_normal(6)
            raw, accel = _reading(arm, robot.q, np.zeros(3), self.contact)
            return SensorSample(self.t, raw, accel, np.zeros(3))

        def read(self):
            sample = self.read_sample()
            return sample.t, sample.wrench

    calibration = _calibration(FusedCalibrationResult)
    controller = hand_guiding(arm, calibration, imu=True)
    sensor = ImuSensor()
    stats = run_admittance(
        robot,
        sensor,
        controller,
        duration=0.1,
        rate_hz=200.0,
        on_tick=lambda now, q, dq: seen.append(
            (controller.last_status.contact_wrench, sensor.contact)
        ),
    )
    assert stats.completed and stats.ticks > 5 and not stats.faults
    for measured, applied in seen:
        np.testing.assert_allclose(measured, applied, atol=1e-9)

    class WrenchOnly:  # read() only: the loop cannot give the controller its specific force
        def read(self):
            return 0.0, np.zeros(6)

    with pytest.raises(InvalidInput, match="no read_sample"):
        run_admittance(robot, WrenchOnly(), controller, duration=0.1)

    class NoAccelerometer(ImuSensor):
        def read_sample(self):
            sample = super().read_sample()
            return SensorSample(sample.t, sample.wrench)

    stats = run_admittance(robot, NoAccelerometer(), controller, duration=0.1)
    assert stats.stop_reason == "imu" and "no specific force" in stats.message
    with pytest.raises(InvalidInput, match="calibration from the IMU"):
        hand_guiding(arm, _fk_calibration(), imu=True)


def _fk_calibration():
    from ftkin.calibration.result import CalibrationResult

    return CalibrationResult(
        force_offset=BIAS[:3],
        torque_offset=BIAS[3:],
        gravity_in_base=MASS * GRAVITY_B,
        center_of_mass=COM,
    )
