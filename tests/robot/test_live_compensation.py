"""compensated_stream without a network: fake readers and sensors, every fault it must raise."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ftkin.calibration import SensorModel
from ftkin.calibration.fit_registry import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.exceptions import InvalidInput, RobotConnectionLost, SensorError
from ftkin.kinematics.record import KinematicsRecord
from ftkin.kinematics.robots import load_robot
from ftkin.robot import compensated_stream
from ftkin.sim.sensor import SimulatedSensor

from .fakes import FakeSensor


class Reader:
    """Joint positions from a list; raises ``error`` once the list is used up."""

    def __init__(self, positions, error=None):
        self.positions, self.error, self.calls = list(positions), error, 0

    def joint_positions(self):
        self.calls += 1
        if self.calls > len(self.positions):
            raise self.error or IndexError("no more positions")
        return self.positions[self.calls - 1]


@pytest.fixture(scope="module")
def setup():
    rng = np.random.default_rng(4)
    arm = load_robot("ur5e")
    truth = SensorModel.from_tool(0.9, [0.0, 0.01, 0.05], [0.5, -0.3, 0.2], [0.01, 0.0, -0.02])
    q = arm.random_configurations(12, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 10)
    calibration = replace(calibrate(samples), kinematics=KinematicsRecord.from_arm(arm))
    return arm, truth, calibration


class ModelSensor:
    """Readings of the tool at the reader's next pose, each with a new stamp."""

    def __init__(self, arm, truth, positions):
        self.arm, self.truth, self.positions, self.count = arm, truth, positions, 0

    def read(self):
        q = self.positions[self.count]
        self.count += 1
        return float(self.count), self.truth.predict(self.arm.rotation_sensor_to_base(q))


def test_contact_of_a_tool_without_contact_is_zero_and_q_is_read_after_each_sample(setup, rng):
    arm, truth, calibration = setup
    positions = arm.random_configurations(20, rng)
    reader = Reader(positions)
    stream = compensated_stream(calibration, reader, ModelSensor(arm, truth, positions))
    for index, (stamp, q, contact) in zip(range(20), stream):
        assert stamp == index + 1 and reader.calls == index + 1
        np.testing.assert_allclose(q, positions[index], atol=0)
        np.testing.assert_allclose(contact, 0.0, atol=0.02)  # the calibration's own error


class PairedSensor:
    """A sensor that gives the joints of its own sample (as UR's built-in sensor does)."""

    def __init__(self, arm, truth, q):
        self.arm, self.truth, self.q, self.count = arm, truth, np.asarray(q, dtype=float), 0

    def read_with_joints(self):
        self.count += 1
        return (
            float(self.count),
            self.q,
            self.truth.predict(self.arm.rotation_sensor_to_base(self.q)),
        )

    def read(self):
        raise AssertionError("the stream must use read_with_joints")


def test_a_paired_sensor_gives_its_own_joints(setup):
    arm, truth, calibration = setup
    q = np.array([0.1, -1.2, 1.0, -0.5, 1.1, 0.2])
    reader = Reader([])
    stream = compensated_stream(calibration, reader, PairedSensor(arm, truth, q))
    for _, (_, q_read, contact) in zip(range(5), stream):
        np.testing.assert_allclose(q_read, q, atol=0)
        np.testing.assert_allclose(contact, 0.0, atol=0.02)  # the calibration's own error
    assert reader.calls == 0


@pytest.mark.parametrize(
    ("fault", "kind"), [("stale", "stale"), ("nan", "not_finite"), ("raise", "read_failed")]
)
def test_sensor_faults_raise_and_never_repeat_a_sample(setup, fault, kind):
    arm, _, calibration = setup
    q = np.zeros(6)
    sensor = FakeSensor(fault_at={4: fault})
    stamps = []
    with pytest.raises(SensorError) as error:
        for stamp, _, _ in compensated_stream(
            calibration, Reader([q] * 100), sensor, stale_after=0.02
        ):
            stamps.append(stamp)
    assert error.value.kind == kind
    assert stamps == sorted(set(stamps)) and len(stamps) == 3


def test_a_lost_robot_passes_through(setup):
    _, _, calibration = setup
    reader = Reader([np.zeros(6)] * 2, RobotConnectionLost("gone", "fake"))
    with pytest.raises(RobotConnectionLost, match="gone"):
        for _ in compensated_stream(calibration, reader, FakeSensor()):
            pass


def test_bad_inputs(setup):
    arm, _, calibration = setup
    with pytest.raises(InvalidInput, match="records no arm"):
        compensated_stream(replace(calibration, kinematics=None), Reader([]), FakeSensor())
    with pytest.raises(InvalidInput, match="joint_positions"):
        compensated_stream(calibration, object(), FakeSensor())
    with pytest.raises(InvalidInput, match="read"):
        compensated_stream(calibration, Reader([]), object())
    with pytest.raises(InvalidInput, match="poll_period"):
        compensated_stream(calibration, Reader([]), FakeSensor(), poll_period=-1.0)
    stream = compensated_stream(calibration, Reader([np.zeros(7)]), FakeSensor())
    with pytest.raises(InvalidInput, match=r"shape \(6,\)"):
        next(stream)
    with pytest.raises(InvalidInput, match="not the one the calibration was made with"):
        compensated_stream(calibration, Reader([]), FakeSensor(), arm=load_robot("ur10e"))
