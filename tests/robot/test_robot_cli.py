"""The robot CLI as a Franka user meets it: a dry run, a plan file, the flags spelled as
``plan`` spells them, ``ftkin robot sim`` served to a second process running ``robot calibrate``
(verification included), Ctrl-C (exit 130, no traceback from the simulator's child, advice that
names only flags and files that exist), ``robot guide`` without a payload."""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv
from ftkin.kinematics.fr3 import fr3_arm

FTKIN = [sys.executable, "-m", "ftkin.cli"]


def test_dry_run_plans_prints_and_writes_without_a_robot(tmp_path, capsys):
    out = tmp_path / "calib.json"
    argv = ["robot", "calibrate", "--dry-run", "--n", "6", "-o", str(out), "--seed", "3"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    assert "dry run: 6 poses" in printed and "nothing moves" in printed
    assert "standard errors" in printed or "±" in printed
    poses = tmp_path / "calib.poses.csv"
    table = read_table(poses)
    assert table.header == ["pose", *fr3_arm().joint_names] and len(table.rows) == 6
    assert not out.exists()
    # the plan file is what --poses reads back: the same six poses, checked and printed
    assert main([*argv[:3], "--poses", str(poses), "-o", str(out)]) == 0
    assert "dry run: 6 poses" in capsys.readouterr().out


def test_a_plan_file_that_does_not_fit_the_arm_is_refused_before_any_move(tmp_path, capsys):
    arm = fr3_arm()
    q = np.tile(0.5 * (arm.lower_limits + arm.upper_limits), (4, 1))
    bad = tmp_path / "degrees.csv"
    write_csv(bad, ["pose", *arm.joint_names], [[i, *np.degrees(row)] for i, row in enumerate(q)])
    argv = ["robot", "calibrate", "--dry-run", "-o", str(tmp_path / "c.json"), "--poses"]
    assert main([*argv, str(bad)]) == 2
    assert "degrees" in capsys.readouterr().err
    low = q.copy()
    low[:, 3] = -2.9  # the elbow bent through the floor? check the floor constraint's answer
    floor = tmp_path / "floor.csv"
    write_csv(floor, ["pose", *arm.joint_names], [[i, *row] for i, row in enumerate(q)])
    assert main([*argv, str(floor), "--floor-height", "3"]) == 2
    assert "rejected by floor" in capsys.readouterr().err


def test_pose_flags_are_spelled_defaulted_and_explained_as_plan_does():
    from ftkin.cli import build_parser

    def actions(command):
        parser = build_parser(command)
        sub = parser._subparsers._group_actions[0].choices[command[0]]
        for name in command[1:]:
            sub = sub._subparsers._group_actions[0].choices[name]
        return {flag: action for action in sub._actions for flag in action.option_strings}

    plan, robot = actions(["plan"]), actions(["robot", "calibrate"])
    shared = ["--margin", "--floor-height", "--no-floor", "--max-tilt-deg", "--joint-range"]
    shared += ["--no-self-collision", "--readings-per-pose"]
    for flag in shared:
        assert flag in robot, flag
        assert robot[flag].help == plan[flag].help, flag
        assert robot[flag].default == plan[flag].default, flag
    assert "--floor" not in robot and "--readings" not in robot


def _serve(tmp_path):
    """``ftkin robot sim`` in a child process; its printed commands once it serves."""
    log = open(tmp_path / "sim.out", "w+")
    process = subprocess.Popen([*FTKIN, "robot", "sim"], stdout=log, stderr=subprocess.STDOUT)
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        log.seek(0)
        text = log.read()
        if "robot guide" in text:
            return process, log, text
        if process.poll() is not None:
            break
        time.sleep(0.2)
    process.kill()
    pytest.fail(f"ftkin robot sim did not start:\n{text}")


def _command(text: str, name: str) -> list[str]:
    line = next(line for line in text.splitlines() if f"ftkin robot {name}" in line)
    return line.strip().split()[1:]  # without "ftkin"


@pytest.fixture(scope="module")
def served(tmp_path_factory):
    pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")
    tmp_path = tmp_path_factory.mktemp("sim")
    process, log, text = _serve(tmp_path)
    yield text, tmp_path
    process.send_signal(signal.SIGINT)
    code = process.wait(30)
    log.seek(0)
    out = log.read()
    log.close()
    assert code == 130 and "Traceback" not in out and "stopping the simulation" in out


def test_robot_sim_serves_a_second_process_calibrate_payload_guide(served):
    text, tmp_path = served
    truth = re.search(r"below the sensor: ([\d.]+) kg", text)
    calib = tmp_path / "calib.json"
    argv = _command(text, "calibrate")
    argv[argv.index("-o") + 1] = str(calib)
    argv += ["--n", "4", "--readings-per-pose", "15", "--verify", "1"]
    done = subprocess.run([*FTKIN, *argv], capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, done.stdout + done.stderr
    mass = float(re.search(r"tool_mass\s+m\s+=\s+([\d.]+)", done.stdout).group(1))
    assert abs(mass - float(truth.group(1))) < 0.01  # --g 9.81: the simulator's gravity
    assert "verification at 1 pose(s)" in done.stdout
    payload = _command(text, "payload")
    payload[payload.index("calib.json")] = str(calib)
    done = subprocess.run([*FTKIN, *payload], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    sent, reported = done.stdout.splitlines()[:2]
    assert sent.split(": ", 1)[1] == reported.split(": ", 1)[1]


def test_ctrl_c_in_a_session_exits_130_and_names_the_resume(served):
    text, tmp_path = served
    argv = _command(text, "calibrate")
    calib = tmp_path / "stopped.json"
    argv[argv.index("-o") + 1] = str(calib)
    argv += ["--n", "6", "--readings-per-pose", "15", "--verify", "0"]
    process = subprocess.Popen(
        [*FTKIN, *argv], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
    )
    samples = tmp_path / "stopped.samples.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and not (samples.exists() and samples.stat().st_size > 0):
        time.sleep(0.1)
    time.sleep(0.5)  # moving to the next pose
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=60)
    assert process.returncode == 130, out
    assert "Traceback" not in out and "interrupted" in out
    assert "--resume" in out and str(samples) in out and samples.exists()
    assert not calib.exists()


def test_guide_without_a_payload_warns_naming_robot_payload(tmp_path, caplog):
    """The warning comes before the loop: checked against a fake robot with no load."""
    from ftkin.cli import robot as robot_cli
    from tests.robot.fakes import FakeRobot, FakeSensor

    class Unloaded(FakeRobot):
        def payload(self):
            return 0.0, np.zeros(3), np.zeros((3, 3))

    from ftkin.calibration.model import SensorModel
    from ftkin.calibration.result import CalibrationResult
    from ftkin.io.calibration_file import save_calibration

    model = SensorModel.from_tool(1.0, [0.0, 0.0, 0.05], [0, 0, 0], [0, 0, 0])
    result = CalibrationResult(
        model.force_offset, model.torque_offset, model.gravity_in_base, model.center_of_mass
    )
    path = save_calibration(result, tmp_path / "c.json")
    original = robot_cli._robot, robot_cli._sensor
    robot_cli._robot = lambda args: Unloaded()
    robot_cli._sensor = lambda args: FakeSensor(noise=0.01)
    import logging

    try:
        argv = ["robot", "guide", str(path), "--franka", "x", "--sensor", "m:f", "--duration"]
        with caplog.at_level(logging.WARNING, logger="ftkin"):
            assert main([*argv, "0.2"]) in (0, 1)
    finally:
        robot_cli._robot, robot_cli._sensor = original
    assert "reports no payload" in caplog.text and "ftkin robot payload" in caplog.text


@pytest.mark.skipif(os.name != "posix", reason="signals")
def test_ctrl_c_in_robot_demo_exits_130_without_a_child_traceback():
    pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")
    process = subprocess.Popen(
        [*FTKIN, "robot", "demo", "--n", "4"],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    time.sleep(8.0)  # started, moving to its first poses
    process.send_signal(signal.SIGINT)
    out, _ = process.communicate(timeout=60)
    assert process.returncode == 130, out
    assert "Traceback" not in out and "--resume" not in out
