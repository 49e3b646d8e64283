"""UrArm with the real ur_rtde client against the RTDE controller emulator (tests/robot/
rtde_controller.py): the outputs, kinematics against actual_TCP_pose, the wrench frame and its
check, a killed and a frozen controller, live compensation against the simulated tool's truth,
an external sensor, the command line."""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from dataclasses import replace

import numpy as np
import pytest

from ftkin.calibration import Samples, calibrate, check_wrench_frame
from ftkin.cli import main
from ftkin.exceptions import (
    ConventionMistake,
    InvalidInput,
    MissingDependency,
    RobotConnectionLost,
    SensorError,
)
from ftkin.io.calibration_file import save_calibration
from ftkin.kinematics.record import KinematicsRecord
from ftkin.kinematics.robots import load_robot
from ftkin.robot import UrArm, compensated_stream
from ftkin.robot.protocols import ForceTorqueSensor
from ftkin.robot.ur import rotation_from_vector

from .rtde_controller import (
    STANDARD_GRAVITY,
    EmulatedController,
    SimulatedTool,
    flange_transform,
    output_type,
    pose_vector,
)

pytest.importorskip("rtde_receive", reason="ur_rtde is not installed (pip install -e '.[ur]')")

STALE = 0.1  # [s] UrArm's default stale limit
CONTACT = (1.0, -2.0, 3.0, 0.1, 0.2, -0.3)  # [N, N·m] sensor frame


def _controller(**kwargs) -> EmulatedController:
    try:
        return EmulatedController(**kwargs)
    except OSError as error:  # ur_rtde has no port option: 30004 on a loopback address
        pytest.skip(f"cannot serve RTDE on a loopback address, port 30004: {error}")


@pytest.fixture
def controller():
    with _controller() as emulated:
        yield emulated


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    """A calibration from 12 poses recorded through UrArm (the emulator's default tool), and its
    file: every emulator of this module carries the same tool."""
    with _controller() as emulated, UrArm(emulated.host) as ur:
        calibration, _ = _calibration(emulated, ur)
    path = tmp_path_factory.mktemp("ur") / "calib.json"
    save_calibration(calibration, path)
    return calibration, str(path)


def _poses(arm, count: int, seed: int = 5) -> np.ndarray:
    return arm.random_configurations(count, np.random.default_rng(seed), margin=0.5)


def _state_at(ur, q, within: float = 30.0):
    """The first state the controller sends from the pose ``q`` on: it streams at 500 Hz, so the
    pose set a moment ago reaches the client one package later, however busy the machine; the
    deadline only keeps a broken emulator from hanging the test."""
    deadline = time.monotonic() + within
    while True:
        state = ur.state()
        if np.allclose(state.q, q, rtol=0, atol=1e-12) or time.monotonic() > deadline:
            np.testing.assert_allclose(state.q, q, atol=1e-12)
            return state
        time.sleep(0.001)


def _record(controller, ur, poses, readings: int = 40) -> Samples:
    """Static poses as a user records them: put the arm there, take new readings."""
    arm = load_robot(controller.robot)
    wrenches, joints, ids = [], [], []
    for index, q in enumerate(poses):
        controller.set_pose(q)
        time.sleep(0.01)
        last, taken = None, 0
        while taken < readings:
            stamp, q_read, wrench = ur.sensor.read_with_joints()
            if stamp != last and np.allclose(q_read, q, atol=1e-12):
                last, taken = stamp, taken + 1
                wrenches.append(wrench)
                joints.append(q_read)
                ids.append(index)
            time.sleep(0.0003)
    joints = np.array(joints)
    return Samples(np.array(wrenches), arm.rotation_sensor_to_base(joints), np.array(ids), joints)


def _calibration(controller, ur, count: int = 12):
    arm = load_robot(controller.robot)
    samples = _record(controller, ur, _poses(arm, count))
    return replace(calibrate(samples), kinematics=KinematicsRecord.from_arm(arm)), samples


