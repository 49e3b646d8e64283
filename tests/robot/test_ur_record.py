"""``ftkin record --ur HOST`` without ``--robot`` (issue 37, item 5): the controller's dashboard
model, the flange orientation any UR shares, which UR the controller's TCP poses say it is, the
arm written into the samples file and checked by ``calibrate``. The truths are the RTDE emulator's
own (tests/robot/rtde_controller.py: its DH products in plain numpy, its simulated tool), never
ftkin's output read back."""

from __future__ import annotations

import shlex
import socket
import threading

import numpy as np
import pytest

from ftkin.cli import main
from ftkin.exceptions import InvalidInput, InvalidSamples
from ftkin.io.samples_csv import load_samples
from ftkin.kinematics.robots import load_robot
from ftkin.kinematics.ur_flange import MATCH_RMS, OTHER_RMS, UrFlange, identify_ur_arm
from ftkin.robot.ur_dashboard import ask_controller_model, robot_name

from .rtde_controller import DH, EmulatedController, SimulatedTool, flange_transform, pose_vector

UR_RTDE = pytest.mark.skipif(
    not __import__("importlib").util.find_spec("rtde_receive"),
    reason="ur_rtde is not installed (pip install -e '.[ur]')",
)
E_SERIES = "URSoftware 5.15.0.12345 (Dec 01 2026)"
REFUSED = "Command is not allowed due to safety reasons. Switch to remote control mode."


def _controller(**kwargs) -> EmulatedController:
    try:
        return EmulatedController(**kwargs)
    except OSError as error:
        pytest.skip(f"cannot serve RTDE on a loopback address, port 30004: {error}")


# ---------------------------------------------------------------- the dashboard's answers
@pytest.mark.parametrize(
    ("model", "software", "expected"),
    [
        ("UR5", E_SERIES, "ur5e"),
        ("UR3", "URSoftware 5.6.0.90886 (Jan 10 2020)", "ur3e"),
        ("UR10", E_SERIES, "ur10e"),
        ("UR16", E_SERIES, "ur16e"),
        ("UR20", "", "ur20"),  # PolyScope 5 only: no version needed
        ("UR30", E_SERIES, "ur30"),
        ("UR5e", "", "ur5e"),  # the series in the name
        ("ur10\r", E_SERIES, "ur10e"),
    ],
)
def test_the_dashboards_model_and_version_name_the_arm(model, software, expected):
    assert robot_name(model, software) == (expected, "")


@pytest.mark.parametrize(
    ("model", "software", "why"),
    [
        ("UR5", "URSoftware 3.15.7.106331 (Jul 13 2022)", "CB3"),  # major 3: not an e-Series
        ("UR5", "URSoftware 4.0.0.1 (x)", "not a known series"),  # neither 3 nor 5
        ("UR5", "", "either series"),  # no version: CB3 or e-Series
        ("UR10", "could not understand: 'PolyscopeVersion'", "either series"),
        ("UR15", E_SERIES, "no model of a UR15"),
        (REFUSED, "", "not a model"),  # e-Series in local mode
        ("could not understand: 'get robot model'", "", "not a model"),  # PolyScope < 3.12
        ("", "", "not a model"),
    ],
)
def test_answers_that_do_not_decide_the_arm_say_why(model, software, why):
    robot, reason = robot_name(model, software)
    assert robot is None and why in reason


def test_the_emulators_dashboard_answers_or_not():
    with _controller(dashboard="UR5") as emulated:
        said = ask_controller_model(emulated.host)
        assert (said.model, said.software, said.robot) == ("UR5", E_SERIES, "ur5e")
        said.check_robot("ur5e")
        said.check_robot(None)  # a URDF: nothing to compare
        with pytest.raises(InvalidInput, match="--robot ur10e contradicts .* --robot ur5e"):
            said.check_robot("ur10e")
    with _controller(dashboard=REFUSED) as emulated:
        said = ask_controller_model(emulated.host)
        assert said.robot is None and "not a model" in said.reason
        said.check_robot("ur10e")  # unknown: --robot is the fallback
    with _controller() as emulated:  # no Dashboard Server
        said = ask_controller_model(emulated.host)
        assert said.robot is None and said.model == "" and "no answer" in said.reason


