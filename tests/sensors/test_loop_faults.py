"""``run_admittance(robot, AtiNetFT(...), controller)``: each injected box fault stops the arm.

The emulated Net F/T box streams what the sensor reads at the home pose (the controller's tool
compensated to a 2 N push along x, beyond hand-guiding's 1 N deadband: the arm moves) until a
fault is injected: a status word, a stalled ft_sequence, silence. The loop must stop with the
fault's kind as its reason, in the tick whose read shows it, and command nothing after.
First against a fake robot (fast), then against franky-sim through franky, as on a real FR3.

The bound is stated in the loop's own ticks and the samples' own stamps, not in wall time (a
busy machine runs a tick late; it must still be the right tick): every read is logged with
what the robot was told, in order. The stopping tick is the first whose read raised; no tick
used a sample older than the adapter's limit; a latched fault (a status word) raised at the
first read after it latched."""

from __future__ import annotations

import time

import numpy as np
import pytest

from ftkin.calibration.model import SensorModel
from ftkin.exceptions import SensorError
from ftkin.kinematics.fr3 import fr3_arm
from ftkin.robot.guiding import hand_guiding
from ftkin.robot.loop import run_admittance

pytest.importorskip("pynetft", reason="pynetft is not installed (extra 'ati')")

from ftkin.sensors import AtiNetFT  # noqa: E402

from ..robot.fakes import FakeRobot  # noqa: E402

HOME = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
RATE = 250.0  # [Hz] the loop
LIMIT = 0.25  # [s] the adapter's silence_after: the emulated box is another process, which a
# busy machine pauses for tens of ms (the loop's default stale limit is twice it)
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


class LoggedSensor:
    """The adapter, each read logged in ``events`` as ``("read", start [s], stamp [s], latched)``
    or ``("raised", start [s], kind)``; ``latched``: a fault was latched before the read."""

    def __init__(self, sensor, events: list):
        self.sensor, self.events = sensor, events

    def read(self):
        start, latched = time.monotonic(), self.sensor.fault is not None
        try:
            t, wrench = self.sensor.read()
        except SensorError as error:
            self.events.append(("raised", start, error.kind))
            raise
        self.events.append(("read", start, t, latched))
        return t, wrench

    def __getattr__(self, name):
        return getattr(self.sensor, name)


def run_with_fault(robot, box, ports, arm, settings, at_tick=40):
    """Run the loop; inject ``settings`` into the box at tick ``at_tick``; the stats and the
    log of reads, commands (``("command", dq)``), the injection and the stop, in order."""
    events = []
    command, stop = robot.command_velocity, robot.stop
    robot.command_velocity = lambda dq: (events.append(("command", dq.copy())), command(dq))
    robot.stop = lambda: (events.append(("stop",)), stop())

    ticks = []

    def on_tick(now, q, dq):
        ticks.append(now)
        if len(ticks) == at_tick:
            box.set(**settings)
            events.append(("injected",))

    box.set(counts=home_counts(arm), dither=20)  # ±20 µN: a live reading is never bit-identical
    try:
        with AtiNetFT(box.host, silence_after=LIMIT, **ports) as sensor:
            stats = run_admittance(
                robot,
                LoggedSensor(sensor, events),
                hand_guiding(arm, TOOL),
                duration=30.0,
                rate_hz=RATE,
                on_tick=on_tick,
            )
    finally:
        del robot.command_velocity, robot.stop
    return stats, events