# ---------------------------------------------------------------- the protocol
def test_ur_rtde_asks_for_its_outputs_and_decodes_every_field(controller):
    with UrArm(controller.host) as ur:
        requested = controller.state()["requested"]
        assert len(requested) == 58 and "ft_raw_wrench" in requested
        assert all(output_type(name) != "NOT_FOUND" for name in requested)
        rtde = ur._rtde
        # the last fields hold distinctive values: a wrong type before them would shift them
        assert rtde.getOutputDoubleRegister(19) == 19.5 and rtde.getOutputIntRegister(19) == 19
        assert rtde.getPayload() == 0.75 and rtde.getPayloadCog() == [0.001, 0.002, 0.003]
        assert rtde.getRobotMode() == 7 and rtde.getSafetyMode() == 1
        assert rtde.getJointMode() == [253] * 6
        stamps = []
        end = time.monotonic() + 0.3
        while time.monotonic() < end:
            stamps.append(ur.state().timestamp)
            time.sleep(0.0003)
        steps = np.diff(np.unique(stamps))
        np.testing.assert_allclose(np.min(steps), 0.002, rtol=1e-9)  # 500 Hz: major version 5


# ---------------------------------------------------------------- kinematics
@pytest.mark.parametrize("robot", ["ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur30"])
def test_forward_kinematics_of_actual_q_is_actual_tcp_pose(robot):
    arm = load_robot(robot)
    configurations = [*_poses(arm, 6, seed=11), [0.0] * 6, [0.4, -1.2, 0.0, 0.3, 0.0, 2.0]]
    with _controller(robot=robot) as controller, UrArm(controller.host) as ur:
        for q in configurations:
            controller.set_pose(q)
            state = _state_at(ur, q)
            rotation, position = arm.frame_placement(state.q, "tool0")
            np.testing.assert_allclose(state.tcp_pose[:3], position, atol=1e-6)
            difference = rotation_from_vector(state.tcp_pose[3:]).T @ rotation
            sine = np.linalg.norm(difference - difference.T) / (2.0 * math.sqrt(2.0))
            assert math.atan2(sine, (np.trace(difference) - 1.0) / 2.0) < 1e-6
            np.testing.assert_allclose(ur.flange_pose()[0], rotation, atol=1e-6)


def test_zero_pose_by_hand_through_the_wire(controller):
    """UR5e at q = 0: tool0 at (a2 + a3, -(d4 + d6), d1 - d5) = (-0.8172, -0.2329, 0.0628) m,
    rotation vector (π/2, 0, 0)."""
    controller.set_pose([0.0] * 6)
    time.sleep(0.01)
    with UrArm(controller.host) as ur:
        np.testing.assert_allclose(
            ur.state().tcp_pose, [-0.8172, -0.2329, 0.0628, math.pi / 2, 0.0, 0.0], atol=1e-12
        )
    with pytest.raises(RobotConnectionLost, match="is closed"):
        ur.state()
    with pytest.raises(SensorError, match="is closed"):
        ur.sensor.read()


# ---------------------------------------------------------------- the wrench frame
def _truth(controller, q) -> np.ndarray:
    tool = SimulatedTool()
    return tool.wrench_in_sensor(flange_transform(controller.robot, q)[:3, :3])


def test_default_frame_is_base_and_gives_the_load_in_the_sensor_frame(controller):
    q = [0.3, -1.1, 1.2, -0.4, 1.3, -0.6]
    controller.set_tool(force_noise=0.0, torque_noise=0.0)
    controller.set_pose(q)
    time.sleep(0.01)
    with UrArm(controller.host) as ur:
        assert isinstance(ur.sensor, ForceTorqueSensor)
        _, wrench = ur.sensor.read()
        np.testing.assert_allclose(wrench, _truth(controller, q), atol=1e-9)
        weight_along_gravity = flange_transform("ur5e", q)[:3, :3] @ wrench[:3]
        assert weight_along_gravity[2] < -0.9 * 1.2 * STANDARD_GRAVITY  # the load pulls down
    with UrArm(controller.host, wrench_frame="sensor") as ur:  # the other choice differs
        _, wrench = ur.sensor.read()
        assert np.abs(wrench - _truth(controller, q)).max() > 1.0


@pytest.mark.parametrize(
    ("controller_frame", "ur_frame", "fix"),
    [("base", "sensor", "--wrench-frame base"), ("sensor", "base", "--wrench-frame sensor")],
)
def test_a_wrench_read_in_the_wrong_frame_is_refused_naming_the_flag(
    controller, controller_frame, ur_frame, fix
):
    controller.set_tool(wrench_frame=controller_frame)
    with UrArm(controller.host, wrench_frame=ur_frame) as ur:
        samples = _record(controller, ur, _poses(load_robot("ur5e"), 8), readings=10)
    with pytest.raises(ConventionMistake, match=fix) as error:
        check_wrench_frame(samples, ur_frame)
    assert error.value.fix == fix
    with UrArm(controller.host, wrench_frame=controller_frame) as ur:  # read as it is sent
        right = _record(controller, ur, _poses(load_robot("ur5e"), 8), readings=10)
    assert check_wrench_frame(right, controller_frame).verdict == "ok"


