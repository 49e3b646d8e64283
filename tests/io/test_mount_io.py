"""The mount, sign and flip in the calibration file; payload exports; wrench frames of bags."""

from __future__ import annotations

import json
import logging
import re
from types import SimpleNamespace

import numpy as np
import pytest

from ftkin import (
    CalibrationFileError,
    Samples,
    SensorNoise,
    calibrate,
    load_calibration,
    load_robot,
    save_calibration,
)
from ftkin.calibration.conventions import reading_signs
from ftkin.calibration.mount import exp_so3
from ftkin.cli import main
from ftkin.io import export_payload, payload_in_flange
from ftkin.io.wrench_frames import wrenches_in_sensor_frame

yaml = pytest.importorskip("yaml")

NOISE = SensorNoise(0.02, 0.002)
MOUNT = exp_so3([0.02, -0.03, np.deg2rad(35.0)])


@pytest.fixture(scope="module")
def mounted(arm, tool):
    """A full-mount calibration with a reversed z axis and reversed sign, and its samples."""
    rng = np.random.default_rng(21)
    q = arm.random_configurations(14, rng, margin=0.3)
    clean = tool.predict(arm.rotation_sensor_to_base(q) @ MOUNT.T)
    raw = (clean + rng.normal(size=clean.shape) * NOISE.channel_std) * reading_signs(-1, "x")
    samples = Samples.from_joint_positions(arm, q, raw)
    return calibrate(
        samples, estimate_mount="full", noise=NOISE, sensor_sign=-1, flip_axis="x"
    ), samples


def test_file_round_trip_keeps_mount_sign_and_flip(mounted, tmp_path):
    result, _ = mounted
    path = save_calibration(result, tmp_path / "calib.json")
    document = json.loads(path.read_text())
    np.testing.assert_array_equal(document["mount_rotation"], result.mount_rotation)
    assert document["mount_rpy_deg"] == pytest.approx(list(result.mount_rpy_deg))
    assert (
        document["sensor_sign"] == -1
        and document["flip_axis"] == "x"
        and document["mount_mode"] == "full"
    )
    loaded = load_calibration(path)
    np.testing.assert_array_equal(loaded.mount_rotation, result.mount_rotation)
    np.testing.assert_array_equal(loaded.mount_covariance, result.mount_covariance)
    assert (loaded.sensor_sign, loaded.flip_axis, loaded.mount_mode) == (-1, "x", "full")
    assert loaded.mount_std_deg == pytest.approx(result.mount_std_deg)


def test_old_file_loads_with_identity_mount_and_plus_sign(mounted, tmp_path):
    result, _ = mounted
    document = json.loads(save_calibration(result, tmp_path / "calib.json").read_text())
    for key in (
        "mount_rotation",
        "mount_rpy_deg",
        "mount_mode",
        "mount_covariance",
        "mount_std_deg",
        "sensor_sign",
        "flip_axis",
    ):
        del document[key]
    (tmp_path / "old.json").write_text(json.dumps(document))
    old = load_calibration(tmp_path / "old.json")
    np.testing.assert_array_equal(old.mount_rotation, np.eye(3))
    assert (old.sensor_sign, old.flip_axis, old.mount_mode, old.has_mount) == (
        1,
        None,
        "none",
        False,
    )


def test_file_with_a_reflection_is_refused(mounted, tmp_path):
    result, _ = mounted
    document = json.loads(save_calibration(result, tmp_path / "calib.json").read_text())
    document["mount_rotation"] = np.diag([1.0, -1.0, 1.0]).tolist()
    (tmp_path / "bad.json").write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="det = \\+1"):
        load_calibration(tmp_path / "bad.json")


def _com_in_flange_by_kinematics(arm, calibration, flange):
    """Hand computation through forward kinematics at a random pose: P_F = R_BFᵀ (R_BS_real P + p_S
    − p_F).
    """
    q = arm.random_configurations(1, np.random.default_rng(0))[0]
    rotation_flange, origin_flange = arm.frame_placement(q, flange)
    rotation_sensor, origin_sensor = arm.frame_placement(q, "sensor")
    real = rotation_sensor @ calibration.mount_rotation.T
    return rotation_flange.T @ (real @ calibration.center_of_mass + origin_sensor - origin_flange)