def check_stopped_in_its_tick(stats, events, kind) -> None:
    """The fault stopped the loop in the tick whose read showed it, after the injection; the
    arm moved before; no sample older than LIMIT was used; a latched fault raised at once."""
    assert stats.stop_reason == kind and stats.faults[kind] == 1, stats.report()
    names = [event[0] for event in events]
    assert names.count("injected") == 1 and names.count("raised") == 1, names[-10:]
    injected, raised = names.index("injected"), names.index("raised")
    assert injected < raised and names[raised + 1 :] == ["stop"]  # nothing commanded after
    moved = [event[1] for event in events[:injected] if event[0] == "command"]
    assert any(dq.any() for dq in moved)  # it moved, then stopped
    reads = [event for event in events if event[0] == "read"]
    assert all(start - t <= LIMIT for _, start, t, _ in reads)  # never a stale sample
    assert not any(latched for *_, latched in reads)  # a latched fault raises at the next read
    if kind == "silence":  # not early: the newest sample was older than the limit (a stall
        # and a status word are latched by pynetft from the records themselves)
        assert stats.fault_time - reads[-1][2] > LIMIT


@pytest.mark.parametrize(("kind", "settings"), FAULTS)
def test_each_box_fault_stops_a_fake_robot_by_its_kind(box, ports, arm, kind, settings):
    robot = FakeRobot()
    robot.q = HOME.copy()
    stats, events = run_with_fault(robot, box, ports, arm, settings)
    check_stopped_in_its_tick(stats, events, kind)
    assert len(robot.stops) == 1


franky = pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")


@pytest.fixture(scope="module")
def franka():
    from ftkin.robot import FrankaRobot, FrankaSim

    with FrankaSim() as sim:  # started once: the block starts it
        robot = FrankaRobot(sim.hostname, realtime=False, speed=0.8, state_timeout=1.0)
        robot.move_to(HOME)
        yield sim, robot


def test_the_simulation_is_started_once(franka):
    """One simulation process writes the state the test reads. A second ``start()`` (the fixture
    once called it inside ``with FrankaSim()``, which starts it) ran two physics processes on one
    shared block: ``sim.time`` read the two clocks in turn (seconds apart), so :func:`simulated`
    returned at once and the hold below was checked a few ms after the stop, while the arm still
    decelerated; and ``hand_position`` read two arms."""
    from ftkin.exceptions import InvalidInput

    sim, _ = franka
    with pytest.raises(InvalidInput, match="runs already.*start\\(\\) it once"):
        sim.start()
    times = []
    for _ in range(400):  # about 0.2 s of polls: one clock, never going back
        times.append(sim.time)
        time.sleep(0.0005)
    assert np.all(np.diff(times) >= 0.0) and times[-1] > times[0]


def simulated(sim, seconds: float) -> None:
    """Wait until the simulation has run ``seconds`` [s] of its own time (a busy machine runs it
    slower than the wall clock: the arm settles in simulated time)."""
    start, deadline = sim.time, time.monotonic() + 120.0
    while sim.time - start < seconds:
        if time.monotonic() > deadline:
            raise AssertionError(f"franky-sim ran {sim.time - start:.3f} s in 120 s")
        time.sleep(0.01)


@pytest.mark.parametrize(("kind", "settings"), FAULTS)
def test_each_box_fault_holds_the_franky_sim_arm(box, ports, arm, franka, kind, settings):
    sim, robot = franka
    stats, events = run_with_fault(robot, box, ports, arm, settings)
    check_stopped_in_its_tick(stats, events, kind)
    moving = max(np.max(np.abs(e[1])) for e in events if e[0] == "command")  # [rad/s] guided
    # the arm holds where it stopped (franky-sim: a PD on the stop position) and does not follow
    # the last command: 0.3 s of simulated time on, what is left is the hold settling under the
    # tool its gravity model does not know (a ~1e-3 rad sag, time constant ~0.1 s: about 0.0013
    # rad/s then, measured), not the commanded speed; an arm that kept the command would move
    # at it or faster (the sag adds to it while a velocity is commanded)
    simulated(sim, 0.3)
    held = robot.joint_positions()
    assert np.max(np.abs(robot.joint_velocities())) < 0.25 * moving
    simulated(sim, 0.3)
    assert np.max(np.abs(robot.joint_positions() - held)) < 1e-3  # [rad]
    robot.move_to(HOME)