def test_a_dashboard_that_accepts_and_stays_silent_is_no_answer():
    listener = socket.create_server(("127.0.0.1", 0))
    port = listener.getsockname()[1]
    accepted = []
    thread = threading.Thread(target=lambda: accepted.append(listener.accept()), daemon=True)
    thread.start()
    import ftkin.robot.ur_dashboard as dashboard

    try:
        with pytest.MonkeyPatch.context() as patch:
            patch.setattr(dashboard, "PORT", port)
            said = ask_controller_model("127.0.0.1", timeout=0.2)
    finally:
        listener.close()
    assert said.robot is None and "no answer" in said.reason
    with pytest.raises(InvalidInput, match="timeout"):
        ask_controller_model("127.0.0.1", timeout=0.0)


# ---------------------------------------------------------------- which UR the TCP poses say
def _tcp_poses(robot: str, q, offset) -> np.ndarray:
    """actual_TCP_pose from the emulator's own DH, the TCP set ``offset`` (4×4) from the flange."""
    return np.array([pose_vector(flange_transform(robot, row) @ offset) for row in q])


def _tcp_offset() -> np.ndarray:
    offset = np.eye(4)
    offset[:3, :3] = flange_transform("ur5e", [0.3, -0.2, 0.5, 0.1, 0.4, -0.7])[:3, :3]
    offset[:3, 3] = [0.02, -0.03, 0.15]  # a tool point 15 cm out [m]
    return offset


@pytest.mark.parametrize("robot", sorted(DH))
def test_the_tcp_poses_name_the_arm_whatever_the_tcp(robot):
    q = load_robot("ur5e").random_configurations(8, np.random.default_rng(3), margin=0.5)
    for offset in (np.eye(4), _tcp_offset()):
        found = identify_ur_arm(q, _tcp_poses(robot, q, offset))
        assert found.robot == robot, found.describe()
        assert found.rms[robot] < 1e-9 and min(found.rms.values()) == found.rms[robot]
        np.testing.assert_allclose(found.offset, offset[:3, 3], atol=1e-9)
        assert min(v for k, v in found.rms.items() if k != robot) > OTHER_RMS


def test_the_flange_orientation_is_every_ur_models():
    q = load_robot("ur5e").random_configurations(5, np.random.default_rng(4))
    for robot in DH:
        expected = np.array([flange_transform(robot, row)[:3, :3] for row in q])
        np.testing.assert_allclose(UrFlange().rotation_sensor_to_base(q), expected, atol=1e-12)


@pytest.mark.parametrize(("scale", "found"), [(0.9, True), (1.1, False)])
def test_a_misfit_either_side_of_the_match_limit(scale, found):
    """Position errors the offset cannot absorb, of RMS 0.9 and 1.1 × MATCH_RMS (a controller
    whose calibrated kinematics differ from the nominal ones by that much)."""
    q = load_robot("ur5e").random_configurations(10, np.random.default_rng(6), margin=0.5)
    tcp = _tcp_poses("ur10e", q, np.eye(4))
    stacked = UrFlange().rotation_sensor_to_base(q).reshape(-1, 3)
    noise = np.random.default_rng(7).normal(size=stacked.shape[0])
    noise -= stacked @ np.linalg.lstsq(stacked, noise, rcond=None)[0]  # what no offset explains
    noise *= scale * MATCH_RMS / np.sqrt(np.mean(np.sum(noise.reshape(-1, 3) ** 2, axis=1)))
    tcp[:, :3] += noise.reshape(-1, 3)
    result = identify_ur_arm(q, tcp)
    np.testing.assert_allclose(result.rms["ur10e"], scale * MATCH_RMS, rtol=1e-6)
    assert (result.robot == "ur10e") is found


