"""Stillness detection, sensor checks and the session's samples file, with fakes."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput, RobotError, SensorError
from ftkin.io.samples_csv import load_samples
from ftkin.kinematics.fr3 import fr3_arm
from ftkin.robot.samples_log import SamplesLog
from ftkin.robot.stillness import CheckedSensor, Stillness, record_still, stationary

from .fakes import FakeRobot, FakeSensor

FAST = Stillness(settle_time=0.005, window=8, poll_period=0.0, timeout=2.0)


def test_records_only_once_the_arm_is_still():
    robot = FakeRobot(moving_until=30)
    sensor = CheckedSensor(FakeSensor([1, 2, 3, 0.1, 0.2, 0.3], noise=0.01), 1.0)
    taken = record_still(robot, sensor, 10, FAST)
    assert taken.wrenches.shape == (10, 6) and taken.joint_positions.shape == (10, 7)
    # 30 moving polls, then the window of 8 fills: no reading from a moving arm
    assert robot.calls >= 30 + 8 + 10 - 1
    assert np.all(np.diff(taken.times) > 0)
    np.testing.assert_allclose(taken.wrenches.mean(axis=0), [1, 2, 3, 0.1, 0.2, 0.3], atol=0.02)


def test_a_noisy_sensor_never_settles_and_the_message_says_why():
    sensor = CheckedSensor(FakeSensor(noise=1.0), 1.0)
    with pytest.raises(RobotError, match="did not settle.*reading spread.*force_std"):
        record_still(FakeRobot(), sensor, 5, Stillness(window=8, timeout=0.05, poll_period=0.0))


@pytest.mark.parametrize(
    ("fault", "kind"), [("nan", "not_finite"), ("raise", "read_failed"), ("stale", "stale")]
)
def test_sensor_faults_are_sensor_errors(fault, kind):
    sensor = CheckedSensor(FakeSensor(fault_at={3: fault}), stale_after=0.01)
    with pytest.raises(SensorError) as caught:
        record_still(FakeRobot(), sensor, 1000, Stillness(poll_period=0.001, timeout=2.0))
    assert caught.value.kind == kind


def test_stationary_tests_spread_and_trend():
    rng = np.random.default_rng(1)
    still = rng.normal(0.0, 0.01, (40, 6))
    assert stationary(still, Stillness())
    ramp = still + np.linspace(0, 1.0, 40)[:, None]  # a settling reading: small spread per half
    assert not stationary(ramp, Stillness())


def test_samples_log_round_trip_resume_and_refusals(tmp_path):
    arm = fr3_arm()
    path = tmp_path / "session.csv"
    log = SamplesLog(path, arm.joint_names, comments=["a test"])
    rng = np.random.default_rng(2)
    q = rng.uniform(-0.5, 0.5, (3, 7)) + [0, 0, 0, -1.5, 0, 1.5, 0]
    for pose in range(3):
        rows = np.repeat(q[pose][None], 4, axis=0)
        log.append_pose(pose, rows, rng.normal(size=(4, 6)), np.arange(4) + 10.0 * pose)
    loaded = load_samples(path, arm)
    assert len(loaded.samples.wrenches) == 12
    assert sorted(set(loaded.samples.pose_ids.tolist())) == [0, 1, 2]
    with pytest.raises(InvalidInput, match="already exists"):
        SamplesLog(path, arm.joint_names)
    resumed = SamplesLog(path, arm.joint_names, resume=True)
    assert sorted(resumed.recorded_poses()) == [0, 1, 2]
    np.testing.assert_allclose(resumed.recorded_poses()[1], q[1], rtol=1e-15)
    with pytest.raises(InvalidInput, match="already recorded"):
        resumed.append_pose(1, q[1][None], np.zeros((1, 6)), [0.0])
    with open(path, "a") as stream:
        stream.write("0.1,0.2")  # a crash in the middle of a line
    with pytest.raises(InvalidInput, match="incomplete"):
        SamplesLog(path, arm.joint_names, resume=True)
