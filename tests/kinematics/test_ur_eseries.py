"""UR e-Series, UR20 and UR30 from UR's DH parameters: hand-computed poses, an independent DH
product, the registry and the command line."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.model import WRENCH_CHANNELS
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.io.csv_table import write_csv
from ftkin.kinematics.record import KinematicsRecord
from ftkin.kinematics.robots import ROBOTS, flange_frame_name, load_robot
from ftkin.kinematics.ur_eseries import JOINT_NAMES, UR_DH, flange_rotation, ur_arm
from ftkin.sim.sensor import SimulatedSensor
from tests.robot.rtde_controller import DH, flange_transform

MODELS = ("ur3e", "ur5e", "ur10e", "ur16e", "ur20", "ur30")
RX90 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])


def test_the_six_arms_are_registered_with_ur_names():
    assert set(MODELS) <= set(ROBOTS) and set(UR_DH) == set(MODELS)
    for name in MODELS:
        arm = load_robot(name)
        assert arm.nq == 6 and arm.joint_names == list(JOINT_NAMES)
        assert arm.sensor_frame == "ft_sensor" and flange_frame_name(arm) == "tool0"
        assert arm.urdf_path is None and arm.robot_name == name


@pytest.mark.parametrize("name", MODELS)
def test_zero_pose_by_hand(name):
    """q = 0: the arm stretched along -x; tool0 at (a2 + a3, -(d4 + d6), d1 - d5), turned by
    +90° about x (z out of the flange along -y)."""
    d1, a2, a3, d4, d5, d6 = DH[name]
    rotation, position = load_robot(name).frame_placement(np.zeros(6), "tool0")
    np.testing.assert_allclose(position, [a2 + a3, -(d4 + d6), d1 - d5], atol=1e-12)
    np.testing.assert_allclose(rotation, RX90, atol=1e-12)


@pytest.mark.parametrize("name", MODELS)
def test_upright_pose_by_hand(name):
    """q = (0, -π/2, 0, -π/2, 0, 0): upper arm and forearm straight up; tool0 at
    (0, -(d4 + d6), d1 - a2 - a3 + d5), axes x = -x_B, y = -z_B, z = -y_B (worked through the
    six DH steps by hand)."""
    d1, a2, a3, d4, d5, d6 = DH[name]
    q = [0.0, -math.pi / 2, 0.0, -math.pi / 2, 0.0, 0.0]
    rotation, position = load_robot(name).frame_placement(q, "tool0")
    np.testing.assert_allclose(position, [0.0, -(d4 + d6), d1 - a2 - a3 + d5], atol=1e-12)
    expected = np.array([[-1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, -1.0, 0.0]])
    np.testing.assert_allclose(rotation, expected, atol=1e-12)


@pytest.mark.parametrize("name", MODELS)
def test_pinocchio_model_equals_the_dh_product(name, rng):
    """Random and near-singular configurations (wrist 2 at 0: wrists 1 and 3 aligned; elbow
    stretched), against the test helper's own numpy DH product."""
    arm = load_robot(name)
    configurations = [
        *arm.random_configurations(20, rng),
        [0.3, -1.0, 0.0, 0.4, 0.0, -2.0],
        [-6.28, 6.28, -3.14, 6.28, -6.28, 6.28],
    ]
    for q in configurations:
        expected = flange_transform(name, q)
        rotation, position = arm.frame_placement(q, "tool0")
        np.testing.assert_allclose(position, expected[:3, 3], atol=1e-12)
        np.testing.assert_allclose(rotation, expected[:3, :3], atol=1e-12)
        np.testing.assert_allclose(arm.rotation_sensor_to_base(q), expected[:3, :3], atol=1e-12)
    batch = arm.random_configurations(40, rng)  # the numpy batch path (RotationChain)
    expected = np.array([flange_transform(name, q)[:3, :3] for q in batch])
    np.testing.assert_allclose(arm.rotation_sensor_to_base(batch), expected, atol=1e-12)


def test_flange_rotation_is_the_same_for_every_model(rng):
    for q in rng.uniform(-6.0, 6.0, (10, 6)):
        for name in MODELS:
            np.testing.assert_allclose(
                flange_rotation(q), flange_transform(name, q)[:3, :3], atol=1e-12
            )
    with pytest.raises(InvalidInput, match="6 finite joint angles"):
        flange_rotation([0.0] * 5)
    with pytest.raises(InvalidInput, match="6 finite joint angles"):
        flange_rotation([0.0, 0.0, math.nan, 0.0, 0.0, 0.0])


def test_limits_follow_urs_description():
    arm = load_robot("ur5e")
    np.testing.assert_allclose(arm.upper_limits, [2 * math.pi] * 2 + [math.pi] + [2 * math.pi] * 3)
    np.testing.assert_allclose(arm.lower_limits, -arm.upper_limits)
    np.testing.assert_allclose(
        np.rad2deg(load_robot("ur20").velocity_limits), [120] * 2 + [150] + [210] * 3
    )


def test_sensor_offset_and_record_round_trip(rng):
    offset = [0.0, 0.0, 0.045, 0.0, 0.0, math.pi / 4]
    arm = load_robot("ur10e", offset)
    for q in arm.random_configurations(3, rng):
        flange = flange_transform("ur10e", q)
        rotation, position = arm.frame_placement(q, "sensor")
        turn = np.array([[math.cos(math.pi / 4), -math.sin(math.pi / 4), 0.0],
                         [math.sin(math.pi / 4), math.cos(math.pi / 4), 0.0],
                         [0.0, 0.0, 1.0]])  # fmt: skip
        np.testing.assert_allclose(rotation, flange[:3, :3] @ turn, atol=1e-12)
        np.testing.assert_allclose(position, flange[:3, 3] + flange[:3, 2] * 0.045, atol=1e-12)
    record = KinematicsRecord.from_dict(
        json.loads(json.dumps(KinematicsRecord.from_arm(arm).to_dict()))
    )
    assert record.robot == "ur10e" and record.urdf is None
    rebuilt = record.build_arm()
    assert not record.mismatches(rebuilt)
    assert record.mismatches(load_robot("ur10e"))  # the offset is part of the record


def test_unknown_ur_name():
    with pytest.raises(InvalidInput, match="known: ur3e, ur5e"):
        ur_arm("ur7e")


def test_no_collision_geometry_is_said_plainly():
    with pytest.raises(InvalidInput, match="not loaded from a URDF"):
        load_robot("ur5e").geometry("collision")


def test_calibrate_on_the_command_line_with_robot_ur5e(tmp_path, truth, rng, capsys):
    arm = load_robot("ur5e")
    q = arm.random_configurations(12, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 20)
    rows = np.column_stack([samples.joint_positions, samples.wrenches, samples.pose_ids])
    write_csv(tmp_path / "ur5e.csv", [*arm.joint_names, *WRENCH_CHANNELS, "pose"], rows.tolist())
    out = tmp_path / "calib.json"
    assert main(["calibrate", str(tmp_path / "ur5e.csv"), "--robot", "ur5e", "-o", str(out)]) == 0
    document = json.loads(out.read_text())
    assert document["kinematics"]["robot"] == "ur5e"
    direct = calibrate(samples)
    np.testing.assert_allclose(document["center_of_mass"], direct.center_of_mass, atol=1e-9)
    capsys.readouterr()
