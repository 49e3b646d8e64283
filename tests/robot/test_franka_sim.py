"""End to end on franky-sim through franky, exactly as on a real FR3 (loopback only).

One simulated robot serves the module's tests in order: the session, the payload round trip,
hand-guiding, the loop's faults; the interrupted sessions and the killed server use their own.
The benchmark (benchmarks/bench_robot.py) runs the full-size versions against the targets;
these use fewer poses and shorter runs, and bounds that hold on a loaded CI machine.
"""

from __future__ import annotations

import os
import signal
import threading
import time

import numpy as np
import pytest

pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")

from ftkin.exceptions import RealtimeUnavailable, SessionInterrupted  # noqa: E402
from ftkin.io.payload_export import payload_in_flange  # noqa: E402
from ftkin.io.payload_inertia import controller_load  # noqa: E402
from ftkin.io.samples_csv import load_samples  # noqa: E402
from ftkin.kinematics.fr3 import fr3_arm  # noqa: E402
from ftkin.robot import (  # noqa: E402
    FrankaRobot,
    FrankaSim,
    Stillness,
    calibrate_on_robot,
    hand_guiding,
    run_admittance,
    wait_still,
)
from ftkin.robot.session import session_poses  # noqa: E402

HOME = np.array([0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785])
PLAN = {"joint_ranges": {"fr3_joint1": (-0.8, 0.8)}}
LOADED = {"state_timeout": 1.0}  # a loaded CI machine may pause the simulation for a while
STILL = Stillness(stale_after=1.0)
SCHEDULING_AT_IMPORT = (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority)


def connect(host: str, attempts: int = 3, **options) -> FrankaRobot:
    """A FrankaRobot, retried on a connection timeout: on a busy 2-core machine (load 6.9 was
    seen) libfranka's connection attempt can time out before franky-sim's server answers."""
    from ftkin.exceptions import RobotConnectionLost

    for attempt in range(attempts):
        try:
            return FrankaRobot(host, **options)
        except RobotConnectionLost:
            if attempt == attempts - 1:
                raise
            time.sleep(1.0)


def assert_whole_poses(ids, counts, expected_ids, readings_per_pose: int) -> None:
    """The samples file holds exactly ``expected_ids``, each with ``readings_per_pose`` readings.

    Pose ids and counts are whole numbers read back from a CSV: compared with an absolute
    tolerance of 0.5 (one id from the next), never with ``==`` on floats.
    """
    np.testing.assert_allclose(ids, expected_ids, rtol=0, atol=0.5)
    np.testing.assert_allclose(
        counts, np.full(len(expected_ids), readings_per_pose), rtol=0, atol=0.5
    )


@pytest.fixture(scope="module")
def arm():
    return fr3_arm()


@pytest.fixture(scope="module")
def sim():
    simulation = FrankaSim()
    try:
        simulation.start()
        yield simulation
    finally:
        simulation.close()


@pytest.fixture(scope="module")
def robot(sim):
    return connect(sim.hostname, realtime=False, speed=0.8, **LOADED)


@pytest.fixture(scope="module")
def session(sim, robot, arm, tmp_path_factory):
    folder = tmp_path_factory.mktemp("session")
    result = calibrate_on_robot(
        robot,
        sim.sensor,
        arm,
        n_poses=3,
        readings_per_pose=30,
        samples_path=folder / "samples.csv",
        output=folder / "calib.json",
        verify_poses=1,
        stillness=STILL,
        g=sim.truth.g,
        plan_options=PLAN,
    )
    return result, folder


def test_session_recovers_the_simulated_tool(sim, arm, session):
    result, folder = session
    truth = sim.truth
    np.testing.assert_allclose(result.tool_mass, truth.mass, rtol=0.01)
    np.testing.assert_allclose(result.center_of_mass, truth.center_of_mass, atol=0.002)
    np.testing.assert_allclose(result.force_offset, truth.bias[:3], atol=0.05)
    np.testing.assert_allclose(result.torque_offset, truth.bias[3:], atol=0.005)
    samples = load_samples(folder / "samples.csv", arm).samples
    ids, counts = np.unique(samples.pose_ids, return_counts=True)
    assert_whole_poses(ids, counts, [0, 1, 2], 30)
    assert (folder / "calib.json").is_file()


