"""``run_admittance(robot, AtiNetFT(...), controller)``: each injected box fault stops the arm.

The emulated Net F/T box streams what the sensor reads at the home pose (the controller's tool
compensated to a 2 N push along x, beyond hand-guiding's 1 N deadband: the arm moves) until a
fault is injected: a status word, a stalled ft_sequence, silence. The loop must stop with the
fault's kind as its reason, within one tick plus the adapter's limit, and command nothing after.
First against a fake robot (fast), then against franky-sim through franky, as on a real FR3.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from ftkin.calibration.model import SensorModel
from ftkin.kinematics.fr3 import fr3_arm
from ftkin.robot.guiding import hand_guiding
from ftkin.robot.loop import run_admittance

pytest.importorskip("pynetft", reason="pynetft is not installed (extra 'ati')")

from ftkin.sensors import AtiNetFT  # noqa: E402

from ..robot.fakes import FakeRobot  # noqa: E402

HOME = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
RATE = 250.0  # [Hz] the loop
LIMIT = 0.05  # [s] the adapter's silence_after (the loop's default stale limit is twice it)
FAULTS = [("status", {"status": 0x80020000}), ("stall", {"fault": "stall"})]
FAULTS += [("silence", {"fault": "silence"})]
TOOL = SensorModel.from_tool(1.0, [0.0, 0.0, 0.05], [1.0, -2.0, 0.5], [0.02, 0.01, -0.03])


@pytest.fixture(scope="module")
def arm():
    return fr3_arm()


def home_counts(arm) -> list[int]:
    """Counts (1e6 per N, N·m) of the tool at home plus a 2 N push along sensor x."""
    reading = TOOL.predict(arm.rotation_sensor_to_base(HOME)) + [2.0, 0, 0, 0, 0, 0]
    return [int(round(value * 1e6)) for value in reading]


def run_with_fault(robot, box, ports, arm, settings, at_tick=40):
    """Run the loop; inject ``settings`` into the box at tick ``at_tick``; the stats, when the
    fault was injected and the commands' times."""
    injected, commands = [], []

    def on_tick(now, q, dq):
        commands.append((now, dq.copy()))
        if len(commands) == at_tick:
            box.set(**settings)
            injected.append(time.monotonic())

    box.set(counts=home_counts(arm), dither=20)  # ±20 µN: a live reading is never bit-identical
    with AtiNetFT(box.host, silence_after=LIMIT, **ports) as sensor:
        stats = run_admittance(
            robot,
            sensor,
            hand_guiding(arm, TOOL),
            duration=5.0,
            rate_hz=RATE,
            on_tick=on_tick,
        )
    return stats, injected[0], commands


@pytest.mark.parametrize(("kind", "settings"), FAULTS)
def test_each_box_fault_stops_a_fake_robot_by_its_kind(box, ports, arm, kind, settings):
    robot = FakeRobot()
    robot.q = HOME.copy()
    stats, injected, commands = run_with_fault(robot, box, ports, arm, settings)
    assert stats.stop_reason == kind and stats.faults[kind] == 1, stats.report()
    assert len(robot.stops) == 1 and any(dq.any() for _, dq in commands)  # it moved, then stopped
    bound = (0.0 if kind == "status" else LIMIT) + 1.0 / RATE + 0.03  # + scheduling
    assert robot.stops[0] - injected < bound, (robot.stops[0] - injected, stats.message)
    assert all(t < stats.fault_time for t, _ in commands)  # nothing commanded once it showed


franky = pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")


@pytest.fixture(scope="module")
def franka():
    from ftkin.robot import FrankaRobot, FrankaSim

    with FrankaSim() as sim:
        sim.start()
        robot = FrankaRobot(sim.hostname, realtime=False, speed=0.8, state_timeout=1.0)
        robot.move_to(HOME)
        yield sim, robot


@pytest.mark.parametrize(("kind", "settings"), FAULTS)
def test_each_box_fault_holds_the_franky_sim_arm(box, ports, arm, franka, kind, settings):
    sim, robot = franka
    stops = []
    stop = robot.stop
    robot.stop = lambda: (stops.append(time.monotonic()), stop())
    try:
        stats, injected, commands = run_with_fault(robot, box, ports, arm, settings)
    finally:
        del robot.stop
    assert stats.stop_reason == kind, stats.report()
    assert len(stops) == 1 and any(dq.any() for _, dq in commands)
    bound = (0.0 if kind == "status" else LIMIT) + 1.0 / RATE + 0.05  # a loaded machine
    assert stops[0] - injected < bound, (stops[0] - injected, stats.message)
    moving = max(np.max(np.abs(dq)) for _, dq in commands)  # [rad/s] commanded while guided
    time.sleep(0.3)  # the arm holds where it stopped: it settles, as after any move, and
    held = robot.joint_positions()  # does not follow the last command
    assert np.max(np.abs(robot.joint_velocities())) < 0.25 * moving
    time.sleep(0.3)
    assert np.max(np.abs(robot.joint_positions() - held)) < 1e-3  # [rad]
    robot.move_to(HOME)
