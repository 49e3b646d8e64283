"""Export to ROS controller formats: parse back, check each value, and replay each peer's formula.

The peers' compensation formulas below are re-implemented from their sources
(see ftkin/export.py) independently of ftkin's Compensator, which serves as
the reference: after the exported parameters, each peer must produce ftkin's
contact wrench (up to what the format cannot represent).
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.model import SensorModel
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.io.calibration_file import save_calibration
from ftkin.io.export import export_notes, export_text
from ftkin.io.ros_controllers import urdf_root_link
from ftkin.sim.sensor import SimulatedSensor

yaml = pytest.importorskip("yaml")


def _rotations(rng, n=20):
    q, _ = np.linalg.qr(rng.standard_normal((n, 3, 3)))
    return q * np.sign(np.linalg.det(q))[:, None, None]


def _contact(model, rotations, raw):
    """ftkin's convention: contact = raw − bias − tool gravity (sensor frame)."""
    return raw - model.predict(rotations)


@pytest.fixture
def readings(truth, rng):
    rotations = _rotations(rng)
    contact = rng.normal(0, 5, (len(rotations), 6))
    raw = truth.predict(rotations) + contact
    return rotations, raw, contact


def test_admittance_values_and_controller_formula(truth, readings):
    level = SensorModel.from_tool(
        truth.tool_mass, truth.center_of_mass, truth.force_offset, truth.torque_offset, (0.0, 0.0)
    )
    params = yaml.safe_load(export_text(level, "admittance", frame_id="ati_sensor"))
    gc = params["admittance_controller"]["ros__parameters"]["gravity_compensation"]
    assert gc["frame"]["id"] == "ati_sensor"
    assert gc["CoG"]["pos"] == list(level.center_of_mass)
    assert gc["CoG"]["force"] == level.tool_weight > 0
    rotations, _, contact = readings
    raw = level.predict(rotations) + contact
    # admittance_rule_impl.hpp: weight = [0, 0, -force] in the world frame;
    # f_w = R f − weight, τ_w = R τ − (R pos) × weight (bias zeroed upstream).
    weight = np.array([0.0, 0.0, -gc["CoG"]["force"]])
    pos = np.array(gc["CoG"]["pos"])
    for rotation, reading, expected in zip(rotations, raw - level.bias, contact):
        force_world = rotation @ reading[:3] - weight
        torque_world = rotation @ reading[3:] - np.cross(rotation @ pos, weight)
        np.testing.assert_allclose(force_world, rotation @ expected[:3], atol=1e-9)
        np.testing.assert_allclose(torque_world, rotation @ expected[3:], atol=1e-9)


def test_gravity_compensation_filter_keeps_the_tilt(truth, readings):
    text = export_text(truth, "gravity-compensation", world_frame="world")
    params = yaml.safe_load(text)["/**"]["ros__parameters"]["sensor_filter_chain"]["filter1"]
    assert params["type"] == "control_filters/GravityCompensationWrench"
    p = params["params"]
    assert p["world_frame"] == "world" and p["sensor_frame"] == "ft_sensor"
    assert p["tool"]["CoG"] == list(truth.center_of_mass)
    assert p["tool"]["mass"] == truth.tool_mass
    field = np.array(p["tool"]["gravity_field"])
    np.testing.assert_allclose(np.linalg.norm(field), truth.g, rtol=1e-12)
    np.testing.assert_allclose(p["tool"]["mass"] * field, truth.gravity_in_base, rtol=1e-12)
    # gravity_compensation.cpp: f_s −= R_sw (mass·field); τ_s −= CoG × that (input already zeroed).
    rotations, raw, contact = readings
    for rotation, reading, expected in zip(rotations, raw - truth.bias, contact):
        force = rotation.T @ (p["tool"]["mass"] * field)
        np.testing.assert_allclose(reading[:3] - force, expected[:3], atol=1e-9)
        np.testing.assert_allclose(
            reading[3:] - np.cross(p["tool"]["CoG"], force), expected[3:], atol=1e-9
        )


def test_ft_calib_values_and_node_formula(truth, readings):
    params = yaml.safe_load(export_text(truth, "ft-calib"))
    assert set(params) == {
        "bias",
        "gripper_mass",
        "gripper_com_frame_id",
        "gripper_com_child_frame_id",
        "gripper_com_pose",
    }
    assert params["bias"] == list(truth.force_offset) + list(truth.torque_offset)
    assert params["gripper_mass"] == truth.tool_mass
    assert params["gripper_com_pose"] == list(truth.center_of_mass) + [0.0, 0.0, 0.0]
    # gravity_compensation.cpp (KTH): zeroed = raw − bias; compensated = zeroed − [m g_S; r × m
    # g_S],
    # g_S = gravity acceleration in the sensor frame; fed here with the tilted gravity a / m.
    g_base = truth.gravity_in_base / truth.tool_mass
    rotations, raw, contact = readings
    for rotation, reading, expected in zip(rotations, raw, contact):
        zeroed = reading - np.array(params["bias"])
        force = params["gripper_mass"] * rotation.T @ g_base
        torque = np.cross(params["gripper_com_pose"][:3], force)
        np.testing.assert_allclose(zeroed - np.concatenate([force, torque]), expected, atol=1e-9)