def test_payload_round_trip(sim, robot, arm, session):
    result, _ = session
    truth = sim.truth
    end_effector = robot.end_effector()
    sent = robot.set_payload(
        result, sensor_mass=truth.sensor_mass, sensor_com=truth.sensor_com_flange
    )
    mass, com, inertia = robot.payload()
    # read back (float32 on the wire) = measured − configured end effector + sensor body
    expected = controller_load(
        payload_in_flange(result, arm), end_effector, None
    )  # without the sensor body, then add it by hand: an independent combination
    expected_mass = expected.mass + truth.sensor_mass
    expected_com = (
        expected.mass * expected.center_of_mass + truth.sensor_mass * truth.sensor_com_flange
    ) / expected_mass
    np.testing.assert_allclose(mass, expected_mass, rtol=1e-6)
    np.testing.assert_allclose(com, expected_com, atol=1e-6)
    np.testing.assert_allclose(mass, sent.mass, rtol=1e-6)
    assert inertia.shape == (3, 3)
    # and against the simulation's truth: hand + fingers + tool − hand setting + sensor body
    np.testing.assert_allclose(mass, truth.mass - end_effector.mass + truth.sensor_mass, rtol=0.01)


def load_from_simulated_bodies(truth, end_effector) -> tuple[float, np.ndarray]:
    """What the controller must hold, from MuJoCo's own bodies in the flange ``fr3_link8``:
    everything from the sensor body down (sensor body, hand, fingers, tool) minus the end
    effector the robot reports as configured (libfranka m_ee, F_x_Cee). Nothing of ftkin's
    calibration, URDF or payload code is used.
    """
    masses = np.array([mass for mass, _ in truth.bodies_in_flange.values()])
    moments = np.array([mass * com for mass, com in truth.bodies_in_flange.values()])
    mass = masses.sum() - end_effector.mass
    return mass, (moments.sum(axis=0) - end_effector.mass * end_effector.center_of_mass) / mass


def test_the_load_sent_is_in_the_flange_frame_of_the_simulated_bodies(sim, robot, session):
    """The FR3 load (mass, centre of mass) in fr3_link8 within 1 mm of MuJoCo's bodies: the
    hand frame (turned −45° about z) taken as the flange put it about 11 mm off."""
    result, _ = session
    end_effector = robot.end_effector()
    robot.set_payload(
        result, sensor_mass=sim.truth.sensor_mass, sensor_com=sim.truth.sensor_com_flange
    )
    mass, com, _ = robot.payload()
    expected_mass, expected_com = load_from_simulated_bodies(sim.truth, end_effector)
    np.testing.assert_allclose(mass, expected_mass, rtol=0.01)
    assert np.linalg.norm(com - expected_com) < 1e-3, (com, expected_com)


def test_export_franka_load_is_in_the_flange_frame_of_the_simulated_bodies(
    sim, robot, session, tmp_path
):
    import yaml

    from ftkin.cli import main

    _, folder = session
    end_effector = robot.end_effector()
    out = tmp_path / "load.yaml"
    numbers = lambda mass, com: [str(value) for value in (mass, *com)]  # noqa: E731
    argv = ["export", str(folder / "calib.json"), "--format", "franka-load", "-o", str(out)]
    argv += ["--end-effector", *numbers(end_effector.mass, end_effector.center_of_mass)]
    argv += ["--sensor-body", *numbers(sim.truth.sensor_mass, sim.truth.sensor_com_flange)]
    assert main(argv) == 0
    written = yaml.safe_load(out.read_text())
    expected_mass, expected_com = load_from_simulated_bodies(sim.truth, end_effector)
    np.testing.assert_allclose(written["mass"], expected_mass, rtol=0.01)
    com = np.array(written["center_of_mass"])
    assert np.linalg.norm(com - expected_com) < 1e-3, (com, expected_com)


def test_cli_payload_sends_and_reads_back(session, capsys):
    from ftkin.cli import main

    _, folder = session
    with FrankaSim() as other:  # a robot takes one client: the module's robot holds the other sim
        argv = ["robot", "payload", str(folder / "calib.json"), "--franka", other.hostname]
        assert main([*argv, "--no-realtime", "--sensor-body", "0.25", "0", "0", "-0.01"]) == 0
        lines = capsys.readouterr().out.splitlines()
        sent, reported = (line.split(": ", 1)[1] for line in lines[:2])
        assert lines[0].startswith("sent:") and sent == reported  # to the printed digits
        assert main([*argv, "--no-realtime", "--end-effector", "5", "0", "0", "0"]) == 2
        assert "negative mass" in capsys.readouterr().err