def test_a_moving_arm_reads_whole_packages(controller):
    """During a motion every sample's wrench is the tool's load at that sample's own joint angles
    (the fields of one package), and the joint speeds are the motion's."""
    controller.set_tool(force_noise=0.0, torque_noise=0.0)
    tool = SimulatedTool()
    with UrArm(controller.host) as ur:
        controller.move([1.5, -0.6, 1.0, 0.4, 1.8, 1.5], 1.0)
        last, count, moving = None, 0, 0
        end = time.monotonic() + 0.8
        while time.monotonic() < end:
            state = ur.state()
            if state.timestamp != last:
                last, count = state.timestamp, count + 1
                rotation = flange_transform("ur5e", state.q)[:3, :3]
                np.testing.assert_allclose(
                    state.wrench_in_sensor, tool.wrench_in_sensor(rotation), atol=1e-9
                )
                moving += bool(np.abs(state.dq).max() > 0.1)
            time.sleep(0.0002)
        assert count > 100 and moving > 0.5 * count
        assert not state.q.flags.writeable  # one package, shared: read-only


# ---------------------------------------------------------------- faults
def test_a_killed_controller_is_a_lost_connection_never_old_values(controller):
    with UrArm(controller.host) as ur:
        last = ur.state().timestamp
        controller.process.kill()
        killed = time.monotonic()
        with pytest.raises(RobotConnectionLost, match="lost|stands still") as error:
            while True:  # what was on the wire before the kill, then the fault
                stamp = ur.state().timestamp
                assert last <= stamp <= last + 0.05
                last = stamp
                time.sleep(0.0005)
        assert time.monotonic() - killed < STALE + 0.05
        assert controller.host in str(error.value)
        for _ in range(3):  # and it stays a fault: never the last values again
            with pytest.raises(SensorError) as sensor_error:
                ur.sensor.read()
            assert sensor_error.value.kind in ("read_failed", "stale")
            with pytest.raises(RobotConnectionLost):
                ur.joint_positions()


def test_a_frozen_controller_is_stale_within_the_limit(controller):
    with UrArm(controller.host) as ur:
        ur.state()
        controller.freeze()
        frozen = time.monotonic()
        stamps = set()
        with pytest.raises(SensorError, match="stands still") as error:
            while True:
                stamps.add(ur.sensor.read()[0])
                time.sleep(0.0005)
        waited = time.monotonic() - frozen
        assert error.value.kind == "stale"
        assert STALE - 0.005 <= waited < STALE + 0.05  # counted from the last new package
        assert len(stamps) <= 2  # the last package (and one in flight), never new values
        with pytest.raises(RobotConnectionLost, match="limit 0.1 s"):
            ur.joint_state()
        controller.freeze(False)
        time.sleep(0.02)
        assert ur.state().timestamp > max(stamps)  # the controller is back: so is the stream


def test_nothing_listening_and_bad_arguments():
    with _controller() as controller:
        host = controller.host
    with pytest.raises(RobotConnectionLost, match="cannot read RTDE from"):
        UrArm(host)
    with pytest.raises(InvalidInput, match="--wrench-frame base|sensor"):
        UrArm("127.0.0.1", wrench_frame="tool")
    with pytest.raises(InvalidInput, match="address"):
        UrArm(" ")
    with pytest.raises(InvalidInput, match="stale_after"):
        UrArm("127.0.0.1", stale_after=0.0)


def test_missing_ur_rtde_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "rtde_receive", None)
    with pytest.raises(MissingDependency, match=r"ftkin\[ur\]"):
        UrArm("127.0.0.1")