def test_franka_load_parsed_back_matches_hand_computation(mounted, arm, tmp_path):
    result, _ = mounted
    inertia = [0.02, 0.025, 0.03, 0.001, 0.0, -0.002]  # a body's (triangle inequality)
    path = export_payload(
        result, arm, tmp_path / "load.yaml", "franka-load", flange_frame="flange", inertia=inertia
    )
    request = yaml.safe_load(path.read_text())
    assert set(request) == {"mass", "center_of_mass", "load_inertia"}
    assert request["mass"] == pytest.approx(
        np.linalg.norm(result.gravity_in_base) / result.g, rel=1e-12
    )
    np.testing.assert_allclose(
        request["center_of_mass"], _com_in_flange_by_kinematics(arm, result, "flange"), atol=1e-12
    )
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    column_major = [ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz]
    np.testing.assert_allclose(request["load_inertia"], column_major)


def test_ur_payload_on_ur5_parsed_back(tool, tmp_path):
    ur5 = load_robot("ur5", [0.0, 0.0, 0.02])  # sensor 2 cm out of tool0
    rng = np.random.default_rng(22)
    q = ur5.random_configurations(12, rng, margin=0.3)
    clean = tool.predict(ur5.rotation_sensor_to_base(q) @ MOUNT.T)
    samples = Samples.from_joint_positions(
        ur5, q, clean + rng.normal(size=clean.shape) * NOISE.channel_std
    )
    result = calibrate(samples, estimate_mount="full", noise=NOISE)
    expected = _com_in_flange_by_kinematics(ur5, result, "tool0")
    request = yaml.safe_load(
        export_payload(result, ur5, tmp_path / "payload.yaml", "ur-payload").read_text()
    )
    assert request["mass"] == pytest.approx(result.tool_mass, rel=1e-12)
    np.testing.assert_allclose(
        [request["center_of_gravity"][k] for k in "xyz"], expected, atol=1e-12
    )
    script = export_payload(result, ur5, tmp_path / "payload.script", "ur-payload").read_text()
    match = re.search(r"set_payload\(([^,]+), \[([^\]]+)\]\)", script)
    assert float(match.group(1)) == pytest.approx(result.tool_mass, rel=1e-12)
    np.testing.assert_allclose([float(v) for v in match.group(2).split(",")], expected, atol=1e-12)
    # the truth, through the mount: within a few standard errors of the COM
    truth = _com_in_flange_by_kinematics(
        ur5, SimpleNamespace(mount_rotation=MOUNT, center_of_mass=tool.center_of_mass), "tool0"
    )
    assert np.all(np.abs(expected - truth) < 5e-4)
    # without the mount the COM lands elsewhere: the mount matters
    assert np.linalg.norm(payload_in_flange(tool, ur5).center_of_mass - truth) > 5e-3


def test_cli_exports_payloads(mounted, tmp_path, capsys):
    result, _ = mounted
    calib = save_calibration(result, tmp_path / "calib.json")
    franka = ["export", str(calib), "--format", "franka-load", "-o", str(tmp_path / "f.yaml")]
    # the bundled arm is no Franka: its flange is named, never assumed
    assert main(franka) == 2
    assert "--flange-frame" in capsys.readouterr().err
    assert main([*franka, "--flange-frame", "flange"]) == 0
    assert "flange frame 'flange'" in capsys.readouterr().out
    assert "load_inertia" in yaml.safe_load((tmp_path / "f.yaml").read_text())
    ur = ["export", str(calib), "--format", "ur-payload", "-o", str(tmp_path / "u.yaml")]
    assert main([*ur, "--flange-frame", "flange"]) == 0


def test_base_frame_wrenches_are_converted(arm, caplog):
    rng = np.random.default_rng(23)
    rotations = arm.rotation_sensor_to_base(arm.random_configurations(5, rng))
    in_sensor = rng.normal(size=(5, 6))
    in_base = np.concatenate(
        [
            np.einsum("nij,nj->ni", rotations, in_sensor[:, :3]),
            np.einsum("nij,nj->ni", rotations, in_sensor[:, 3:]),
        ],
        axis=1,
    )
    converted = wrenches_in_sensor_frame(in_base, rotations, "base_link", arm, "base")
    np.testing.assert_allclose(converted, in_sensor, atol=1e-12)
    with caplog.at_level(logging.WARNING):
        same = wrenches_in_sensor_frame(in_base, rotations, "base_link", arm)
    assert same is in_base and "--wrench-frame base" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        wrenches_in_sensor_frame(in_sensor, rotations, "ft_link", arm)
    assert "'ft_link' is not the arm's sensor frame 'ft_sensor'" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        wrenches_in_sensor_frame(in_sensor, rotations, "ft_sensor", arm)
    assert caplog.text == ""