def test_hand_guiding_follows_a_push_and_stops(sim, robot, arm, session):
    result, _ = session
    robot.move_to(HOME)
    wait_still(robot)
    controller = hand_guiding(arm, result)
    track = []
    end = sim.time + 0.2 + 1.0 + 0.8  # simulation time: a loaded machine slows the simulation

    def on_tick(now, q, dq):
        track.append((sim.time, *sim.hand_position(), dq.any()))
        return track[-1][0] > end

    sim.push([15.0, 0.0, 0.0], 1.0, delay=0.2)
    stats = run_admittance(
        robot, sim.sensor, controller, duration=30.0, stale_after=1.0, on_tick=on_tick
    )
    assert stats.stop_reason == "duration", stats.report()
    assert stats.rate_hz > 100.0
    track = np.array(track)
    moved = track[-1, 1:4] - track[0, 1:4]
    assert moved[0] > 0.025, moved  # along the push (the benchmark asks ≥ 4 cm unloaded)
    assert np.hypot(moved[1], moved[2]) < 0.3 * moved[0], moved
    last_command = np.flatnonzero(track[:, 4])[-1]
    assert last_command < len(track) - 1, "the command returns to exactly zero after release"
    after = track[last_command + 1 :, 1:4]
    assert np.linalg.norm(after[-1] - after[0]) < 0.001  # no creep once stopped


class _TimedReads:
    """The simulated sensor, each read logged as ``(start [s], end [s], stamp)`` (monotonic)."""

    def __init__(self, sensor):
        self.sensor, self.reads = sensor, []

    def read(self):
        start = time.monotonic()
        t, wrench = self.sensor.read()
        self.reads.append((start, time.monotonic(), t))
        return t, wrench

    def __getattr__(self, name):
        return getattr(self.sensor, name)


@pytest.mark.parametrize(("fault", "reason"), [("nan", "not_finite"), ("stale", "stale")])
def test_loop_stops_on_a_sensor_fault(sim, robot, arm, session, fault, reason):
    """The loop stops in the tick that shows the fault, by the loop's own ticks and reads (a
    busy machine runs ticks late; they must still be the right ticks)."""
    result, _ = session
    robot.move_to(HOME)
    controller = hand_guiding(arm, result)
    ticks, stops = [], []
    sensor = _TimedReads(sim.sensor)
    stale_after = 0.3  # [s] a loaded machine may pause the simulation for tens of ms

    def on_tick(now, q, dq):
        ticks.append(now)
        if len(ticks) == 25:
            sim.sensor.inject(fault)

    stop = robot.stop
    robot.stop = lambda: (stops.append(time.monotonic()), stop())
    try:
        stats = run_admittance(
            robot,
            sensor,
            controller,
            duration=30.0,
            stale_after=stale_after if fault == "stale" else 30.0,
            on_tick=on_tick,
        )
    finally:
        sim.sensor.inject(None)
        del robot.stop
    assert stats.stop_reason == reason and len(stops) == 1
    if fault == "nan":  # the next tick reads it and stops: nothing commanded after it
        assert stats.ticks == 25
        return
    # stale: the stamp stopped at the injection; the loop took it as new at the first read that
    # returned it (between that read's end and the next read's start) and stopped at the first
    # read more than stale_after later: not before, and no tick commanded after that
    assert stats.ticks >= 25
    frozen = sensor.reads[-1][2]
    first = next(k for k, read in enumerate(sensor.reads) if read[2] == frozen)
    assert stats.fault_time - sensor.reads[first][1] > stale_after  # not early
    used = sensor.reads[first + 1 : stats.ticks + 1]  # the reads of commanded ticks (+ warm-up)
    assert all(start - sensor.reads[first + 1][0] <= stale_after for start, _, _ in used)


class _Interrupting:
    """The robot, with ``action()`` run once at the start of its ``at_move``-th ``move_to``."""

    def __init__(self, robot, at_move, action):
        self.robot, self.at_move, self.action, self.moves = robot, at_move, action, 0

    def move_to(self, q, while_moving=None):
        self.moves += 1
        if self.moves == self.at_move:
            self.action()
        return self.robot.move_to(q, while_moving)

    def __getattr__(self, name):
        return getattr(self.robot, name)


