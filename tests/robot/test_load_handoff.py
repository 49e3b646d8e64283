"""The load in the hand to the controller (issue 39) without a robot: the held load's file, its
place in the flange frame, the combined body, the export formats and the hand-off's decisions.

Expectations are computed here by hand (parallel-axis theorem, the sensor 2 cm out of ``tool0``
as the arm is built), never read back from the code under test.
"""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from ftkin.calibration.information import SensorNoise
from ftkin.calibration.model import SensorModel
from ftkin.calibration.result import CalibrationResult
from ftkin.cli import main
from ftkin.control.load_events import LoadTracker
from ftkin.exceptions import InvalidInput
from ftkin.io.calibration_file import save_calibration
from ftkin.io.export import export_text
from ftkin.io.payload_held_load import HeldLoad, combined_payload, read_held_load
from ftkin.io.payload_inertia import Payload, RigidBody
from ftkin.kinematics import load_robot
from ftkin.robot.load_handoff import LoadHandoff, MotionFlag, held_load_of

yaml = pytest.importorskip("yaml")

G = 9.81
TOOL = SensorModel.from_tool(1.2, [0.01, -0.02, 0.06], [0.5, -0.3, 0.2], [0.01, 0.0, -0.02], g=G)
OFFSET = np.array([0.0, 0.0, 0.02])  # the sensor frame in tool0 [m] (load_robot's offset)
HELD = (0.4, np.array([0.015, 0.005, 0.12]))  # [kg], [m, sensor frame]


@pytest.fixture(scope="module")
def ur5():
    return load_robot("ur5", OFFSET)


def test_two_point_masses_combine_by_the_parallel_axis_theorem():
    tool = Payload(1.0, np.array([0.0, 0.0, 0.1]), "tool0", None)
    held = RigidBody.point(0.5, [0.1, 0.0, 0.1])
    both = combined_payload(tool, held)
    # 1 kg and 0.5 kg 0.1 m apart along x: COM 1/3 of the way, I = μ d² about y and z
    reduced = 1.0 * 0.5 / 1.5
    assert both.mass == pytest.approx(1.5, rel=1e-12)
    np.testing.assert_allclose(both.center_of_mass, [0.1 / 3, 0.0, 0.1], atol=1e-12)
    np.testing.assert_allclose(
        both.inertia, np.diag([0.0, reduced * 0.01, reduced * 0.01]), atol=1e-12
    )


def test_ur_payload_with_a_held_load_is_the_two_bodies_in_tool0(ur5, tmp_path):
    path = tmp_path / "load.json"
    path.write_text(json.dumps({"mass": HELD[0], "center_of_mass": HELD[1].tolist()}))
    request = yaml.safe_load(export_text(TOOL, "ur-payload", ur5, held_load=str(path)))
    mass = 1.2 + HELD[0]
    com = (1.2 * (TOOL.center_of_mass + OFFSET) + HELD[0] * (HELD[1] + OFFSET)) / mass
    assert request["mass"] == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose([request["center_of_gravity"][k] for k in "xyz"], com, atol=1e-12)
    # the URScript line carries the inertia of the two bodies about their common COM
    script = export_text(
        TOOL, "ur-payload", ur5, held_load=HeldLoad(*HELD), path=tmp_path / "p.script"
    )
    line = re.search(r"set_target_payload\(([^,]+), \[([^\]]+)\], \[([^\]]+)\]\)", script)
    numbers = [float(v) for v in line.group(3).split(",")]
    d = HELD[1] - TOOL.center_of_mass
    reduced = 1.2 * HELD[0] / mass
    inertia = reduced * (d @ d * np.eye(3) - np.outer(d, d))
    np.testing.assert_allclose(
        numbers,
        [inertia[0, 0], inertia[1, 1], inertia[2, 2], *inertia[[0, 0, 1], [1, 2, 2]]],
        atol=1e-12,
    )


