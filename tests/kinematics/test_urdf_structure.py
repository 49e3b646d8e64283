"""URDF structure errors are named as what they are: a kinematic loop, a folder, a missing link."""

from __future__ import annotations

import re

import numpy as np
import pytest

from ftkin import Arm
from ftkin.exceptions import UrdfError
from ftkin.kinematics.urdf_loading import tree_reasons, xml_reasons


def urdf(*joints, links=("base", "a", "b", "ft_sensor")) -> str:
    """A URDF with the given links and ``(name, parent, child)`` revolute joints."""
    body = "".join(f'<link name="{name}"/>' for name in links)
    for name, parent, child in joints:
        body += (
            f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
            '<axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>'
        )
    return f'<robot name="r">{body}</robot>'


CHAIN = [("j1", "base", "a"), ("j2", "a", "b"), ("j3", "b", "ft_sensor")]


def test_a_chain_is_fine():
    assert xml_reasons(urdf(*CHAIN)) == []


@pytest.mark.parametrize(
    "joints, pattern",
    [
        ([*CHAIN, ("j4", "base", "b")], "link 'b' is the child of two joints .* kinematic loop"),
        ([("j1", "a", "b"), ("j2", "b", "a"), ("j3", "b", "ft_sensor")], "kinematic loop"),
        ([*CHAIN[:2], ("j3", "flange", "ft_sensor")], "parent link 'flange', which is not a"),
        ([*CHAIN[:2], ("j3", "b", "tool0")], "child link 'tool0', which is not a"),
    ],
)
def test_structure_errors_are_named(joints, pattern):
    import re

    reasons = xml_reasons(urdf(*joints))
    assert reasons and re.search(pattern, reasons[0]), reasons


def test_several_roots_are_named():
    import xml.etree.ElementTree as ET

    root = ET.fromstring(urdf(*CHAIN[:2]))
    assert "2 root links ['base', 'ft_sensor']" in tree_reasons(root)[0]


def test_loop_through_arm_loading(tmp_path):
    path = tmp_path / "loop.urdf"
    path.write_text(urdf(*CHAIN, ("j4", "base", "b")))
    with pytest.raises(UrdfError, match="kinematic loop"):
        Arm.from_urdf(path, "ft_sensor")


def test_a_folder_given_as_a_urdf(tmp_path):
    (tmp_path / "robot.urdf").write_text(urdf(*CHAIN))
    with pytest.raises(UrdfError, match=r"is a folder, expected a URDF file \(it holds \['robot"):
        Arm.from_urdf(tmp_path, "ft_sensor")


def test_limits_in_degrees_and_a_zero_axis_are_named(tmp_path):
    """A URDF whose revolute limits were written in degrees (±170) planned poses beyond the real
    limits; a joint with axis 0 0 0 leaked a numpy warning and 'not a rotation matrix'."""
    from ftkin.kinematics.arm import bundled_urdf_path

    text = bundled_urdf_path().read_text()
    degrees = re.sub(
        r'<limit([^>]*?)lower="([-\d.e]+)"([^>]*?)upper="([-\d.e]+)"',
        lambda m: (
            f'<limit{m[1]}lower="{np.rad2deg(float(m[2])):.1f}"{m[3]}'
            f'upper="{np.rad2deg(float(m[4])):.1f}"'
        ),
        text,
    )
    assert degrees != text
    path = tmp_path / "degrees.urdf"
    path.write_text(degrees)
    with pytest.raises(UrdfError, match=r"joint \[joint1\] has limits .* look like degrees"):
        Arm.from_urdf(path, "ft_sensor")
    zero = tmp_path / "zero_axis.urdf"
    zero.write_text(re.sub(r'<axis xyz="[^"]*"', '<axis xyz="0 0 0"', text, count=1))
    with pytest.raises(UrdfError, match=r"has axis xyz='0 0 0': expected a direction"):
        Arm.from_urdf(zero, "ft_sensor")