def test_interrupted_sessions_keep_their_samples_and_resume(sim, robot, arm, tmp_path):
    """A NaN sensor stops the session at the second pose, Ctrl-C the resumed one at the third;
    each leaves whole poses, and the last resume finishes with no pose twice.
    """
    poses = session_poses(arm, 3, seed=3, readings_per_pose=20, plan_options=PLAN)
    path = tmp_path / "samples.csv"
    options = {
        "poses": poses,
        "readings_per_pose": 20,
        "samples_path": path,
        "verify_poses": 0,
        "stillness": STILL,
        "g": sim.truth.g,
    }
    assert threading.main_thread().ident == threading.get_ident()  # SIGINT lands here
    faults = [
        (False, lambda: sim.sensor.inject("nan")),  # while the arm moves to the second pose
        (True, lambda: os.kill(os.getpid(), signal.SIGINT)),  # Ctrl-C as it starts the third
    ]
    for done, (resume, action) in enumerate(faults, start=1):
        try:
            with pytest.raises(SessionInterrupted) as caught:
                calibrate_on_robot(
                    _Interrupting(robot, 2, action), sim.sensor, arm, resume=resume, **options
                )
        finally:
            sim.sensor.inject(None)
        assert caught.value.poses_recorded == done and caught.value.samples_path == path
        assert ("interrupted" in caught.value.reason) == resume
        recorded = load_samples(path, arm).samples  # intact: readable, whole poses only
        ids, counts = np.unique(recorded.pose_ids, return_counts=True)
        assert_whole_poses(ids, counts, list(range(done)), 20)
    result = calibrate_on_robot(robot, sim.sensor, arm, resume=True, **options)
    ids, counts = np.unique(load_samples(path, arm).samples.pose_ids, return_counts=True)
    assert_whole_poses(ids, counts, [0, 1, 2], 20)  # no pose twice
    np.testing.assert_allclose(result.tool_mass, sim.truth.mass, rtol=0.02)


def test_realtime_true_on_a_kernel_without_it_names_the_option(sim):
    if (
        open("/sys/kernel/realtime").read().strip() == "1"
        if os.path.exists("/sys/kernel/realtime")
        else False
    ):
        pytest.skip("this kernel has real-time scheduling")
    with pytest.raises(RealtimeUnavailable, match="realtime=False"):
        connect(sim.hostname, realtime=True)


def test_a_killed_server_stops_the_loop_cleanly(arm):
    from ftkin.calibration.model import SensorModel

    calibration = SensorModel.from_tool(1.96, [0.0, 0.0, 0.07], [0, 0, 0], [0, 0, 0])
    with FrankaSim() as other:
        robot = connect(other.hostname, realtime=False, state_timeout=0.2)
        ticks = []

        def on_tick(now, q, dq):
            ticks.append(now)
            if len(ticks) == 20:
                other.kill()

        stats = run_admittance(
            robot,
            other.sensor,
            hand_guiding(arm, calibration, force_deadband=50.0),
            duration=10.0,
            stale_after=5.0,
            on_tick=on_tick,
        )
    assert stats.stop_reason == "connection", stats.report()
    assert stats.ticks < 20 + 250  # noticed within the state timeout, not libfranka's seconds


def test_connecting_leaves_the_calling_threads_scheduling_alone(robot, sim):
    # libfranka raises the connecting thread to SCHED_FIFO 99 when it may (as root, even with
    # RealtimeConfig.Ignore); every process started afterwards (a browser, a simulator) would
    # inherit it and starve the machine. The robot fixture connected already.
    with pytest.raises(RealtimeUnavailable):
        connect(sim.hostname, realtime=True)
    assert (os.sched_getscheduler(0), os.sched_getparam(0).sched_priority) == SCHEDULING_AT_IMPORT


def test_a_pause_of_ours_is_not_a_lost_robot(sim, robot):
    """franky's state is the last motion's while the arm is idle: a program that does not poll
    for a while (a fit between the session and its verification) must not take the still clock
    for a dead robot; a robot that stops while polled still is (test_a_killed_server_...)."""
    limit = robot.state_timeout  # the module's robot: restored below
    robot.state_timeout = 0.2
    try:
        robot.move_to(HOME)
        time.sleep(0.6)  # three limits without a poll
        robot.joint_state()
        robot.move_to(HOME + np.array([0.0, 0.05, 0.0, 0.0, 0.0, 0.0, 0.0]))
    finally:
        robot.state_timeout = limit