def test_export_cli_takes_a_held_load_file_and_refuses_a_bad_one(ur5, tmp_path, capsys):
    calib = save_calibration(CalibrationResult.from_model(TOOL), tmp_path / "calib.json")
    good, bad, nan = (tmp_path / name for name in ("good.json", "bad.json", "nan.json"))
    good.write_text(json.dumps({"mass": 0.4, "center_of_mass": [0.0, 0.0, 0.1]}))
    bad.write_text("{mass: 0.4")
    nan.write_text('{"mass": 0.4, "center_of_mass": [0.0, 0.0, NaN]}')
    out = tmp_path / "u.yaml"
    args = ["export", str(calib), "--format", "ur-payload", "--robot", "ur5", "-o", str(out)]
    args += ["--sensor-offset", "0", "0", "0.02"]
    assert main([*args, "--held-load", str(good)]) == 0
    assert yaml.safe_load(out.read_text())["mass"] == pytest.approx(1.6, rel=1e-12)
    capsys.readouterr()
    assert main([*args, "--held-load", str(bad)]) == 2
    assert "not a held load's JSON" in capsys.readouterr().err
    assert main([*args, "--held-load", str(nan)]) == 2
    assert "turn the wrist" in capsys.readouterr().err
    assert main([*args, "--held-load", str(tmp_path / "none.json")]) == 2
    assert "no held-load file" in capsys.readouterr().err


@pytest.mark.parametrize(
    "document, words",
    [
        ({"mass": -0.1, "center_of_mass": [0, 0, 0]}, ">= 0 kg"),
        ({"mass": "heavy", "center_of_mass": [0, 0, 0]}, "must be a number"),
        ({"mass": 0.1, "center_of_mass": [0, 0]}, "3 numbers"),
        ({"mass": 0.1}, "'center_of_mass'"),
        ({"mass": 0.1, "center_of_mass": [0, 0, 0], "colour": "red"}, "colour"),
        ([0.1, 0, 0, 0], "JSON object"),
    ],
)
def test_malformed_held_loads_are_named(tmp_path, document, words):
    path = tmp_path / "load.json"
    path.write_text(json.dumps(document))
    with pytest.raises(InvalidInput, match=re.escape(words)):
        read_held_load(path)


def still(tracker, rotation, load, seconds, start, rng, noise):
    """Feed ``tracker`` a load (mass, COM) held still at ``rotation`` for ``seconds`` (1 kHz)."""
    mass, com = load
    down = rotation.T @ np.asarray(tracker.gravity_in_base)
    force = mass * down
    wrench = np.concatenate([force, np.cross(com, force)]) if mass else np.zeros(6)
    for i in range(int(seconds * 1000)):
        noisy = wrench + rng.normal(size=6) * noise.channel_std
        tracker.compensate(rotation, noisy, time=start + i * 1e-3)
    return start + seconds


def turned(angle_x, angle_y):
    cx, sx, cy, sy = np.cos(angle_x), np.sin(angle_x), np.cos(angle_y), np.sin(angle_y)
    rx = np.array([[1, 0, 0], [0, cx, -sx], [0, sx, cx]])
    ry = np.array([[cy, 0, sy], [0, 1, 0], [-sy, 0, cy]])
    return rx @ ry


def test_held_load_of_a_tracker_across_gravity_then_whole():
    noise = SensorNoise(0.02, 0.002)
    tracker = LoadTracker(noise, [0.0, 0.0, -G])
    rng = np.random.default_rng(3)
    level = np.eye(3)
    t = still(tracker, level, (0.0, None), 0.2, 0.0, rng, noise)
    t = still(tracker, level, HELD, 0.5, t, rng, noise)
    with pytest.raises(InvalidInput, match="gravity_in_sensor"):
        held_load_of(tracker)
    held = held_load_of(tracker, [0.0, 0.0, -1.0])  # gravity along −z: z unknown, sent as 0
    assert held.mass == pytest.approx(HELD[0], rel=2e-3)
    np.testing.assert_allclose(held.center_of_mass, [*HELD[1][:2], 0.0], atol=1e-3)
    t = still(tracker, turned(0.6, 0.0), HELD, 0.5, t, rng, noise)
    t = still(tracker, turned(0.0, 0.6), HELD, 0.5, t, rng, noise)
    held = held_load_of(tracker, [0.0, 0.0, -1.0])  # now known: the direction does not matter
    assert held.mass == pytest.approx(HELD[0], rel=2e-3)
    np.testing.assert_allclose(held.center_of_mass, HELD[1], atol=1e-3)
    with pytest.raises(InvalidInput, match="LoadTracker or LoadEstimate"):
        held_load_of({"mass": 0.4})


class RecordingRobot:
    """Records what set_payload was given (the hand-off's decisions)."""

    def __init__(self):
        self.calls = []

    def set_payload(self, calibration, *, arm=None, held_load=None, **options):
        self.calls.append(held_load)
        mass = 1.2 + (0.0 if held_load is None else held_load.mass)
        return Payload(mass, np.zeros(3), "flange", None)