# ---------------------------------------------------------------- live compensation
def test_live_compensation_against_the_simulated_truth(controller, calibrated):
    calibration, _ = calibrated
    assert abs(calibration.tool_mass - 1.2) < 0.005
    with UrArm(controller.host) as ur:
        q = [0.2, -1.3, 1.1, -0.9, 1.4, 0.5]
        controller.set_pose(q)
        controller.set_tool(contact=CONTACT)
        time.sleep(0.02)
        contacts, stamps = [], []
        for stamp, q_read, contact in compensated_stream(calibration, ur, ur.sensor):
            np.testing.assert_allclose(q_read, q, atol=1e-12)
            stamps.append(stamp)
            contacts.append(contact)
            if len(contacts) == 500:
                break
    assert np.all(np.diff(stamps) > 0)  # each sample once, none old
    mean = np.mean(contacts, axis=0)
    # 500 readings of noise 0.05 N / 0.002 N·m, plus the calibration's own error
    np.testing.assert_allclose(mean[:3], CONTACT[:3], atol=0.03)
    np.testing.assert_allclose(mean[3:], CONTACT[3:], atol=0.002)


class FlangeSensor:
    """An external sensor on the flange (an ATI, a Bota...): its own clock, the true load at the
    joint angles the arm reports, no noise."""

    def __init__(self, ur, controller):
        self.ur, self.controller = ur, controller
        self.tool = SimulatedTool()

    def read(self):
        q = self.ur.joint_positions()
        return time.monotonic(), self.tool.wrench_in_sensor(
            flange_transform(self.controller.robot, q)[:3, :3]
        )


def test_an_external_sensor_with_urarm_for_the_joints(controller, calibrated):
    calibration, _ = calibrated
    with UrArm(controller.host) as ur:
        sensor = FlangeSensor(ur, controller)
        for count, (_, _, contact) in enumerate(compensated_stream(calibration, ur, sensor)):
            assert np.abs(contact[:3]).max() < 0.03 and np.abs(contact[3:]).max() < 0.002
            if count == 50:
                break


# ---------------------------------------------------------------- the command line
def test_cli_live_log_at_full_rate(tmp_path, controller, calibrated, capsys):
    calib = calibrated[1]
    controller.set_tool(contact=CONTACT)
    log = tmp_path / "live.csv"
    args = ["compensate", calib, "--ur", controller.host, "--live", "--duration", "1"]
    assert main([*args, "--log", str(log)]) == 0
    out = capsys.readouterr().out
    table = np.loadtxt(log, delimiter=",", skiprows=1)
    header = log.read_text().splitlines()[0].split(",")
    assert header[0] == "t" and header[-6:] == ["fx", "fy", "fz", "mx", "my", "mz"]
    stamps = table[:, 0]
    # every package the controller sent while the log ran is in it, once, in order (the log
    # reads them on a connection of its own; ur_rtde's getters skip some on a loaded machine)
    sent = np.array(sorted(stamp for stamp, _ in controller.sent()))
    sent = sent[(sent >= stamps[0]) & (sent <= stamps[-1])]
    np.testing.assert_allclose(stamps, sent, rtol=0, atol=1e-9)
    assert f"{len(stamps)} samples" in out and "0 missed" in out
    assert len(stamps) > 0.9 * 500  # a second at 500 Hz, all of it
    np.testing.assert_allclose(table[:, -6:].mean(axis=0), CONTACT, atol=0.03)
    assert main([*args, "--log", str(log)]) == 2  # never over an existing file
    assert "exists" in capsys.readouterr().err


def test_cli_live_with_an_external_sensor(tmp_path, controller, calibrated, capsys):
    log = tmp_path / "external.csv"
    args = ["compensate", calibrated[1], "--ur", controller.host, "--live", "--duration", "0.3"]
    external = ["--sensor", "tests.robot.fakes:FakeSensor", "--log", str(log)]
    assert main([*args, *external]) == 0
    assert "tests.robot.fakes:FakeSensor" in capsys.readouterr().out
    table = np.loadtxt(log, delimiter=",", skiprows=1)
    assert len(table) > 10 and np.all(np.diff(table[:, 0]) > 0)  # the sensor's own stamps
    assert main([*args, "--sensor", "tests.robot.fakes:FakeSensor", "--sensor-option", "x"]) == 2
    assert "KEY=VALUE" in capsys.readouterr().err


