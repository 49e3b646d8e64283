"""``ftkin record``: calibration data from an arm ftkin does not drive.

The arm is moved by the test, never by ftkin: a scripted arm and sensor on a schedule driven by
the sensor's reads (:mod:`tests.robot.record_fakes`, readings written from first principles: a
busy machine sees the same readings as an idle one), and franky-sim's FR3
moved through planned poses by a thread of the test while the recorder reads the same robot
(franky-sim serves one client at a time: a second ``franky.Robot`` blocks). The recorder finds
the still phases itself; the tolerances on franky-sim are those of ``robot calibrate``'s
(tests/robot/test_franka_sim.py).
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.exceptions import InvalidInput, InvalidSamples, RecordingInterrupted
from ftkin.io.csv_table import read_table
from ftkin.io.samples_csv import load_samples
from ftkin.kinematics.fr3 import fr3_arm
from ftkin.robot.recorder import record_poses
from ftkin.robot.stillness import Stillness
from ftkin.robot.stream_log import log_stream

from .record_fakes import (
    ACCEL_BIAS,
    IMU_ROTATION,
    RATE,
    TOOL,
    Schedule,
    ScriptedArm,
    ScriptedSensor,
    joint_path,
    rotation_path,
    spread_rotations,
)

ROOT = Path(__file__).resolve().parents[2]
FTKIN = [sys.executable, "-m", "ftkin.cli"]
QUICK = Stillness(settle_time=0.05, window=10, stale_after=0.5)
"""Stillness for the scripted arm (1 kHz readings, poses held 0.3 s: a pose needs at most 0.05 s
of wall clock, hence at most 50 reads as each poll sleeps 1 ms, plus the window and the readings,
well within the 300 reads of a hold however busy the machine)."""
HOLD, MOVE = 0.3, 0.15
"""The scripted arm's schedule [s]: each pose held, then the move to the next."""
PLAN = {"joint_ranges": {"fr3_joint1": (-0.8, 0.8)}}


def whole_poses(path, expected_ids, readings):
    """The file's pose ids are ``expected_ids``, each with ``readings`` rows (ids and counts are
    whole numbers read from a CSV: compared within 0.5)."""
    table = read_table(path)
    ids = table.floats(["pose"])[:, 0]
    unique, counts = np.unique(np.round(ids), return_counts=True)
    np.testing.assert_allclose(unique, expected_ids, rtol=0, atol=0.5)
    np.testing.assert_allclose(counts, np.full(len(expected_ids), readings), rtol=0, atol=0.5)
    return table


def poses_in(path) -> int:
    """Distinct poses in a samples file being written (complete lines only; 0 before any)."""
    if not path.exists():
        return 0
    text = path.read_text()
    lines = [line for line in text[: text.rfind("\n") + 1].splitlines() if line[:1] != "#"]
    if len(lines) < 2:
        return 0
    column = lines[0].split(",").index("pose")
    return len({line.split(",")[column] for line in lines[1:]})


def joint_poses(count, seed=0):
    from ftkin.robot.session import session_poses

    return session_poses(fr3_arm(), count, seed=seed, readings_per_pose=20, plan_options=PLAN)


def scripted_joints(poses, hold=HOLD, move=MOVE, order=None, lost_after=None):
    arm = fr3_arm()
    schedule = Schedule(len(poses), hold, move, order)
    joints = ScriptedArm(poses, schedule, lost_after)
    return arm, joints, schedule