def test_the_handoff_sends_on_grasp_once_the_com_is_known_and_on_release():
    from ftkin import Arm

    arm = Arm.default()
    noise = SensorNoise(0.02, 0.002)
    tracker = LoadTracker(noise, [0.0, 0.0, -G])
    robot = RecordingRobot()
    handoff = LoadHandoff(robot, TOOL, tracker, arm)
    rng = np.random.default_rng(4)
    q = np.zeros(6)
    level = arm.rotation_sensor_to_base(q[None])[0]
    t = still(tracker, level, (0.0, None), 0.2, 0.0, rng, noise)
    assert handoff.update(q) is None and robot.calls == []
    t = still(tracker, level, HELD, 0.3, t, rng, noise)
    assert handoff.update(q).mass == pytest.approx(1.2 + HELD[0], rel=2e-3)
    assert [why for why, _ in handoff.sent] == ["grasp"]
    assert handoff.update(q) is None  # nothing new
    for q_turned in (q + [0, 0, 0, 0.6, 0, 0], q + [0, 0, 0, 0.6, 0.6, 0]):
        rotation = arm.rotation_sensor_to_base(q_turned[None])[0]
        t = still(tracker, rotation, HELD, 0.5, t, rng, noise)
        handoff.update(q_turned)
    assert [why for why, _ in handoff.sent] == ["grasp", "com"]
    np.testing.assert_allclose(robot.calls[-1].center_of_mass, HELD[1], atol=1e-3)
    t = still(tracker, rotation, (0.0, None), 0.3, t, rng, noise)
    handoff.update(q_turned)
    assert [why for why, _ in handoff.sent] == ["grasp", "com", "release"]
    assert robot.calls[-1] is None  # the tool alone


def test_the_motion_flag_holds_after_the_arm_stops():
    tracker = LoadTracker(SensorNoise(0.02, 0.002))
    flag = MotionFlag(tracker, speed=0.01, settle=0.15)
    assert not flag.update(0.0, np.zeros(6))
    assert flag.update(0.1, [0, 0, 0.0101, 0, 0, 0])  # just above the speed
    assert flag.update(0.249, np.zeros(6))  # within the settle time
    assert not flag.update(0.251, np.zeros(6))
    assert not flag.update(0.3, [0, 0, 0.0099, 0, 0, 0])  # just below


@pytest.mark.parametrize(
    "flags, words",
    [
        (["--send-load"], "go with --track-load"),
        (["--noise-force", "0.02", "--noise-torque", "0.002"], "go with --track-load"),
        (["--track-load", "--noise-force", "0.02"], "give both --noise-force"),
        (["--track-load"], "records no noise"),  # a calibration without noise, none given
    ],
)
def test_guide_load_options_are_checked_before_anything_opens(tmp_path, capsys, flags, words):
    calib = save_calibration(CalibrationResult.from_model(TOOL), tmp_path / "calib.json")
    argv = ["robot", "guide", str(calib), "--franka", "192.0.2.1", "--sensor", "nowhere:none"]
    assert main([*argv, *flags]) == 2
    assert words in capsys.readouterr().err


def test_an_identified_inertia_is_moved_to_the_load_com():
    """A LoadEstimate's inertia (about the sensor origin, Pinocchio's order) becomes the held
    load's about its own COM: a solid sphere (2/5 m r²) 0.1 m below the origin, by hand."""
    from ftkin.control.load_estimator import LoadEstimate

    mass, radius, com = 0.5, 0.03, np.array([0.0, 0.0, 0.1])
    own = 0.4 * mass * radius**2
    about_origin = own * np.eye(3) + mass * (com @ com * np.eye(3) - np.outer(com, com))
    i = about_origin
    parameters = [mass, *(mass * com), i[0, 0], i[0, 1], i[1, 1], i[0, 2], i[1, 2], i[2, 2]]
    estimate = LoadEstimate(
        mass, 1e-4, com, np.full(3, 1e-4), parameters, np.full(6, 1e-6), 1000, 5994.0, 5990
    )
    held = held_load_of(estimate)
    assert held.mass == pytest.approx(mass, rel=1e-12)
    np.testing.assert_allclose(held.center_of_mass, com, atol=1e-15)
    np.testing.assert_allclose(held.inertia, own * np.eye(3), atol=1e-15)
    undetermined = LoadEstimate(
        mass, 1e-4, [0.0, 0.0, np.nan], [1e-4, 1e-4, np.inf], None, None, 10, 0.0, 57
    )
    with pytest.raises(InvalidInput, match="turn the wrist"):
        held_load_of(undetermined)