def test_notes_state_what_cannot_be_represented(truth):
    admittance = export_notes(truth, "admittance")
    assert any("no sensor bias" in note for note in admittance)
    assert any("base tilt" in note for note in admittance)
    assert not any("base tilt" in note for note in export_notes(truth, "gravity-compensation"))
    assert not any("bias" in note for note in export_notes(truth, "ft-calib"))
    level = SensorModel.from_tool(1.0, [0, 0, 0.1], [0, 0, 0], [0, 0, 0], (0.0, 0.0))
    assert not any("tilt" in note for note in export_notes(level, "ft-calib"))
    for note in admittance:
        assert "# NOTE: " + note in export_text(truth, "admittance")


def test_unknown_format(truth):
    with pytest.raises(InvalidInput, match="admittance, gravity-compensation, ft-calib"):
        export_text(truth, "yaml")


def test_bad_options_and_weightless_tool(truth):
    with pytest.raises(
        InvalidInput,
        match=r"ft-calib takes no node_name \(--node-name: --format admittance, "
        r"gravity-compensation\); its options: frame_id \(--frame-id\)",
    ):
        export_text(truth, "ft-calib", node_name="ft_node")
    weightless = SensorModel(
        truth.force_offset, truth.torque_offset, [0.0, 0.0, 0.0], truth.center_of_mass
    )
    with pytest.raises(InvalidInput, match="no tool weight"):
        export_text(weightless, "gravity-compensation")


@pytest.mark.parametrize(
    "options, message",
    [
        ({"frame_id": 'odd "frame"\\ with: colon'}, "--frame-id 'odd .* is not a valid ROS frame"),
        ({"frame_id": "/ft_sensor"}, "no leading '/'"),
        ({"frame_id": "ft__sensor"}, "no '__'"),
        ({"node_name": "2nd_node"}, "--node-name '2nd_node' is not a valid ROS node name"),
        ({"node_name": "admittance-controller"}, "not a valid ROS node name"),
    ],
)
def test_names_the_ros_side_would_reject_are_refused(truth, options, message):
    with pytest.raises(InvalidInput, match=message):
        export_text(truth, "admittance", **options)


def test_ros_names_that_are_valid_pass(truth):
    for node in ("admittance_controller", "/robot1/admittance_controller", "_private"):
        assert node in yaml.safe_load(export_text(truth, "admittance", node_name=node))
    text = export_text(truth, "gravity-compensation", frame_id="wrist/ft_sensor", world_frame="w")
    assert "wrist/ft_sensor" in text


def test_world_frame_from_urdf_root(arm):
    assert urdf_root_link(arm.urdf_path) == "base_link"
    assert urdf_root_link("/no/such.urdf") is None


@pytest.mark.parametrize("fmt", ["admittance", "gravity-compensation", "ft-calib"])
def test_cli_export(fmt, tmp_path, arm, truth, rng, capsys):
    q = arm.random_configurations(10, rng, margin=0.1)
    result = calibrate(
        SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 5)
    )
    calib = tmp_path / "calib.json"
    save_calibration(result, calib)
    out = tmp_path / "out.yaml"
    assert (
        main(["export", str(calib), "--format", fmt, "-o", str(out), "--frame-id", "wrist_ft"]) == 0
    )
    text = out.read_text()
    assert "wrist_ft" in text and yaml.safe_load(text)
    if fmt == "gravity-compensation":  # world frame taken from the calibration's URDF
        assert (
            yaml.safe_load(text)["/**"]["ros__parameters"]["sensor_filter_chain"]["filter1"][
                "params"
            ]["world_frame"]
            == "base_link"
        )
    printed = capsys.readouterr().out
    assert f"wrote {fmt}" in printed


def test_an_inertia_no_body_has_is_refused():
    """Principal moments 1, 1, 10 kg·m²: positive, symmetric, and impossible (10 > 1 + 1)."""
    from ftkin.io.payload_export import checked_inertia

    with pytest.raises(InvalidInput, match="triangle inequality"):
        checked_inertia([1.0, 1.0, 10.0, 0.0, 0.0, 0.0])
    rod = checked_inertia([0.5, 0.5, 1e-12, 0.0, 0.0, 0.0])  # a thin rod: on the boundary
    np.testing.assert_allclose(np.diag(rod), [0.5, 0.5, 1e-12], atol=0)
