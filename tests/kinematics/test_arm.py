"""Arm kinematics against independent computations; URDF loading errors."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin import Arm, SensorMount
from ftkin.kinematics import bundled_urdf_path

TOOL_DOWN = np.array([0.0, 0.0, -0.5236, 0.0, -1.0472, 0.0])


# ------------------------------------------------------------ independent FK
def _rpy_matrix(rpy):
    # URDF: R = Rz(yaw) Ry(pitch) Rx(roll) = extrinsic x-y-z
    return Rotation.from_euler("xyz", rpy).as_matrix()


def _axis_angle(axis, angle):
    return Rotation.from_rotvec(
        np.asarray(axis, dtype=float) / np.linalg.norm(axis) * angle
    ).as_matrix()


def _hand_chain_rotation(urdf_path, q_by_joint, tip="ft_sensor", root="base_link"):
    """R_root_tip from the URDF's joint origins and axes, parsed with xml.etree."""
    joints = {}
    for joint in ET.parse(urdf_path).getroot().iter("joint"):
        origin = joint.find("origin")
        axis = joint.find("axis")
        joints[joint.find("child").get("link")] = {
            "name": joint.get("name"),
            "type": joint.get("type"),
            "parent": joint.find("parent").get("link"),
            "xyz": np.array(
                [
                    float(v)
                    for v in (origin.get("xyz", "0 0 0") if origin is not None else "0 0 0").split()
                ]
            ),
            "rpy": np.array(
                [
                    float(v)
                    for v in (origin.get("rpy", "0 0 0") if origin is not None else "0 0 0").split()
                ]
            ),
            "axis": np.array(
                [float(v) for v in (axis.get("xyz") if axis is not None else "1 0 0").split()]
            ),
        }
    rotation, translation = np.eye(3), np.zeros(3)
    link = tip
    while link != root:
        joint = joints[link]
        local = _rpy_matrix(joint["rpy"])
        if joint["type"] in ("revolute", "continuous"):
            local = local @ _axis_angle(joint["axis"], q_by_joint[joint["name"]])
        # prepend the joint's transform: T = T_origin · T_axis(q) · T
        translation = joint["xyz"] + local @ translation
        rotation = local @ rotation
        link = joint["parent"]
    return rotation, translation


def test_sensor_rotation_matches_yourdfpy(arm, rng):
    yourdfpy = pytest.importorskip("yourdfpy")
    robot = yourdfpy.URDF.load(str(bundled_urdf_path()))
    assert list(robot.actuated_joint_names) == arm.joint_names
    for q in arm.random_configurations(20, rng):
        robot.update_cfg(q)
        transform = robot.get_transform("ft_sensor", "base_link")
        np.testing.assert_allclose(arm.rotation_sensor_to_base(q), transform[:3, :3], atol=1e-12)
        rotation, position = arm.frame_placement(q, "sensor")
        np.testing.assert_allclose(rotation, transform[:3, :3], atol=1e-12)
        np.testing.assert_allclose(position, transform[:3, 3], atol=1e-12)


def test_sensor_and_tool_placement_match_hand_built_chain(arm, rng):
    for q in arm.random_configurations(20, rng):
        q_by_joint = dict(zip(arm.joint_names, q))
        for frame, name in (("sensor", "ft_sensor"), ("tool", "tool"), ("link3", "link3")):
            rotation, position = _hand_chain_rotation(bundled_urdf_path(), q_by_joint, tip=name)
            ours_rotation, ours_position = arm.frame_placement(q, frame)
            np.testing.assert_allclose(ours_rotation, rotation, atol=1e-12)
            np.testing.assert_allclose(ours_position, position, atol=1e-12)


def test_tool_down_pose_has_sensor_z_down(arm):
    expected = _axis_angle([0, 0, 1], np.pi / 2) @ _axis_angle([1, 0, 0], np.pi)
    np.testing.assert_allclose(arm.rotation_sensor_to_base(TOOL_DOWN), expected, atol=1e-4)


