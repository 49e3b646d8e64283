"""Arms are compared by their kinematics, not by the URDF's bytes (issue 37 item 4).

The record keeps the chain from the base to the sensor frame (each joint's screw axis and the
sensor frame at zero joint angles); two files with that chain are the same arm, a difference names
the joint and by how much. The perturbations below are hand-made in the URDF text, so the amount
each message must report is known without ftkin: a joint origin moved by ``d`` perpendicular to
the joint axes moves that axis (and the sensor) by ``d``; an origin turned by ``ε`` turns the axis
by ``ε``. The tolerance (:data:`KINEMATICS_TOLERANCE`) is probed on both sides.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import ftkin
from ftkin import Arm, load_calibration, save_calibration
from ftkin.kinematics.fr3 import fr3_arm
from ftkin.kinematics.record import KINEMATICS_TOLERANCE, KinematicsRecord

TOLERANCE = KINEMATICS_TOLERANCE


def two_joint_urdf(
    path: Path,
    *,
    shift_x: float = 0.0,
    turn_x: float = 0.0,
    kind: str = "revolute",
    split: bool = False,
    prefix: str = "",
) -> Path:
    """A base, a revolute joint about z, a second joint about z 0.3 m out along x (moved by
    ``shift_x`` [m], turned ``turn_x`` [rad] about x), the sensor 0.05 m above its child.
    ``split``: the first link's 0.3 m written as two fixed-joint pieces (0.1 + 0.2 m), the same
    chain; ``prefix`` renames every link and joint."""
    p = prefix
    limit = '<limit lower="-3" upper="3" effort="10" velocity="1"/>'
    if split:
        first_link = f"""
  <link name="{p}link1"/><link name="{p}middle"/>
  <joint name="{p}piece" type="fixed"><parent link="{p}link1"/><child link="{p}middle"/>
    <origin xyz="0.1 0 0"/></joint>"""
        second_parent, second_x = f"{p}middle", 0.2 + shift_x
    else:
        first_link, second_parent, second_x = f'\n  <link name="{p}link1"/>', f"{p}link1", 0.3
        second_x += shift_x
    path.write_text(
        f"""<?xml version="1.0"?>
<robot name="{p}two">
  <link name="{p}base"/>{first_link}
  <link name="{p}link2"/><link name="{p}ft_link"/>
  <joint name="{p}j1" type="revolute"><parent link="{p}base"/><child link="{p}link1"/>
    <origin xyz="0 0 0.2"/><axis xyz="0 0 1"/>{limit}</joint>
  <joint name="{p}j2" type="{kind}"><parent link="{second_parent}"/><child link="{p}link2"/>
    <origin xyz="{second_x!r} 0 0" rpy="{turn_x!r} 0 0"/><axis xyz="0 0 1"/>{limit}</joint>
  <joint name="{p}sensor" type="fixed"><parent link="{p}link2"/><child link="{p}ft_link"/>
    <origin xyz="0 0 0.05"/></joint>
