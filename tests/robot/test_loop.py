"""run_admittance with a fake robot and sensor: pacing, stats and every stopping fault."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.kinematics.fr3 import fr3_arm
from ftkin.robot.loop import run_admittance
from ftkin.sim.sensor import paper_like_truth

from .fakes import ERRORS, FakeRobot, FakeSensor

RATE = 250.0


@pytest.fixture(scope="module")
def controller_factory():
    from ftkin.calibration.model import SensorModel
    from ftkin.robot.guiding import hand_guiding

    arm = fr3_arm()
    calibration = SensorModel.from_tool(1.0, [0, 0, 0.05], [0, 0, 0], [0, 0, 0])
    assert paper_like_truth() is not None
    return lambda: hand_guiding(arm, calibration)


def _home_robot(**options):
    robot = FakeRobot(**options)
    robot.q = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
    return robot


def test_runs_its_duration_and_reports_the_rate(controller_factory):
    robot = _home_robot()
    # the tool's weight as the sensor reads it at this pose: compensated to zero
    stats = run_admittance(robot, FakeSensor(), controller_factory(), duration=0.3, rate_hz=RATE)
    assert stats.completed and stats.stop_reason == "duration"
    assert stats.ticks == len(robot.commands) and stats.ticks > 30
    assert stats.rate_hz > 0.5 * RATE  # paced, not free-running
    assert stats.rate_hz < 1.2 * RATE
    assert stats.period_p50 <= stats.period_p99 <= stats.period_max
    assert robot.stops, "the robot is stopped at the end"


@pytest.mark.parametrize(
    ("fault", "reason"), [("nan", "not_finite"), ("stale", "stale"), ("raise", "read_failed")]
)
def test_sensor_faults_stop_the_robot_in_the_same_tick(controller_factory, fault, reason):
    robot = _home_robot()
    sensor = FakeSensor(fault_at={20: fault})
    stats = run_admittance(robot, sensor, controller_factory(), duration=5.0, stale_after=0.02)
    assert stats.stop_reason == reason and stats.faults[reason] == 1
    assert len(robot.stops) == 1
    if fault != "stale":  # NaN and a raising read: no command after the faulty reading
        assert len(robot.commands) == 18  # read 1 is the warm-up tick, 2..19 commanded
        assert robot.stops[0] - sensor.fault_time < 1.0 / RATE
    else:  # stale: stopped in the tick that sees the stamp too old
        assert robot.stops[0] - sensor.fault_time < 0.02 + 1.0 / RATE + 0.01


@pytest.mark.parametrize("kind", ["robot", "connection"])
def test_robot_errors_stop_cleanly(controller_factory, kind):
    robot = _home_robot(fail_at={10: ERRORS[kind]})
    stats = run_admittance(robot, FakeSensor(), controller_factory(), duration=5.0)
    assert stats.stop_reason == kind and stats.ticks == 10 and len(robot.stops) == 1


def test_ctrl_c_returns_stats(controller_factory):
    robot = _home_robot(fail_at={15: KeyboardInterrupt()})
    stats = run_admittance(robot, FakeSensor(), controller_factory(), duration=5.0)
    assert stats.stop_reason == "interrupt" and stats.ticks == 15 and len(robot.stops) == 1


def test_a_push_beyond_the_limit_is_a_safety_stop(controller_factory):
    robot = _home_robot()
    sensor = FakeSensor([0.0, 0.0, 100.0, 0, 0, 0])  # within the range, beyond the 60 N limit
    stats = run_admittance(robot, sensor, controller_factory(), duration=1.0)
    assert stats.stop_reason == "safety" and "exceeded the limit" in stats.message
    assert stats.ticks == 0 and len(robot.stops) == 1


def test_a_saturated_channel_holds_ticks_and_the_loop_goes_on(controller_factory):
    robot = _home_robot()
    sensor = FakeSensor([0.0, 0.0, 500.0, 0, 0, 0])  # beyond the 200 N range: held, not stopped
    stats = run_admittance(robot, sensor, controller_factory(), duration=0.2)
    assert stats.completed and stats.faults["saturated"] == stats.ticks
    assert all(not command.any() for _, command in robot.commands)


def test_ctrl_c_during_the_warm_up_tick_stops_the_loop_without_a_command(controller_factory):
    # Ctrl-C comes once: swallowed in the warm-up, the loop would command the arm until a second
    robot = _home_robot()

    class InterruptedOnce(FakeSensor):
        def read(self):
            self.calls = getattr(self, "calls", 0) + 1
            if self.calls == 1:
                raise KeyboardInterrupt
            return super().read()

    stats = run_admittance(robot, InterruptedOnce(), controller_factory(), duration=1.0)
    assert stats.stop_reason == "interrupt" and stats.faults["interrupt"] == 1
    assert robot.commands == [] and len(robot.stops) == 1
