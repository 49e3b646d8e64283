"""Batched numpy forward kinematics (RotationChain) against Pinocchio, one configuration at a
time.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import ftkin
from ftkin import Arm, Compensator
from ftkin.kinematics.chain import RotationChain
from ftkin.sim.sensor import paper_like_truth


def _pinocchio_rotations(model, frame_id, configurations):
    data = model.createData()
    out = []
    for q in configurations:
        pin.forwardKinematics(model, data, q)
        out.append(pin.updateFramePlacement(model, data, frame_id).rotation.copy())
    return np.array(out)


@pytest.mark.parametrize("name", ["bundled", "ur5"])
def test_batched_rotations_equal_pinocchio(name, rng):
    arm = Arm.default() if name == "bundled" else ftkin.load_robot("ur5")
    configurations = rng.uniform(-2 * np.pi, 2 * np.pi, size=(300, arm.nq))
    expected = _pinocchio_rotations(arm.model, arm.sensor_frame_id, configurations)
    chain = RotationChain.from_model(arm.model, arm.sensor_frame_id)
    assert chain is not None
    np.testing.assert_allclose(chain.rotations(configurations), expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        arm.rotation_sensor_to_base(configurations), expected, rtol=0, atol=1e-12
    )
    tool = arm.tool_frame_id if arm.tool_frame_id is not None else arm.sensor_frame_id
    np.testing.assert_allclose(
        RotationChain.from_model(arm.model, tool).rotations(configurations),
        _pinocchio_rotations(arm.model, tool, configurations),
        rtol=0,
        atol=1e-12,
    )


def _mixed_chain():
    """Revolute about a tilted axis, prismatic along another, RX, PZ, placements with rotations."""
    model = pin.Model()
    placements = [
        pin.SE3(pin.rpy.rpyToMatrix(0.3, -0.2, 0.9), np.array([0.1, 0.0, 0.2])) for _ in range(4)
    ]
    joints = [
        pin.JointModelRevoluteUnaligned(np.array([0.0, 0.6, 0.8])),
        pin.JointModelPrismaticUnaligned(np.array([1.0, 2.0, 2.0]) / 3.0),
        pin.JointModelRX(),
        pin.JointModelPZ(),
    ]
    parent = 0
    for i, (joint, placement) in enumerate(zip(joints, placements)):
        parent = model.addJoint(parent, joint, placement, f"j{i}")
    frame = model.addFrame(
        pin.Frame(
            "sensor",
            parent,
            0,
            pin.SE3(pin.rpy.rpyToMatrix(1.0, 0.5, -0.4), np.zeros(3)),
            pin.FrameType.OP_FRAME,
        )
    )
    return model, frame


def test_revolute_and_prismatic_axes_of_any_direction(rng):
    model, frame = _mixed_chain()
    configurations = rng.uniform(-3.0, 3.0, size=(200, model.nq))
    chain = RotationChain.from_model(model, frame)
    np.testing.assert_allclose(
        chain.rotations(configurations),
        _pinocchio_rotations(model, frame, configurations),
        rtol=0,
        atol=1e-12,
    )


def test_other_joint_kinds_fall_back_to_pinocchio():
    model = pin.Model()
    joint = model.addJoint(0, pin.JointModelTranslation(), pin.SE3.Identity(), "slider")
    joint = model.addJoint(joint, pin.JointModelRZ(), pin.SE3.Identity(), "spin")
    frame = model.addFrame(
        pin.Frame("sensor", joint, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME)
    )
    assert RotationChain.from_model(model, frame) is None


def test_log_compensation_from_joint_angles_equals_row_by_row(arm, rng):
    truth = paper_like_truth()
    compensator = Compensator(truth, arm)
    q = arm.random_configurations(500, rng)
    raw = truth.predict(_pinocchio_rotations(arm.model, arm.sensor_frame_id, q)) + rng.normal(
        size=(500, 6)
    )
    rows = np.array([compensator.compensate(x, w) for x, w in zip(q, raw)])
    np.testing.assert_allclose(compensator.compensate_batch(q, raw), rows, rtol=0, atol=1e-12)


def test_cos_sin_table_equals_numpy_to_a_few_ulp(rng):
    from ftkin.kinematics.chain import _cos_sin

    angles = np.concatenate(
        [
            rng.uniform(-60.0, 60.0, 5000),
            np.arange(-8, 9) * np.pi / 4,
            np.arange(-3, 4) * np.pi / 4096 + 0.5 * np.pi / 2048,
            [0.0, -0.0, 9999.5],
        ]
    )
    cos, sin = _cos_sin(angles.reshape(2, -1) if angles.size % 2 == 0 else angles)
    np.testing.assert_allclose(cos.ravel(), np.cos(angles), rtol=0, atol=2e-15)
    np.testing.assert_allclose(sin.ravel(), np.sin(angles), rtol=0, atol=2e-15)
    wide = np.array(
        [1e5, -3e7, np.nan, 1.0]
    )  # beyond the table's range, and NaN: numpy's functions
    cos, sin = _cos_sin(wide)
    np.testing.assert_allclose(cos, np.cos(wide), rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sin, np.sin(wide), rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("name", ["bundled", "ur5", "mixed"])
def test_vector_in_sensor_frame_equals_pinocchio_over_several_blocks(name, rng):
    from ftkin.kinematics.chain import VECTOR_BLOCK

    if name == "mixed":
        model, frame = _mixed_chain()
    else:
        arm = Arm.default() if name == "bundled" else ftkin.load_robot("ur5")
        model, frame = arm.model, arm.sensor_frame_id
    configurations = rng.uniform(
        -20.0, 20.0, size=(VECTOR_BLOCK + 37, model.nq)
    )  # a full block and a short one
    vector = np.array([0.4, -1.2, -9.3])
    expected = np.einsum("nji,j->ni", _pinocchio_rotations(model, frame, configurations), vector)
    got = RotationChain.from_model(model, frame).transposed_times(configurations, vector)
    assert got.shape == (len(configurations), 3)
    np.testing.assert_allclose(got, expected, rtol=0, atol=1e-12)