</robot>
"""
    )
    return path


@pytest.fixture(scope="module")
def folder(tmp_path_factory):
    return tmp_path_factory.mktemp("urdf")


@pytest.fixture(scope="module")
def record(folder):
    arm = Arm.from_urdf(two_joint_urdf(folder / "base.urdf"), "ft_link")
    return KinematicsRecord.from_arm(arm)


def arm_of(folder: Path, name: str, sensor_frame: str = "ft_link", **options) -> Arm:
    return Arm.from_urdf(two_joint_urdf(folder / f"{name}.urdf", **options), sensor_frame)


def test_the_same_chain_in_another_file_is_the_same_arm(folder, record):
    # other bytes, links split by a fixed joint, every name changed: the same kinematics
    other = arm_of(folder, "split", "x_ft_link", split=True, prefix="x_")
    assert (folder / "split.urdf").read_bytes() != (folder / "base.urdf").read_bytes()
    assert record.mismatches(other) == []
    assert KinematicsRecord.from_arm(other).mismatches(arm_of(folder, "again")) == []


@pytest.mark.parametrize("factor", [0.5, 2.0])
def test_a_moved_joint_is_named_with_its_distance(folder, record, factor):
    shift = factor * TOLERANCE  # [m] along x, perpendicular to both joint axes
    problems = record.mismatches(arm_of(folder, f"moved{factor}", shift_x=shift))
    if factor < 1.0:
        assert problems == []
        return
    mm = f"{shift * 1e3:.3g} mm"  # the axis line and the sensor origin move by the shift
    assert problems == [
        f"joint 2 (j2): its axis is moved {mm} from the calibration's (j2)",
        f"at zero joint angles the sensor frame 'ft_link' is moved {mm} from the calibration's "
        f"(at [{0.3 + shift:.6g}, 0.0, 0.25] m, calibrated at [0.3, 0.0, 0.25] m, base frame)",
    ]


@pytest.mark.parametrize("factor", [0.5, 2.0])
def test_a_turned_joint_is_named_with_its_angle(folder, record, factor):
    angle = factor * TOLERANCE  # [rad] about x: joint 2's z axis tilts by it
    problems = record.mismatches(arm_of(folder, f"turned{factor}", turn_x=angle))
    if factor < 1.0:
        assert problems == []
        return
    degrees = f"{np.rad2deg(angle):.3g}°"
    assert problems[0] == f"joint 2 (j2): its axis is turned {degrees} from the calibration's (j2)"
    # the sensor frame turns by the angle too, and its origin (0.05 m up joint 2's axis) moves
    # by 0.05·ε = 1e-6 m, within the tolerance: only the turn is named
    assert problems[1].startswith(
        f"at zero joint angles the sensor frame 'ft_link' is turned {degrees} from"
    )


def test_another_joint_kind_and_another_joint_count_are_named(folder, record):
    sliding = arm_of(folder, "prismatic", kind="prismatic")
    assert record.mismatches(sliding)[0] == "joint 2 (j2) is prismatic, calibrated revolute"
    assert record.mismatches(ftkin.Arm.default()) == [
        "6 joints (joint1, joint2, joint3, joint4, joint5, joint6), calibrated with 2 (j1, j2)"
    ]


def test_the_users_fr3_urdf_is_the_bundled_fr3():
    """franky-sim's FR3 URDF is another file than ftkin's bundled copy, with the same chain."""
    franky_sim = pytest.importorskip("franky_sim")
    path = Path(franky_sim.__file__).parent / "assets" / "fr3.urdf"
    users = Arm.from_urdf(path, "fr3_hand", "fr3_hand_tcp")
    bundled = fr3_arm()
    assert path.read_bytes() != bundled.urdf_path.read_bytes()
    assert KinematicsRecord.from_arm(users).mismatches(bundled) == []
    assert KinematicsRecord.from_arm(bundled).mismatches(users) == []
    # the Panda at its flange: the same joints, the sensor frame 45° about z from the hand's
    panda = ftkin.load_robot("panda")
    assert KinematicsRecord.from_arm(users).mismatches(panda) == [
        "at zero joint angles the sensor frame 'ft_sensor' is turned 45° from the calibration's "
        "(at [0.088, 0.0, 0.926] m, calibrated at [0.088, 0.0, 0.926] m, base frame)"
    ]


def test_the_chain_round_trips_and_a_malformed_one_is_refused(folder, record, tool, tmp_path):
    result = ftkin.CalibrationResult.from_model(tool)
    from dataclasses import replace

    path = save_calibration(replace(result, kinematics=record), tmp_path / "c.json")
    assert load_calibration(path).kinematics == record
    document = json.loads(path.read_text())
    cases = {
        "screw_axes": ([[0, 0, 1, 0, 0]] * 2, "screw_axes must be a list of"),
        "joints": (["j1"], "1 joints but 2 screw_axes"),
        "sensor_home": (None, "screw_axes and sensor_home come together"),
    }
    for key, (value, message) in cases.items():
        broken = json.loads(json.dumps(document))
        broken["kinematics"][key] = value
        path.write_text(json.dumps(broken))
        with pytest.raises(ftkin.CalibrationFileError, match=message):
            load_calibration(path)


@pytest.mark.parametrize("factor", [0.5, 2.0])
def test_a_sensor_offset_is_judged_by_the_same_tolerance(factor):
    """The sensor moved along the UR5's flange z by ``factor`` tolerances: only the sensor frame
    moves, by exactly that distance."""
    shift = factor * TOLERANCE  # [m]
    record = KinematicsRecord.from_arm(ftkin.load_robot("ur5", [0.0, 0.0, 0.05]))
    problems = record.mismatches(ftkin.load_robot("ur5", [0.0, 0.0, 0.05 + shift]))
    if factor < 1.0:
        assert problems == []
    else:
        assert len(problems) == 1
        assert problems[0].startswith(
            f"at zero joint angles the sensor frame 'ft_sensor' is moved {shift * 1e3:.3g} mm "
        )
