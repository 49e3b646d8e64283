"""``calibrate_on_robot`` with a sensor that has an IMU (issue 31): the session records the IMU's
columns beside the joints and calibrates the orientation and the IMU together, the mount checked.

The arm is :class:`FakeRobot` (it is at each pose as soon as it is sent there); the sensor reads
the tool of :mod:`record_fakes` (written from first principles there) at the sensor orientation
the bundled arm's kinematics give for the robot's joints, with an IMU turned by 90° about z and
an accelerometer bias. The truth is record_fakes' tool and IMU, not ftkin's output read back.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.calibration.fused_result import FusedCalibrationResult
from ftkin.io.csv_table import read_table
from ftkin.kinematics.arm import Arm
from ftkin.robot import Stillness, calibrate_on_robot

from .fakes import FakeRobot
from .record_fakes import ACCEL_BIAS, IMU_ROTATION, TOOL, Schedule, ScriptedSensor

STILL = Stillness(window=10, settle_time=0.001, poll_period=0.0, force_std=0.1, torque_std=0.01)


def _session(tmp_path, imu: bool):
    arm = Arm.default()
    robot = FakeRobot(nq=arm.nq)
    schedule = Schedule(1, 1.0, 1.0)  # only its clock: the robot says where the sensor is
    sensor = ScriptedSensor(
        lambda t: (arm.rotation_sensor_to_base(robot.q), np.zeros(3)), schedule, imu=imu, seed=3
    )
    samples_path = tmp_path / "samples.csv"
    result = calibrate_on_robot(
        robot,
        sensor,
        arm,
        n_poses=10,
        readings_per_pose=20,
        samples_path=samples_path,
        verify_poses=0,
        stillness=STILL,
        g=9.81,
        progress=False,
    )
    return result, read_table(samples_path).header


def test_the_imu_is_recorded_and_fitted_with_the_joints(tmp_path):
    result, header = _session(tmp_path, imu=True)
    assert header[-6:] == ["ax", "ay", "az", "wx", "wy", "wz"]
    assert isinstance(result, FusedCalibrationResult)
    # record_fakes' truth; noise 0.02 N over 10 poses × 20 readings
    assert result.tool_mass == pytest.approx(TOOL["mass"], rel=0.005)
    np.testing.assert_allclose(result.center_of_mass, TOOL["com"], atol=1e-3)
    np.testing.assert_allclose(result.force_offset, TOOL["bias"][:3], atol=0.05)
    turn = Rotation.from_matrix(result.imu_rotation.T @ IMU_ROTATION).magnitude()
    assert np.degrees(turn) < 0.5
    np.testing.assert_allclose(result.accel_bias, ACCEL_BIAS, atol=0.01)
    # the URDF's sensor frame is the sensor's: the mount check sees nothing beyond the noise
    assert result.mount_check is not None and not result.mount_check.significant
    assert result.kinematics is not None and result.kinematics.robot == "ftkin_c4"


def test_a_sensor_without_an_imu_records_the_wrench_alone(tmp_path):
    result, header = _session(tmp_path, imu=False)
    assert header[-2:] == ["pose", "t"]
    assert not isinstance(result, FusedCalibrationResult)
    assert result.tool_mass == pytest.approx(TOOL["mass"], rel=0.005)