# ---------------------------------------------------------------------- the scripted arm
def test_records_each_still_pose_and_calibrates_the_known_tool(tmp_path):
    poses = joint_poses(5)
    arm, joints, schedule = scripted_joints(poses)
    sensor = ScriptedSensor(joint_path(arm, joints), schedule, seed=1)
    events = []
    recording = record_poses(
        sensor,
        joints,
        arm,
        samples_path=tmp_path / "s.csv",
        n_poses=5,
        readings_per_pose=20,
        stillness=QUICK,
        g=9.81,
        on_event=events.append,
    )
    said = [event.message for event in events if event.kind == "recorded"]
    assert said == [f"pose {k} of 5 recorded: move on" for k in range(1, 5)] + [
        "pose 5 of 5 recorded"
    ]
    assert not recording.interrupted and recording.poses_recorded == 5
    table = whole_poses(tmp_path / "s.csv", range(5), 20)
    assert table.header == [*arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz", "pose", "t"]
    # each pose's joints are the scripted pose (still: no reading while moving)
    q = table.floats(arm.joint_names)
    ids = np.round(table.floats(["pose"])[:, 0]).astype(int)
    for pose in range(5):
        np.testing.assert_allclose(q[ids == pose], poses[pose][None].repeat(20, 0), atol=1e-12)
    result = recording.calibration
    np.testing.assert_allclose(result.tool_mass, TOOL["mass"], rtol=0.002)
    np.testing.assert_allclose(result.center_of_mass, TOOL["com"], atol=2e-4)
    np.testing.assert_allclose(result.force_offset, TOOL["bias"][:3], atol=0.01)
    np.testing.assert_allclose(result.torque_offset, TOOL["bias"][3:], atol=5e-4)
    coverage = [event for event in events if event.kind == "coverage"]
    assert len(coverage) == 5 and not coverage[1].coverage.determined
    assert coverage[-1].coverage.determined and "weakest:" in coverage[-1].message


def test_a_pose_already_recorded_is_refused_and_the_arm_moves_on(tmp_path):
    poses = joint_poses(4, seed=2)
    # the user goes back to the first pose after the second, then on to the others
    arm, joints, schedule = scripted_joints(poses, order=[0, 1, 0, 2, 3])
    sensor = ScriptedSensor(joint_path(arm, joints), schedule, seed=2)
    events = []
    recording = record_poses(
        sensor,
        joints,
        arm,
        samples_path=tmp_path / "s.csv",
        n_poses=4,
        readings_per_pose=20,
        stillness=QUICK,
        on_event=events.append,
    )
    refused = [event for event in events if event.kind == "same_pose"]
    assert len(refused) == 1 and refused[0].pose == 0
    assert refused[0].message.startswith("same pose as pose 0 (gravity 0.0° from it")
    assert refused[0].message.endswith("move to another")
    assert recording.poses_recorded == 4
    q = read_table(tmp_path / "s.csv").floats(arm.joint_names)
    recorded = np.unique(np.round(q, 9), axis=0)
    assert len(recorded) == 4  # the second visit of pose 0 is not in the file


def test_resume_continues_the_file_and_refuses_another_recordings(tmp_path):
    poses = joint_poses(5, seed=4)
    path = tmp_path / "s.csv"
    arm, joints, schedule = scripted_joints(poses[:3])
    first = record_poses(
        ScriptedSensor(joint_path(arm, joints), schedule),
        joints,
        arm,
        samples_path=path,
        n_poses=3,
        readings_per_pose=15,
        stillness=QUICK,
    )
    assert first.poses_recorded == 3
    with pytest.raises(InvalidInput, match="already exists.*resume"):
        record_poses(ScriptedSensor(joint_path(arm, joints), schedule), joints, arm,
                     samples_path=path, n_poses=5, stillness=QUICK)  # fmt: skip
    # resumed where the first ended: pose 2 again (refused), then the two new ones
    arm, joints, schedule = scripted_joints(poses, order=[2, 3, 4])
    events = []
    second = record_poses(
        ScriptedSensor(joint_path(arm, joints), schedule, seed=5),
        joints,
        arm,
        samples_path=path,
        n_poses=5,
        readings_per_pose=15,
        resume=True,
        stillness=QUICK,
        on_event=events.append,
    )
    assert events[0].message.startswith("resuming") and "3 recorded" in events[0].message
    assert [e.pose for e in events if e.kind == "same_pose"] == [2]
    assert second.poses_recorded == 5
    whole_poses(path, range(5), 15)
    np.testing.assert_allclose(second.calibration.tool_mass, TOOL["mass"], rtol=0.005)
    # a file of another arm (the IMU columns, no joints) is not continued
    imu = tmp_path / "imu.csv"
    imu.write_text("fx,fy,fz,mx,my,mz,pose,t,ax,ay,az,wx,wy,wz\n" + ",".join(["0"] * 14) + "\n")
    with pytest.raises(InvalidSamples, match="not this session's"):
        record_poses(ScriptedSensor(joint_path(arm, joints), schedule), joints, arm,
                     samples_path=imu, n_poses=5, resume=True, stillness=QUICK)  # fmt: skip


@pytest.mark.parametrize("what", ["sensor", "joints"])
def test_a_fault_stops_the_recording_with_whole_poses(tmp_path, what):
    poses = joint_poses(4, seed=6)
    # the fault comes while moving from the second pose to the third
    lost = (HOLD + MOVE) + HOLD + MOVE / 2  # pose 1 held from HOLD + MOVE, then the move
    arm, joints, schedule = scripted_joints(poses, lost_after=lost if what == "joints" else None)
    sensor = ScriptedSensor(
        joint_path(arm, joints), schedule, fault_after=lost if what == "sensor" else None
    )
    with pytest.raises(RecordingInterrupted) as caught:
        record_poses(
            sensor,
            joints,
            arm,
            samples_path=tmp_path / "s.csv",
            n_poses=4,
            readings_per_pose=20,
            stillness=QUICK,
        )
    # at once, not after a timeout: the poll that met the fault was the last (the clock is the
    # samples read, one per poll: the first sample after ``lost`` is the last one read)
    assert lost < schedule.elapsed() <= lost + 1.0 / RATE + 1e-12
    error = caught.value
    assert error.poses_recorded == 2 and error.poses_total == 4
    assert ("read failed" in error.reason or "read_failed" in error.reason) == (what == "sensor")
    assert ("no state" in error.reason) == (what == "joints")
    assert "resume" in str(error)
    whole_poses(tmp_path / "s.csv", [0, 1], 20)


def test_without_joints_it_records_the_imu_and_calibrates_from_it(tmp_path):
    rotations = spread_rotations(8, seed=3)
    schedule = Schedule(8, HOLD, MOVE)
    sensor = ScriptedSensor(rotation_path(rotations, schedule), schedule, imu=True, seed=3)
    events = []
    recording = record_poses(
        sensor,
        None,
        samples_path=tmp_path / "imu.csv",
        n_poses=8,
        readings_per_pose=30,
        stillness=QUICK,
        g=9.81,
        on_event=events.append,
    )
    table = whole_poses(tmp_path / "imu.csv", range(8), 30)
    assert table.header == [*"fx fy fz mx my mz pose t ax ay az wx wy wz".split()]
    # the recorded accelerometer is the scripted specific force at each pose (bias included)
    accel = table.floats(["ax", "ay", "az"])
    ids = np.round(table.floats(["pose"])[:, 0]).astype(int)
    for pose, rotation in enumerate(rotations):
        expected = IMU_ROTATION.T @ rotation.T @ [0.0, 0.0, 9.81] + ACCEL_BIAS
        np.testing.assert_allclose(accel[ids == pose].mean(axis=0), expected, atol=0.01)
    result = recording.calibration
    np.testing.assert_allclose(result.tool_mass, TOOL["mass"], rtol=0.005)
    np.testing.assert_allclose(result.center_of_mass, TOOL["com"], atol=1e-3)
    np.testing.assert_allclose(result.force_offset, TOOL["bias"][:3], atol=0.05)
    np.testing.assert_allclose(result.torque_offset, TOOL["bias"][3:], atol=5e-3)
    assert all("IMU frame" in e.message for e in events if e.kind == "coverage")


def test_without_joints_a_sensor_without_an_imu_is_refused(tmp_path):
    schedule = Schedule(3, HOLD, MOVE)
    sensor = ScriptedSensor(rotation_path(spread_rotations(3), schedule), schedule)
    with pytest.raises(InvalidInput, match="needs a sensor with an IMU.*--raw"):
        record_poses(sensor, None, samples_path=tmp_path / "s.csv", n_poses=3)
    assert not (tmp_path / "s.csv").exists()


# ---------------------------------------------------------------------- the raw stream
def test_raw_log_writes_every_sample_with_its_imu_and_temperature(tmp_path):
    schedule = Schedule(2, 0.3, 0.2)
    sensor = ScriptedSensor(rotation_path(spread_rotations(2), schedule), schedule, imu=True)
    log = log_stream(sensor, tmp_path / "stream.csv", duration=0.6, flush_period=0.1)
    table = read_table(tmp_path / "stream.csv")
    assert table.header == [*"t fx fy fz mx my mz ax ay az wx wy wz temperature".split()]
    values = table.floats(table.header)
    assert log.rows == len(values) and log.stop_reason == "duration"
    # every sample the sensor produced while logging, in order, each once
    produced = {sample.t: sample for sample in sensor.samples}
    during = [t for t in produced if values[0, 0] <= t <= values[-1, 0]]
    np.testing.assert_allclose(values[:, 0], sorted(during), rtol=1e-15)
    assert len(values) > 100 and np.all(np.diff(values[:, 0]) > 0)
    for row in values[:: max(1, len(values) // 50)]:
        sample = produced[row[0]]
        expected = [*sample.wrench, *sample.specific_force, *sample.angular_velocity]
        np.testing.assert_allclose(row[1:-1], expected, rtol=1e-15)
        np.testing.assert_allclose(row[-1], sample.temperature, rtol=1e-15)
    with pytest.raises(InvalidInput, match="already exists"):
        log_stream(sensor, tmp_path / "stream.csv", duration=0.1)


class PushedSensor:
    """A sensor whose samples come at their own rate (a thread, as ftkin's adapters), numbered
    in fx, with a temperature and no IMU."""

    def __new__(cls, rate: float):
        from ftkin.sensors.sample import SensorSample
        from ftkin.sensors.stream import StreamingSensor

        class Pushed(StreamingSensor):
            def __init__(self):
                super().__init__("a pushed test stream", silence_after=1.0, connect_timeout=2.0)
                self.stop = threading.Event()
                self._start()

            def _stream(self):
                count = 0
                while not self.stop.is_set():
                    count += 1
                    wrench = [float(count), 0.0, 0.0, 0.0, 0.0, 0.0]
                    self._deliver(SensorSample(time.monotonic(), wrench, temperature=31.5))
                    time.sleep(1.0 / rate)

            def _stop_stream(self):
                self.stop.set()

        return Pushed()


def test_raw_log_counts_the_samples_its_polling_missed(tmp_path):
    with PushedSensor(400.0) as sensor:
        log = log_stream(sensor, tmp_path / "stream.csv", duration=0.5, poll_period=0.004)
    table = read_table(tmp_path / "stream.csv")
    assert table.header == [*"t fx fy fz mx my mz temperature".split()]
    numbers = table.floats(["fx"])[:, 0]
    gaps = numbers[-1] - numbers[0] + 1 - len(numbers)  # the sequence numbers not logged
    assert log.rows == len(numbers) > 50 and np.all(np.diff(numbers) >= 1)
    assert gaps > 0  # polled every 4 ms, the stream every 2.5 ms: some are missed, and counted
    assert abs(log.missed - gaps) <= 1  # within a sample that came between the last two calls
    np.testing.assert_allclose(table.floats(["temperature"])[:, 0], 31.5, rtol=1e-15)
    assert "missed by the polling" in log.report()


def test_raw_log_stops_on_a_fault_keeping_the_rows_and_cli_exits_2(tmp_path, capsys):
    schedule = Schedule(2, 0.3, 0.2)
    sensor = ScriptedSensor(rotation_path(spread_rotations(2), schedule), schedule, fault_after=0.3)
    log = log_stream(sensor, tmp_path / "stream.csv", flush_period=0.05)
    assert log.stop_reason == "fault" and log.fault.kind == "read_failed"
    # every sample read before the fault is in the file, however few a busy machine allowed
    stamps = read_table(tmp_path / "stream.csv").floats(["t"])[:, 0]
    assert log.rows == len(stamps) == len(sensor.samples) > 0
    np.testing.assert_allclose(stamps, [sample.t for sample in sensor.samples], atol=5e-4)
    argv = ["record", "--raw", "--sensor", "tests.robot.record_fakes:scripted_imu"]
    assert main([*argv, "--sensor-option", "fault_after=0.2", "-o", str(tmp_path / "r.csv")]) == 2
    out, err = capsys.readouterr()
    assert "stopped: sensor fault" in out and "samples before it are in" in err
    assert "Traceback" not in err


# ---------------------------------------------------------------------- the command line
def test_cli_records_without_joints_and_saves_the_calibration(tmp_path, capsys):
    argv = ["record", "--sensor", "tests.robot.record_fakes:scripted_imu", "--n", "8"]
    argv += ["--sensor-option", "hold=0.3", "--sensor-option", "move=0.15"]
    argv += ["-o", str(tmp_path / "s.csv"), "--calibrate", str(tmp_path / "c.json"), "--g", "9.81"]
    argv += ["--readings-per-pose", "30", "--still-settle-time", "0.05", "--still-window", "10"]
    assert main([*argv, "--stale-after", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "pose 1 of 8 recorded: move on" in out and "pose 8 of 8 recorded\n" in out
    assert "next: gravity along" in out and f"wrote {tmp_path / 'c.json'}" in out
    from ftkin.io.calibration_file import load_calibration

    np.testing.assert_allclose(load_calibration(tmp_path / "c.json").tool_mass, 1.2, rtol=0.01)


@pytest.mark.parametrize(
    "extra, pattern",
    [
        (["--raw", "--franka", "h"], "--raw logs the sensor's stream only"),
        (["--duration", "2"], "--duration goes with --raw"),
        (["--calibrate", "SAME"], "-o/--output and --calibrate both name"),
        (["--franka", "h", "--ur", "h"], "give one joint source"),
        ([], "give the sensor"),
    ],
)
def test_cli_refuses_what_does_not_fit(tmp_path, capsys, extra, pattern):
    out = str(tmp_path / "s.csv")
    extra = [out if word == "SAME" else word for word in extra]
    assert main(["record", "-o", out, *extra]) == 2
    err = capsys.readouterr().err
    assert pattern in err and "Traceback" not in err


def test_wrench_frame_goes_with_ur(tmp_path, capsys):
    argv = ["record", "--sensor", "tests.robot.record_fakes:scripted_imu", "--wrench-frame"]
    assert main([*argv, "sensor", "-o", str(tmp_path / "s.csv")]) == 2
    assert "--wrench-frame is the axes of a UR's built-in sensor" in capsys.readouterr().err
    assert not (tmp_path / "s.csv").exists()


@pytest.mark.skipif(os.name != "posix", reason="signals")
def test_ctrl_c_exits_130_with_whole_poses_then_resume_finishes(tmp_path):
    samples = tmp_path / "s.csv"
    argv = [*FTKIN, "record", "--sensor", "tests.robot.record_fakes:scripted_imu", "--n", "8"]
    argv += ["--sensor-option", "hold=0.3", "--sensor-option", "move=0.15"]
    argv += ["-o", str(samples), "--still-settle-time", "0.05", "--still-window", "10"]
    argv += ["--readings-per-pose", "30", "--stale-after", "0.5", "--g", "9.81"]
    env = {**os.environ, "PYTHONPATH": f"{ROOT}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    process = subprocess.Popen(
        argv, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, cwd=tmp_path
    )
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:  # six poses in: Ctrl-C while moving to the seventh
        if poses_in(samples) >= 6:
            break
        time.sleep(0.05)
    time.sleep(0.25)
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=60)
    assert process.returncode == 130, out
    assert "Traceback" not in out and "interrupted" in out and "--resume" in out
    done = poses_in(samples)
    whole_poses(samples, range(done), 30)
    assert done >= 6 and "ftkin calibration from the IMU" in out  # calibrated from them
    # resume: the schedule starts again at the first pose (refused: recorded), then the others
    resumed = subprocess.run(
        [*argv, "--resume"], capture_output=True, text=True, env=env, cwd=tmp_path, timeout=120
    )
    assert resumed.returncode == 0, resumed.stdout + resumed.stderr
    assert "same pose as pose 0" in resumed.stdout
    whole_poses(samples, range(8), 30)


# ---------------------------------------------------------------------- franky-sim
franky_sim = pytest.mark.skipif(
    not all(__import__("importlib").util.find_spec(name) for name in ("franky", "franky_sim")),
    reason="franky-control and franky-sim are not installed (extras 'franka', 'franka-sim')",
)
SIM_STILL = Stillness(stale_after=1.0)  # a loaded machine may pause the simulation


@pytest.fixture(scope="module")
def sim():
    from ftkin.robot import FrankaSim

    simulation = FrankaSim()
    try:
        simulation.start()
        yield simulation
    finally:
        simulation.close()


@pytest.fixture(scope="module")
def robot(sim):
    from .test_franka_sim import connect

    return connect(sim.hostname, realtime=False, speed=0.8, state_timeout=1.0)


class Mover(threading.Thread):
    """The user: moves the robot to each pose, waits there until told it is recorded (``done``
    released by the recorder's event), then goes on to the next. ftkin commands nothing."""

    def __init__(self, robot, poses):
        super().__init__(daemon=True)
        self.robot, self.poses = robot, poses
        self.done = threading.Semaphore(0)
        self.error = None

    def on_event(self, event):
        if event.kind == "recorded":
            self.done.release()

    def run(self):
        try:
            for q in self.poses:
                if not self.done.acquire(timeout=60):
                    raise TimeoutError("the recorder said nothing for 60 s")
                self.robot.move_to(q)
        except Exception as error:  # noqa: BLE001 - reported by the test
            self.error = error


def check_truth(result, truth):
    np.testing.assert_allclose(result.tool_mass, truth.mass, rtol=0.01)
    np.testing.assert_allclose(result.center_of_mass, truth.center_of_mass, atol=0.002)
    np.testing.assert_allclose(result.force_offset, truth.bias[:3], atol=0.05)
    np.testing.assert_allclose(result.torque_offset, truth.bias[3:], atol=0.005)


@franky_sim
def test_franky_sim_moved_by_the_test_records_and_calibrates(sim, robot, tmp_path):
    from ftkin.robot.stillness import wait_still

    poses = joint_poses(3, seed=0)
    robot.move_to(poses[0])  # the user brings the arm to the first pose before starting
    wait_still(robot, SIM_STILL)
    mover = Mover(robot, poses[1:])
    mover.start()
    watchdog = threading.Timer(90.0, sim.kill)  # a recording that hangs fails, not waits
    watchdog.start()
    recording = record_poses(
        sim.sensor,
        robot,  # read only: the mover's thread moves it
        fr3_arm(),
        samples_path=tmp_path / "s.csv",
        n_poses=3,
        readings_per_pose=30,
        stillness=SIM_STILL,
        output=tmp_path / "c.json",
        g=sim.truth.g,
        on_event=mover.on_event,
    )
    watchdog.cancel()
    mover.join(30)
    assert mover.error is None
    assert recording.poses_recorded == 3 and (tmp_path / "c.json").is_file()
    samples = load_samples(tmp_path / "s.csv", fr3_arm()).samples
    ids, counts = np.unique(samples.pose_ids, return_counts=True)
    np.testing.assert_allclose(ids, range(3), atol=0.5)
    np.testing.assert_allclose(counts, 30, atol=0.5)
    # each pose is one of the planned poses the test moved to, the arm still while recorded
    # (franky-sim's hold sags by ~0.01 rad under the tool its gravity model does not know)
    for pose, q in enumerate(poses):
        recorded = samples.joint_positions[samples.pose_ids == pose]
        np.testing.assert_allclose(recorded, q[None].repeat(30, 0), atol=0.03)
        np.testing.assert_allclose(recorded, recorded.mean(axis=0)[None].repeat(30, 0), atol=1e-4)
    check_truth(recording.calibration, sim.truth)


@franky_sim
def test_franky_sim_cli_record_franka(sim, robot, tmp_path, capsys, monkeypatch):
    """``ftkin record --franka HOST`` as typed, its robot the test's (one client at a time)."""
    from ftkin.robot.stillness import wait_still

    poses = joint_poses(4, seed=5)
    robot.move_to(poses[0])
    wait_still(robot, SIM_STILL)
    mover = Mover(robot, poses[1:])
    import ftkin.robot.franka

    monkeypatch.setattr(ftkin.robot.franka, "FrankaRobot", lambda *args, **kwargs: robot)
    said = lambda event: (print(event.message), mover.on_event(event))  # noqa: E731
    monkeypatch.setattr("ftkin.cli.record._print_event", said)
    mover.start()
    watchdog = threading.Timer(90.0, sim.kill)  # a recording that hangs fails, not waits
    watchdog.start()
    argv = ["record", "--franka", sim.hostname, "--no-realtime", "--state-timeout", "1"]
    argv += sim.sensor_spec().split() + ["--stale-after", "1", "--n", "4", "--g", str(sim.truth.g)]
    argv += ["-o", str(tmp_path / "s.csv"), "--calibrate", str(tmp_path / "c.json")]
    try:
        assert main([*argv, "--readings-per-pose", "30"]) == 0
    finally:
        watchdog.cancel()
    mover.join(30)
    assert mover.error is None
    out = capsys.readouterr().out
    assert "pose 4 of 4 recorded" in out and "tool_mass" in out
    from ftkin.io.calibration_file import load_calibration

    check_truth(load_calibration(tmp_path / "c.json"), sim.truth)


def test_joint_sources_and_the_samples_log_columns(tmp_path):
    from ftkin.robot import FrankaRobot, JointStateSource, Robot
    from ftkin.robot.samples_log import SamplesLog

    arm, joints, _ = scripted_joints(joint_poses(3))
    assert isinstance(joints, JointStateSource) and not isinstance(joints, Robot)
    assert callable(FrankaRobot.joint_state)  # a FrankaRobot is one without being commanded
    path = tmp_path / "imu.csv"
    log = SamplesLog(path, (), extra_columns=("ax", "ay", "az"))
    with pytest.raises(InvalidInput, match=r"\(2, 3\) extra values"):
        log.append_pose(0, np.zeros((2, 0)), np.zeros((2, 6)), [0.0, 0.1], np.zeros((2, 2)))
    # stopped before its first pose (the header only): it resumes, with nothing recorded
    resumed = SamplesLog(path, (), resume=True, extra_columns=("ax", "ay", "az"))
    assert resumed.recorded_poses() == {}
    resumed.append_pose(0, np.zeros((2, 0)), np.ones((2, 6)), [0.0, 0.1], [[0, 0, 9.8]] * 2)
    again = SamplesLog(path, (), resume=True, extra_columns=("ax", "ay", "az"))
    np.testing.assert_allclose(again.recorded_extra()[0], [0.0, 0.0, 9.8], rtol=1e-15)


def clocked(monkeypatch, schedule) -> None:
    """The recorder's clock is the schedule's (the samples read), and its polls do not sleep:
    the wall clock plays no part, so the bound on a pose is tested to the sample."""
    from types import SimpleNamespace

    import ftkin.robot.recorder

    clock = SimpleNamespace(
        monotonic=lambda: schedule.start + schedule.elapsed(), sleep=lambda s: None
    )
    monkeypatch.setattr(ftkin.robot.recorder, "time", clock)


UNSETTLED = Stillness(settle_time=0.05, window=10, timeout=0.3, stale_after=0.5)


def test_a_still_arm_whose_readings_never_settle_is_explained_then_stopped(tmp_path, monkeypatch):
    from .record_fakes import NOISE

    arm, joints, schedule = scripted_joints(joint_poses(3), hold=2.0)
    clocked(monkeypatch, schedule)
    noisy = NOISE * 50.0  # 1 N: above --still-force-std
    # a backstop: the sensor fails at 1.5 s, where a recorder without a bound would end
    sensor = ScriptedSensor(joint_path(arm, joints), schedule, noise=noisy, fault_after=1.5)
    events = []
    with pytest.raises(RecordingInterrupted) as caught:
        record_poses(
            sensor,
            joints,
            arm,
            samples_path=tmp_path / "s.csv",
            n_poses=3,
            stillness=UNSETTLED,
            on_event=events.append,
        )
    hints = [event for event in events if event.kind == "unsettled"]
    assert len(hints) == 1 and "not stationary" in hints[0].message
    assert hints[0].message.startswith("pose 1 of 3:") and "--still-force-std" in hints[0].message
    error = caught.value
    assert error.poses_recorded == 0 and "pose 1 did not settle within 0.3 s" in error.reason
    assert "not stationary" in error.reason and "--still-force-std" in error.reason
    # stopped at the bound: the first poll more than 0.3 s after the first (the arm stood
    # still from the start; the clock is the samples read, one per poll, the first at 1 ms)
    assert 0.301 < schedule.elapsed() <= 0.301 + 2.0 / RATE + 1e-12


def test_without_joints_or_a_gyro_a_pose_that_does_not_settle_is_explained_only(
    tmp_path, monkeypatch
):
    """No speed: a sensor carried about and a noisy one look alike, so the bound does not stop
    the recording (the line is given); the sensor's fault at 1 s ends it here."""
    from ftkin.sensors.sample import SensorSample

    from .record_fakes import NOISE

    schedule = Schedule(3, 2.0, MOVE)
    clocked(monkeypatch, schedule)
    path = rotation_path(spread_rotations(3), schedule)
    noisy = ScriptedSensor(path, schedule, imu=True, noise=NOISE * 50.0, fault_after=1.0)

    class NoGyro:  # the accelerometer only
        def read(self):
            sample = self.read_sample()
            return sample.t, sample.wrench

        def read_sample(self):
            sample = noisy.read_sample()
            return SensorSample(sample.t, sample.wrench, sample.specific_force)

    events = []
    with pytest.raises(RecordingInterrupted) as caught:
        record_poses(
            NoGyro(),
            None,
            samples_path=tmp_path / "s.csv",
            n_poses=3,
            stillness=UNSETTLED,
            on_event=events.append,
        )
    assert "read failed" in caught.value.reason and "did not settle" not in caught.value.reason
    hints = [event.message for event in events if event.kind == "unsettled"]
    assert len(hints) == 1 and "not stationary" in hints[0]


class Creeping:
    """The scripted arm, ``speed`` [rad/s] added to every joint's until ``until`` [s] on the
    schedule's clock (a hold that drifts), the scripted speeds alone after."""

    def __init__(self, joints, speed: float, until: float = np.inf):
        self.joints, self.speed, self.until = joints, speed, until

    def joint_state(self):
        q, dq = self.joints.joint_state()
        creeping = self.joints.schedule.elapsed() < self.until
        return q, dq + (self.speed if creeping else 0.0)


def test_an_arm_that_creeps_is_named_then_stopped(tmp_path, monkeypatch):
    arm, joints, schedule = scripted_joints(joint_poses(3), hold=1.0)
    clocked(monkeypatch, schedule)
    sensor = ScriptedSensor(joint_path(arm, joints), schedule)
    events = []
    with pytest.raises(RecordingInterrupted) as caught:  # 0.01 rad/s: twice the limit
        record_poses(
            sensor,
            Creeping(joints, 0.01),
            arm,
            samples_path=tmp_path / "s.csv",
            n_poses=3,
            stillness=UNSETTLED,
            on_event=events.append,
        )
    hints = [event.message for event in events if event.kind == "unsettled"]
    assert len(hints) == 1 and "crept at about 0.01 rad/s" in hints[0]
    assert "--still-joint-speed" in hints[0]
    reason = caught.value.reason
    assert "pose 1 did not settle within 0.3 s" in reason and "crept at about 0.01 rad/s" in reason
    assert "ftkin record --resume" in str(caught.value) and poses_in(tmp_path / "s.csv") == 0
    # the advice followed: a limit above the creep records the pose
    followed = Stillness(joint_speed=0.02, settle_time=0.05, window=10, timeout=0.3)
    recording = record_poses(
        sensor,
        Creeping(joints, 0.01),
        arm,
        samples_path=tmp_path / "t.csv",
        n_poses=3,
        readings_per_pose=10,
        stillness=followed,
    )
    assert recording.poses_recorded == 3


@pytest.mark.parametrize(("creep", "recorded"), [(0.40, True), (0.45, False)])
def test_a_pose_that_settles_within_its_timeout_is_recorded(tmp_path, monkeypatch, creep, recorded):
    """Both sides of the bound. The arm creeps until ``creep`` s, then is still: the detector
    has it still from the first poll after (``creep``), a pose ``settle_time`` later plus the
    19 samples after the first reading: at ``creep + 0.069`` s; the bound is 0.5 s after the
    first poll (1 ms): recorded up to ``creep`` 0.432 s."""
    arm, joints, schedule = scripted_joints(joint_poses(3), hold=1.0)
    clocked(monkeypatch, schedule)
    sensor = ScriptedSensor(joint_path(arm, joints), schedule)
    stillness = Stillness(settle_time=0.05, window=10, timeout=0.5)
    options = {"samples_path": tmp_path / "s.csv", "n_poses": 3, "readings_per_pose": 20}
    if recorded:  # then the two other poses, held still
        record_poses(sensor, Creeping(joints, 0.01, creep), arm, stillness=stillness, **options)
        whole_poses(tmp_path / "s.csv", range(3), 20)
    else:
        with pytest.raises(RecordingInterrupted, match="pose 1 did not settle within 0.5 s"):
            record_poses(sensor, Creeping(joints, 0.01, creep), arm, stillness=stillness, **options)
        assert poses_in(tmp_path / "s.csv") == 0


def test_cli_recording_fault_exits_2_naming_the_resume(tmp_path, capsys):
    argv = ["record", "--sensor", "tests.robot.record_fakes:scripted_imu", "--n", "8"]
    argv += ["--sensor-option", "fault_after=1.2", "-o", str(tmp_path / "s.csv")]
    argv += ["--sensor-option", "hold=0.3", "--sensor-option", "move=0.15"]
    argv += ["--readings-per-pose", "30", "--still-settle-time", "0.05", "--still-window", "10"]
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert "pose 2 of 8 recorded" in captured.out and "Traceback" not in captured.err
    assert "the sensor's read failed" in captured.err and "--resume" in captured.err
    done = poses_in(tmp_path / "s.csv")  # held 0.3 s, moved 0.15 s: three poses by 1.2 s
    assert done >= 2
    whole_poses(tmp_path / "s.csv", range(done), 30)


def test_a_resumed_sensor_whose_clock_restarted_is_named(tmp_path, caplog):
    import logging

    poses = joint_poses(3, seed=8)
    arm, joints, schedule = scripted_joints(poses)
    sensor = ScriptedSensor(joint_path(arm, joints), schedule)
    path = tmp_path / "s.csv"
    options = {"samples_path": path, "n_poses": 3, "readings_per_pose": 10, "stillness": QUICK}
    record_poses(sensor, joints, arm, **options)

    class Restarted:  # the same sensor, its clock started again (a simulator restarted)
        def read(self):
            stamp, wrench = sensor.read()
            return stamp - 1e6, wrench

    with caplog.at_level(logging.WARNING, logger="ftkin"):
        again = record_poses(Restarted(), joints, arm, resume=True, **options)
    assert "is behind the last stamp" in caplog.text and "--drift none" in caplog.text
    assert again.poses_recorded == 3 and again.calibration is not None  # nothing more to record


@pytest.mark.skipif(
    not __import__("importlib").util.find_spec("rtde_receive"),
    reason="ur_rtde is not installed (pip install -e '.[ur]')",
)
@pytest.mark.parametrize(
    ("sent_in", "flag", "fits"),
    [("base", None, True), ("sensor", "sensor", True), ("sensor", None, False)],
)
def test_cli_record_ur_from_the_rtde_emulator_moved_by_the_test(
    tmp_path, capsys, monkeypatch, sent_in, flag, fits
):
    """``ftkin record --ur HOST --robot ur5e [--wrench-frame F]``: the real ur_rtde client
    against the RTDE emulator, the arm moved by the test (the emulator's own motion), its
    built-in sensor's simulated tool recovered; a controller that sends the wrench in the sensor's
    axes, read as base axes (the default), is refused after the poses, naming
    ``--wrench-frame sensor``. The UR support's own tests are tests/robot/test_ur.py."""
    from ftkin.io.calibration_file import load_calibration
    from ftkin.kinematics.robots import load_robot

    from .rtde_controller import EmulatedController, SimulatedTool, flange_transform

    # four poses whose gravity directions in the flange differ by 30° or more (the emulator's own
    # kinematics): random joint angles often differ by a turn about the vertical only
    poses, seen = [], []
    for q in load_robot("ur5e").random_configurations(200, np.random.default_rng(5), margin=0.5):
        down = flange_transform("ur5e", q)[:3, :3].T @ [0.0, 0.0, -1.0]
        if all(np.degrees(np.arccos(np.clip(down @ other, -1, 1))) >= 30.0 for other in seen):
            poses.append(q)
            seen.append(down)
        if len(poses) == 4:
            break
    try:
        emulated = EmulatedController(q=poses[0], wrench_frame=sent_in)
    except OSError as error:
        pytest.skip(f"cannot serve RTDE on a loopback address, port 30004: {error}")
    recorded = threading.Semaphore(0)

    def user():  # waits at each pose until it is recorded, then moves on
        for q in poses[1:]:
            if not recorded.acquire(timeout=30):
                return
            emulated.move(q, 0.4)

    said = lambda event: (print(event.message), event.kind == "recorded" and recorded.release())  # noqa: E731
    monkeypatch.setattr("ftkin.cli.record._print_event", said)
    mover = threading.Thread(target=user, daemon=True)
    mover.start()
    watchdog = threading.Timer(60.0, emulated.kill)  # a recording that hangs fails, not waits
    watchdog.start()
    argv = ["record", "--ur", emulated.host, "--robot", "ur5e", "--n", "4", "--g", "9.80665"]
    argv += ["-o", str(tmp_path / "s.csv"), "--calibrate", str(tmp_path / "c.json")]
    argv += [] if flag is None else ["--wrench-frame", flag]
    try:
        code = main([*argv, "--readings-per-pose", "30", "--stale-after", "0.5"])
    finally:
        watchdog.cancel()
        emulated.kill()
    mover.join(10)
    if not fits:
        assert code == 2
        error = capsys.readouterr().err
        assert "record again with --wrench-frame sensor" in error and "Traceback" not in error
        assert not (tmp_path / "c.json").exists()
        whole_poses(tmp_path / "s.csv", range(4), 30)
        return
    assert code == 0, capsys.readouterr().err
    assert "pose 4 of 4 recorded" in capsys.readouterr().out
    whole_poses(tmp_path / "s.csv", range(4), 30)
    tool, result = SimulatedTool(), load_calibration(tmp_path / "c.json")
    np.testing.assert_allclose(result.tool_mass, tool.mass, rtol=0.01)
    np.testing.assert_allclose(result.center_of_mass, tool.com, atol=0.002)
    np.testing.assert_allclose(result.force_offset, tool.bias[:3], atol=0.05)