def test_poses_that_cannot_tell_the_models_apart_name_none():
    q = load_robot("ur5e").random_configurations(6, np.random.default_rng(8), margin=0.5)
    repeated = np.repeat(q[:1], 6, axis=0)  # one pose, six times: any offset fits any model
    assert identify_ur_arm(repeated, _tcp_poses("ur5e", repeated, np.eye(4))).robot is None
    assert identify_ur_arm(q[:2], _tcp_poses("ur5e", q[:2], np.eye(4))).robot is None  # too few
    with pytest.raises(InvalidInput, match=r"\(n, 6\)"):
        identify_ur_arm(q, q[:, :3])
    with pytest.raises(InvalidInput, match="finite"):
        identify_ur_arm(np.full((3, 6), np.nan), np.zeros((3, 6)))


# ---------------------------------------------------------------- the arm written in the file
def _write_recording(path, robots=("ur5e",)) -> None:
    """Three poses of the emulator's tool on a UR5e in the samples file's layout."""
    q = load_robot("ur5e").random_configurations(3, np.random.default_rng(9), margin=0.5)
    tool = SimulatedTool()
    names = ",".join(UrFlange.joint_names)
    lines = [f"# robot: {robot} (test)" for robot in robots]
    lines.append(f"{names},fx,fy,fz,mx,my,mz,pose")
    for pose, row in enumerate(q):
        wrench = tool.wrench_in_sensor(flange_transform("ur5e", row)[:3, :3])
        lines.append(",".join(repr(float(value)) for value in [*row, *wrench]) + f",{pose}")
    path.write_text("\n".join(lines) + "\n")


def test_a_recording_is_read_with_the_arm_it_names(tmp_path):
    path = tmp_path / "s.csv"
    _write_recording(path)
    load_samples(path, load_robot("ur5e"))
    with pytest.raises(InvalidSamples, match="recorded on a ur5e .* --robot ur10e: give --robot"):
        load_samples(path, load_robot("ur10e"))
    with pytest.raises(InvalidSamples, match="no --robot .*: give --robot ur5e"):
        load_samples(path)
    _write_recording(path, ("ur5e", "ur10e"))
    with pytest.raises(InvalidSamples, match="more than one arm"):
        load_samples(path, load_robot("ur5e"))


def test_calibrate_refuses_another_robot_than_the_recordings(tmp_path, capsys):
    path = tmp_path / "s.csv"
    _write_recording(path)
    assert main(["calibrate", str(path), "--robot", "ur10e"]) == 2
    error = capsys.readouterr().err
    assert "recorded on a ur5e" in error and "give --robot ur5e" in error
    assert "Traceback" not in error


# ---------------------------------------------------------------- the command line
def _distinct_poses(count: int, degrees: float) -> list[np.ndarray]:
    """Poses whose gravity directions in the flange differ by ``degrees`` or more (the emulator's
    own kinematics)."""
    poses, seen = [], []
    for q in load_robot("ur5e").random_configurations(400, np.random.default_rng(5), margin=0.5):
        down = flange_transform("ur5e", q)[:3, :3].T @ [0.0, 0.0, -1.0]
        if all(np.degrees(np.arccos(np.clip(down @ other, -1, 1))) >= degrees for other in seen):
            poses.append(q)
            seen.append(down)
        if len(poses) == count:
            return poses
    raise AssertionError(f"only {len(poses)} poses {degrees}° apart")


def _record(monkeypatch, emulated, poses, argv) -> int:
    """``main(argv)`` while the test moves the emulator to the next pose after each one recorded."""
    recorded = threading.Semaphore(0)

    def user():
        for q in poses[1:]:
            if not recorded.acquire(timeout=30):
                return
            emulated.move(q, 0.3)

    def said(event):
        print(event.message)
        if event.kind == "recorded":
            recorded.release()

    monkeypatch.setattr("ftkin.cli.record._print_event", said)
    mover = threading.Thread(target=user, daemon=True)
    mover.start()
    watchdog = threading.Timer(120.0, emulated.kill)  # a recording that hangs fails
    watchdog.start()
    try:
        return main([*argv, "--readings-per-pose", "30", "--stale-after", "0.5"])
    finally:
        watchdog.cancel()
        mover.join(10)


def _check_tool(calibration) -> None:
    tool = SimulatedTool()  # noise 0.05 N, 0.002 N·m
    np.testing.assert_allclose(calibration.tool_mass, tool.mass, rtol=0.01)
    np.testing.assert_allclose(calibration.center_of_mass, tool.com, atol=0.002)
    np.testing.assert_allclose(calibration.force_offset, tool.bias[:3], atol=0.05)
    np.testing.assert_allclose(calibration.torque_offset, tool.bias[3:], atol=0.005)