def test_cli_live_track_load_reports_a_grasp(controller, calibrated, capsys):
    """``compensate --live --track-load``: an object taken at a fixed pose (0.4 kg, its COM at
    (0.01, 0, 0.1) m; its weight given as the emulator's contact, from the emulator's own flange
    rotation) is printed as one grasp with its mass as it happens (issue 39)."""
    import re
    import threading

    q = [0.2, -1.3, 1.1, -0.9, 1.4, 0.5]
    controller.set_pose(q)
    rotation = flange_transform(controller.robot, np.array(q))[:3, :3]
    weight = rotation.T @ np.array([0.0, 0.0, -0.4 * STANDARD_GRAVITY])
    contact = tuple(np.concatenate([weight, np.cross([0.01, 0.0, 0.1], weight)]).tolist())
    grasp = threading.Timer(0.8, controller.set_tool, kwargs={"contact": contact})
    grasp.start()
    args = ["compensate", calibrated[1], "--ur", controller.host, "--live", "--duration", "2"]
    try:
        code = main([*args, "--track-load", "--noise-force", "0.05", "--noise-torque", "0.002"])
    finally:
        grasp.join()
    out = capsys.readouterr().out
    assert code == 0, out
    grasps = [line for line in out.splitlines() if ": grasp (mass step" in line]
    assert len(grasps) == 1, out
    mass = float(re.search(r"mass step ([0-9.]+) kg", grasps[0]).group(1))
    assert abs(mass - 0.4) < 0.01, out  # a block's mean: 0.05 N noise is 0.005 kg


def test_cli_refuses_live_options_that_do_not_fit(tmp_path, capsys):
    calib = tmp_path / "c.json"
    calib.write_text("{}")
    cases = [
        (["--ur", "127.0.0.1"], "add --live"),
        (["--live"], "--live needs --ur HOST"),
        (["--duration", "1", "x.csv", "-o", "y.csv"], "--duration go with --ur HOST --live"),
        ([], "give LOG.csv and -o OUT.csv"),
        (["--ur", "127.0.0.1", "--live", "log.csv"], "give no LOG.csv"),
    ]
    for extra, message in cases:
        assert main(["compensate", str(calib), *extra]) == 2
        assert message in capsys.readouterr().err


def _ftkin(*args):
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([os.getcwd(), *sys.path])}
    return subprocess.Popen(
        [sys.executable, "-m", "ftkin.cli", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


def _lines(path) -> int:
    return len(path.read_text().splitlines()) if path.exists() else 0


def test_cli_ctrl_c_ends_cleanly_with_130(tmp_path, controller, calibrated):
    calib = calibrated[1]
    log = tmp_path / "live.csv"
    process = _ftkin("compensate", calib, "--ur", controller.host, "--live", "--log", str(log))
    # until it runs (the log is flushed with every batch of packages): a Ctrl-C before the command
    # has started is Python's, not ftkin's, so the signal waits for the log however slow the
    # machine; the deadline only keeps a broken run from hanging
    deadline = time.monotonic() + 120.0
    while _lines(log) < 300 and time.monotonic() < deadline and process.poll() is None:
        time.sleep(0.05)
    assert _lines(log) >= 300, f"the live run logged {_lines(log)} lines: {process.poll()}"
    process.send_signal(signal.SIGINT)
    out, err = process.communicate(timeout=20)
    assert process.returncode == 130, err
    assert "Traceback" not in err and "stopped by Ctrl-C" in out
    lines = log.read_text().splitlines()
    assert len(lines) > 250 and all(len(line.split(",")) == 13 for line in lines)


def test_cli_killed_controller_exits_2_with_the_reason(tmp_path, controller, calibrated):
    calib = calibrated[1]
    log = tmp_path / "live.csv"
    process = _ftkin("compensate", calib, "--ur", controller.host, "--live", "--log", str(log))
    deadline = time.monotonic() + 20.0
    while (not log.exists() or log.stat().st_size < 2000) and time.monotonic() < deadline:
        time.sleep(0.05)
    controller.kill()
    out, err = process.communicate(timeout=20)
    assert process.returncode == 2
    assert "Traceback" not in err and "ftkin: error:" in err and "lost" in err + out
    assert all(len(line.split(",")) == 13 for line in log.read_text().splitlines())
    json.loads(open(calib).read())  # the input is untouched


def test_pose_vector_round_trip_of_the_helper(rng):
    """The emulator's rotation vector and ftkin's Rodrigues inverse agree (angles up to π)."""
    for q in load_robot("ur5e").random_configurations(20, rng):
        transform = flange_transform("ur5e", q)
        np.testing.assert_allclose(
            rotation_from_vector(pose_vector(transform)[3:]), transform[:3, :3], atol=1e-12
        )