def test_ros_exports_note_the_mount_and_the_sign(mounted):
    from ftkin.io.export import export_notes

    result, _ = mounted
    notes = " ".join(export_notes(result, "admittance"))
    assert "estimated mount" in notes and "sensor_sign -1 and the x axis reversed" in notes


def test_franka_load_takes_a_dynamic_calibrations_inertia_into_flange_axes(mounted, arm, tmp_path):
    """The inertia of a dynamic calibration (sensor axes) is exported in flange axes: I_F = R I_S Rᵀ
    by FK.
    """
    import dataclasses

    from ftkin import DynamicCalibrationResult

    result, _ = mounted
    inertia_in_sensor = np.array(
        [[0.012, 0.001, -0.002], [0.001, 0.02, 0.0005], [-0.002, 0.0005, 0.03]]
    )
    fields = {f.name: getattr(result, f.name) for f in dataclasses.fields(result)}
    fields["inertia_about_com_in_sensor"] = inertia_in_sensor
    dynamic = DynamicCalibrationResult(**fields)
    request = yaml.safe_load(
        export_payload(
            dynamic, arm, tmp_path / "load.yaml", "franka-load", flange_frame="flange"
        ).read_text()
    )
    q = arm.random_configurations(1, np.random.default_rng(3))[0]
    rotation_flange, _ = arm.frame_placement(q, "flange")
    rotation_sensor, _ = arm.frame_placement(q, "sensor")
    sensor_to_flange = rotation_flange.T @ rotation_sensor @ result.mount_rotation.T
    expected = sensor_to_flange @ inertia_in_sensor @ sensor_to_flange.T
    np.testing.assert_allclose(
        np.reshape(request["load_inertia"], (3, 3), order="F"), expected, atol=1e-12
    )


def test_ur_payload_with_an_inertia_is_set_target_payload(tool, tmp_path):
    """A known inertia (a dynamic calibration's, or --inertia) goes into URScript's
    set_target_payload(mass, cog, [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]) in flange axes, about the
    centre of gravity; without one, set_payload and a note."""
    import dataclasses

    from ftkin import DynamicCalibrationResult
    from ftkin.calibration.result import CalibrationResult

    ur5 = load_robot("ur5", [0.0, 0.0, 0.02])  # sensor axes = tool0 axes, 2 cm out
    base = CalibrationResult(
        tool.force_offset, tool.torque_offset, tool.gravity_in_base, tool.center_of_mass
    )
    inertia = np.array([[0.012, 0.001, -0.002], [0.001, 0.02, 0.0005], [-0.002, 0.0005, 0.03]])
    fields = {f.name: getattr(base, f.name) for f in dataclasses.fields(base)}
    fields["inertia_about_com_in_sensor"] = inertia
    dynamic = DynamicCalibrationResult(**fields)
    script = export_payload(dynamic, ur5, tmp_path / "p.script", "ur-payload").read_text()
    match = re.search(r"set_target_payload\(([^,]+), \[([^\]]+)\], \[([^\]]+)\]\)", script)
    assert match, script
    terms = [float(v) for v in match.group(3).split(",")]
    expected = [
        inertia[0, 0],
        inertia[1, 1],
        inertia[2, 2],
        inertia[0, 1],
        inertia[0, 2],
        inertia[1, 2],
    ]
    np.testing.assert_allclose(terms, expected, atol=1e-15)
    cog = [float(v) for v in match.group(2).split(",")]
    np.testing.assert_allclose(cog, tool.center_of_mass + [0.0, 0.0, 0.02], atol=1e-12)
    plain = export_payload(base, ur5, tmp_path / "q.script", "ur-payload").read_text()
    assert "set_payload(" in plain and "set_target_payload" not in plain