@UR_RTDE
def test_record_without_a_model_prints_the_calibrate_command_that_works(
    tmp_path, capsys, monkeypatch
):
    """The contract as written: ``ftkin record --ur HOST --n 12 -o s.csv`` on a controller with
    no dashboard, then the printed ``ftkin calibrate s.csv --robot ur5e``, run as printed."""
    from ftkin.io.calibration_file import load_calibration

    poses = _distinct_poses(12, 20.0)
    samples = tmp_path / "s.csv"
    with _controller(q=poses[0]) as emulated:
        code = _record(monkeypatch, emulated, poses, ["record", "--ur", emulated.host, "--n", "12"]
                       + ["-o", str(samples)])  # fmt: skip
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "pose 12 of 12 recorded" in out and "no model from the controller" in out
    assert "fit ur5e" in out
    line = next(line for line in out.splitlines() if "finish with: " in line)
    command = shlex.split(line.split("finish with: ", 1)[1])
    assert command == ["ftkin", "calibrate", str(samples), "--robot", "ur5e"]
    assert "# robot: ur5e (actual_TCP_pose" in samples.read_text()  # written for calibrate
    assert main(command[1:]) == 0  # as printed
    assert "tool_mass" in capsys.readouterr().out
    assert main([*command[1:], "-o", str(tmp_path / "c.json")]) == 0
    _check_tool(load_calibration(tmp_path / "c.json"))
    assert main(["calibrate", str(samples), "--robot", "ur16e"]) == 2  # the file names its arm
    assert "recorded on a ur5e" in capsys.readouterr().err


@UR_RTDE
def test_record_takes_the_model_the_dashboard_names_and_calibrates(tmp_path, capsys, monkeypatch):
    from ftkin.io.calibration_file import load_calibration

    poses = _distinct_poses(4, 30.0)
    argv = ["--n", "4", "-o", str(tmp_path / "s.csv"), "--calibrate", str(tmp_path / "c.json")]
    with _controller(q=poses[0], dashboard="UR5") as emulated:
        code = _record(monkeypatch, emulated, poses, ["record", "--ur", emulated.host, *argv])
    out, err = capsys.readouterr()
    assert code == 0, err
    assert "UR5 on URSoftware 5.15.0.12345 (Dec 01 2026) (--robot ur5e)" in out
    text = (tmp_path / "s.csv").read_text()
    assert "# robot: ur5e (the controller's dashboard: UR5 on URSoftware 5.15.0" in text
    calibration = load_calibration(tmp_path / "c.json")
    assert calibration.kinematics.robot == "ur5e"
    _check_tool(calibration)


@UR_RTDE
def test_a_robot_the_dashboard_contradicts_is_refused_before_recording(tmp_path, capsys):
    with _controller(dashboard="UR10") as emulated:
        argv = ["record", "--ur", emulated.host, "--robot", "ur5e", "-o", str(tmp_path / "s.csv")]
        assert main(argv) == 2
    error = capsys.readouterr().err
    assert "--robot ur5e contradicts the controller" in error and "UR10" in error
    assert "give --robot ur10e" in error and "Traceback" not in error
    assert not (tmp_path / "s.csv").exists()


@UR_RTDE
def test_without_a_model_the_wrench_frame_is_still_checked(tmp_path, capsys, monkeypatch):
    """A controller that sends the wrench in the sensor's axes, read as base axes (the default),
    is refused after the poses, naming ``--wrench-frame sensor``, with no model at all."""
    poses = _distinct_poses(4, 30.0)
    with _controller(q=poses[0], wrench_frame="sensor") as emulated:
        argv = ["record", "--ur", emulated.host, "--n", "4", "-o", str(tmp_path / "s.csv")]
        code = _record(monkeypatch, emulated, poses, argv)
    assert code == 2
    error = capsys.readouterr().err
    assert "record again with --wrench-frame sensor" in error and "Traceback" not in error