def test_batch_equals_singles(arm, rng):
    configurations = arm.random_configurations(7, rng)
    batch = arm.rotation_sensor_to_base(configurations)
    assert batch.shape == (7, 3, 3)
    for q, rotation in zip(configurations, batch):
        single = arm.rotation_sensor_to_base(q)
        assert single.shape == (3, 3)
        np.testing.assert_allclose(single, rotation, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(
            arm.sensor_rotation_unchecked(q), rotation, rtol=1e-12, atol=1e-15
        )


def test_mounted_batch_equals_singles_after_the_chain_was_built(arm, rng):
    # regression: mounted_arm copied the arm's batch chain, built for the URDF sensor frame
    from ftkin.kinematics import mounted_arm

    q = arm.random_configurations(20, rng)
    arm.rotation_sensor_to_base(q)  # builds the arm's batch chain
    mount = Rotation.from_euler("zyx", [0.1, 0.2, 0.3]).as_matrix()
    mounted = mounted_arm(arm, mount)
    singles = np.array([mounted.rotation_sensor_to_base(row) for row in q])
    np.testing.assert_allclose(mounted.rotation_sensor_to_base(q), singles, atol=1e-12)
    np.testing.assert_allclose(singles, arm.rotation_sensor_to_base(q) @ mount.T, atol=1e-12)


def test_random_configurations_respect_limits_and_margin(arm, rng):
    configurations = arm.random_configurations(500, rng, margin=0.2)
    assert configurations.shape == (500, arm.nq)
    assert np.all(configurations >= arm.lower_limits + 0.2)
    assert np.all(configurations <= arm.upper_limits - 0.2)


@pytest.mark.parametrize(
    ("q", "pattern"),
    [
        (np.zeros(5), r"shape \(6,\) or \(N, 6\)"),
        (np.zeros((2, 7)), r"shape \(6,\) or \(N, 6\)"),
        ([0, 0, np.nan, 0, 0, 0], "finite.*nan"),
        ("abc", "numeric"),
    ],
)
def test_bad_configurations_are_refused(arm, q, pattern):
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        arm.rotation_sensor_to_base(q)


def test_bad_configuration_for_jacobian_and_placement(arm):
    with pytest.raises(
        ftkin.InvalidInput, match=r"joint positions q \(joints joint1.*shape \(6,\)"
    ):
        arm.jacobian(np.zeros(4))
    with pytest.raises(ftkin.InvalidInput, match="finite"):
        arm.frame_placement([np.inf, 0, 0, 0, 0, 0])


# ---------------------------------------------------------------- Jacobians
def _finite_difference_jacobian(arm, q, frame, reference, step=1e-6):
    jac = np.empty((6, arm.nq))
    rotation, position = arm.frame_placement(q, frame)
    for j in range(arm.nq):
        dq = np.zeros(arm.nq)
        dq[j] = step
        rot_plus, pos_plus = arm.frame_placement(pin.integrate(arm.model, q, dq), frame)
        rot_minus, pos_minus = arm.frame_placement(pin.integrate(arm.model, q, -dq), frame)
        linear = (pos_plus - pos_minus) / (2 * step)
        # angular velocity in base axes from the relative rotation R+ R-^T
        angular = pin.log3(rot_plus @ rot_minus.T) / (2 * step)
        if reference == "local":
            linear, angular = rotation.T @ linear, rotation.T @ angular
        elif reference == "world":
            linear = linear - np.cross(angular, position)
        jac[:3, j], jac[3:, j] = linear, angular
    return jac


@pytest.mark.parametrize("reference", ["local_world_aligned", "local", "world"])
@pytest.mark.parametrize("frame", ["sensor", "tool", "link4"])
def test_jacobian_matches_finite_differences(arm, rng, frame, reference):
    for q in arm.random_configurations(5, rng, margin=0.1):
        analytic = arm.jacobian(q, frame=frame, reference=reference)
        assert analytic.shape == (6, arm.nq)
        numeric = _finite_difference_jacobian(arm, q, frame, reference)
        np.testing.assert_allclose(analytic, numeric, atol=1e-8)


def test_jacobian_default_is_sensor_local_world_aligned(arm):
    q = TOOL_DOWN + 0.1
    np.testing.assert_allclose(
        arm.jacobian(q), arm.jacobian(q, "sensor", "local_world_aligned"), rtol=1e-12, atol=1e-15
    )
    # the returned array must not alias Pinocchio's buffer
    first = arm.jacobian(q, "sensor").copy()
    arm.jacobian(q + 0.3, "tool")
    np.testing.assert_allclose(arm.jacobian(q, "sensor"), first, rtol=1e-12, atol=1e-15)


def test_unknown_reference_is_refused(arm):
    with pytest.raises(ftkin.InvalidInput, match="reference must be one of.*'local_world_aligned'"):
        arm.jacobian(TOOL_DOWN, reference="base")


# -------------------------------------------------------------- frame names
def test_unknown_frame_lists_available(arm):
    with pytest.raises(ftkin.FrameNotFound, match="'ft_sensr' not found.*ft_sensor.*tool") as info:
        arm.frame_placement(TOOL_DOWN, "ft_sensr")
    assert info.value.name == "ft_sensr"
    assert "ft_sensor" in info.value.available and "base_link" in info.value.available
    with pytest.raises(ftkin.FrameNotFound, match="gripper"):
        arm.jacobian(TOOL_DOWN, frame="nope")


def test_unknown_sensor_frame_at_load_lists_available():
    with pytest.raises(ftkin.FrameNotFound, match="'force_sensor' not found.*ft_sensor"):
        Arm.from_urdf(bundled_urdf_path(), "force_sensor")
    with pytest.raises(ftkin.FrameNotFound, match="'tcp' not found"):
        Arm.from_urdf(bundled_urdf_path(), "ft_sensor", "tcp")


def test_tool_frame_missing_is_explained():
    arm = Arm.default(tool_frame=None)
    with pytest.raises(ftkin.InvalidInput, match="no tool frame"):
        arm.jacobian(TOOL_DOWN, frame="tool")


# ------------------------------------------------------------- sensor mount
def test_sensor_mount_is_parent_placement_times_offset(arm, rng):
    translation, rpy = np.array([0.01, -0.02, 0.035]), np.array([0.1, -0.25, 0.4])
    mounted = Arm.from_urdf(
        bundled_urdf_path(), "my_sensor", sensor_mount=SensorMount("flange", translation, rpy)
    )
    offset_rotation = _rpy_matrix(rpy)
    frame = mounted.model.frames[mounted.sensor_frame_id]
    parent_id = mounted.model.getFrameId("flange")
    assert frame.parentFrame == parent_id
    assert (
        frame.parentJoint
        == mounted.model.frames[parent_id].parentJoint
        == mounted.model.getJointId("joint6")
    )
    for q in arm.random_configurations(10, rng):
        parent_rotation, parent_position = mounted.frame_placement(q, "flange")
        rotation, position = mounted.frame_placement(q, "sensor")
        np.testing.assert_allclose(rotation, parent_rotation @ offset_rotation, atol=1e-13)
        np.testing.assert_allclose(
            position, parent_position + parent_rotation @ translation, atol=1e-13
        )
        np.testing.assert_allclose(mounted.rotation_sensor_to_base(q), rotation, atol=0)


def test_sensor_mount_reproduces_the_urdf_sensor_frame(arm, rng):
    # the URDF's ft_sensor_joint: xyz 0 0 0.02, rpy 0 0 pi/2 from flange
    mounted = Arm.from_urdf(
        bundled_urdf_path(),
        "copy",
        sensor_mount=SensorMount("flange", (0, 0, 0.02), (0, 0, 1.570796327)),
    )
    for q in arm.random_configurations(5, rng):
        np.testing.assert_allclose(
            mounted.frame_placement(q)[0], arm.frame_placement(q)[0], atol=1e-14
        )
        np.testing.assert_allclose(
            mounted.frame_placement(q)[1], arm.frame_placement(q)[1], atol=1e-14
        )


def test_sensor_mount_errors():
    with pytest.raises(ftkin.FrameNotFound, match="'flang' not found.*flange"):
        Arm.from_urdf(bundled_urdf_path(), "s", sensor_mount=SensorMount("flang"))
    with pytest.raises(ftkin.InvalidInput, match="'ft_sensor' already exists"):
        Arm.from_urdf(bundled_urdf_path(), "ft_sensor", sensor_mount=SensorMount("flange"))
    with pytest.raises(ftkin.InvalidInput, match=r"translation must have shape \(3,\)"):
        Arm.from_urdf(bundled_urdf_path(), "s", sensor_mount=SensorMount("flange", (0.0, 0.1)))
    with pytest.raises(ftkin.InvalidInput, match="rpy must be finite"):
        Arm.from_urdf(
            bundled_urdf_path(), "s", sensor_mount=SensorMount("flange", rpy=(0, np.nan, 0))
        )


# ------------------------------------------------------------ locked joints
def test_locked_joint_removed_from_q(arm, rng):
    locked = Arm.from_urdf(bundled_urdf_path(), "ft_sensor", "tool", locked_joints={"joint6": 0.7})
    assert locked.nq == 5
    assert locked.joint_names == arm.joint_names[:5]
    for q in arm.random_configurations(5, rng):
        q[5] = 0.7
        np.testing.assert_allclose(
            locked.rotation_sensor_to_base(q[:5]), arm.rotation_sensor_to_base(q), atol=1e-14
        )
        np.testing.assert_allclose(
            locked.frame_placement(q[:5], "tool")[1], arm.frame_placement(q, "tool")[1], atol=1e-14
        )


def test_locked_joint_geometry_matches_reduced_model():
    locked = Arm.from_urdf(bundled_urdf_path(), "ft_sensor", locked_joints={"joint2": 0.1})
    geometry = locked.geometry("collision")
    assert geometry.ngeoms > 0
    # every geometry's parent joint exists in the reduced model
    assert all(obj.parentJoint < locked.model.njoints for obj in geometry.geometryObjects)


def test_locking_an_unknown_joint_lists_joints():
    with pytest.raises(ftkin.InvalidInput, match="cannot lock joint 'joint9'.*joint1, joint2"):
        Arm.from_urdf(bundled_urdf_path(), locked_joints={"joint9": 0.0})


# ---------------------------------------------------------------- geometry
def test_bundled_geometry_has_no_meshes_and_is_cached(arm):
    collision = arm.geometry("collision")
    assert collision.ngeoms > 0
    assert arm.geometry("collision") is collision
    assert arm.geometry("visual").ngeoms > 0
    with pytest.raises(ftkin.InvalidInput, match="'collision' or 'visual'"):
        arm.geometry("mesh")


# ------------------------------------------------------------- URDF errors
LIMIT = '<limit lower="-1" upper="1" effort="1" velocity="1"/>'


def _urdf(links: str, joints: str) -> str:
    return f'<?xml version="1.0"?>\n<robot name="r">\n{links}\n{joints}\n</robot>\n'


GOOD_LINKS = '  <link name="base"/>\n  <link name="l1"/>'
GOOD_JOINT = (
    f'  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>'
    f'<axis xyz="0 0 1"/>{LIMIT}</joint>'
)


def _write(tmp_path, text, name="robot.urdf"):
    path = tmp_path / name
    path.write_text(text)
    return path


def test_small_valid_urdf_loads(tmp_path):
    arm = Arm.from_urdf(_write(tmp_path, _urdf(GOOD_LINKS, GOOD_JOINT)), "l1")
    assert arm.nq == 1
    np.testing.assert_allclose(
        arm.rotation_sensor_to_base([0.3]), _axis_angle([0, 0, 1], 0.3), atol=1e-15
    )


def test_missing_file(tmp_path):
    path = tmp_path / "absent.urdf"
    with pytest.raises(ftkin.UrdfError, match="absent.urdf: file not found") as info:
        Arm.from_urdf(path)
    assert info.value.path == str(path)


def test_broken_xml_names_line(tmp_path):
    path = _write(
        tmp_path, '<?xml version="1.0"?>\n<robot name="r">\n  <link name="base">\n</robot>\n'
    )
    with pytest.raises(ftkin.UrdfError, match="not well-formed XML at line 4"):
        Arm.from_urdf(path, "base")


def test_wrong_root_element(tmp_path):
    path = _write(tmp_path, '<?xml version="1.0"?>\n<sdf version="1.6"><model name="m"/></sdf>\n')
    with pytest.raises(ftkin.UrdfError, match=r"root element is <sdf>, expected <robot>"):
        Arm.from_urdf(path)


def test_joint_referencing_missing_link(tmp_path):
    joint = GOOD_JOINT.replace('child link="l1"', 'child link="nowhere"')
    path = _write(tmp_path, _urdf(GOOD_LINKS, joint))
    with pytest.raises(ftkin.UrdfError, match=r"nowhere.*j1|j1.*nowhere") as info:
        Arm.from_urdf(path, "l1")
    assert str(path) in str(info.value)
    assert "does not contain a valid URDF model" not in str(info.value)


def test_continuous_joint_is_explained(tmp_path):
    joint = GOOD_JOINT.replace('type="revolute"', 'type="continuous"')
    path = _write(tmp_path, _urdf(GOOD_LINKS, joint))
    with pytest.raises(ftkin.InvalidInput, match="one coordinate per joint.*continuous"):
        Arm.from_urdf(path, "l1")
    arm = Arm.from_urdf(path, "l1", locked_joints={"j1": 0.0})
    assert arm.nq == 0


def test_missing_mesh_detected_when_geometry_requested(tmp_path):
    links = (
        '  <link name="base"><collision><geometry><mesh '
        'filename="meshes/base.stl"/></geometry></collision>'
        '<visual><geometry><mesh filename="meshes/base.stl"/></geometry></visual></link>\n  <link '
        'name="l1"/>'
    )
    path = _write(tmp_path, _urdf(links, GOOD_JOINT))
    arm = Arm.from_urdf(path, "l1")  # kinematics need no meshes
    assert arm.nq == 1
    for kind in ("collision", "visual"):
        with pytest.raises(ftkin.UrdfError, match="meshes/base.stl") as info:
            arm.geometry(kind)
        assert info.value.path == str(path.resolve())


@pytest.mark.parametrize(
    ("change", "pattern"),
    [
        (
            lambda links, joint: (links, joint.replace('type="revolute"', 'type="revolut"')),
            r"no known type \[revolut\]",
        ),
        (
            lambda links, joint: (links, joint.replace('<parent link="base"/>', "")),
            r"\[j1\] is missing a parent",
        ),
        (lambda links, joint: (links + '\n  <link name="l1"/>', joint), "link 'l1' is not unique"),
        (
            lambda links, joint: (links, joint.replace(LIMIT, "")),
            "REVOLUTE but it does not specify limits",
        ),
    ],
)
def test_pinocchio_refusals_carry_the_parser_reason(tmp_path, change, pattern):
    path = _write(tmp_path, _urdf(*change(GOOD_LINKS, GOOD_JOINT)))
    with pytest.raises(ftkin.UrdfError, match=pattern) as info:
        Arm.from_urdf(path, "l1")
    # regression: the parser's own source locations ("at line 262 in model.cpp") read like URDF
    # lines
    assert ".cpp" not in str(info.value)
    assert all(reason.strip() for reason in info.value.reasons)


def test_sensor_mount_with_locked_joints(arm, rng):
    mounted = Arm.from_urdf(
        bundled_urdf_path(),
        "copy",
        sensor_mount=SensorMount("flange", (0, 0, 0.02), (0, 0, 1.570796327)),
        locked_joints={"joint6": 0.3},
    )
    for q in arm.random_configurations(5, rng):
        q[5] = 0.3
        np.testing.assert_allclose(
            mounted.rotation_sensor_to_base(q[:5]), arm.rotation_sensor_to_base(q), atol=1e-14
        )
