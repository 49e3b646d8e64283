"""Robots by name: example-robot-data arms with a sensor frame at the flange."""

from __future__ import annotations

import importlib.metadata
import json

import numpy as np
import pinocchio as pin
import pytest

from ftkin import calibrate
from ftkin.calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
)
from ftkin.calibration.model import WRENCH_CHANNELS
from ftkin.cli import main
from ftkin.exceptions import FrameNotFound, InvalidInput, MissingDependency
from ftkin.io.calibration_file import load_calibration
from ftkin.io.csv_table import write_csv
from ftkin.kinematics.robots import (
    DEFAULT_ROBOT,
    ROBOT_SPECS,
    ROBOTS,
    example_robot_data_share,
    flange_frame_name,
    load_robot,
)
from ftkin.sim.sensor import SimulatedSensor

READINGS = 20


def _predicted_sigma(truth, rotations, noise):
    information = fisher_information(truth, rotations, noise, READINGS)
    return np.sqrt(np.diag(covariance_from_information(information)))


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_round_trip_by_name(name, truth, rng):
    arm = load_robot(name)
    q = arm.random_configurations(12, rng, margin=0.05)
    noise = SensorNoise.paper()
    samples = SimulatedSensor(truth, noise).samples_at_configurations(arm, q, rng, READINGS)
    result = calibrate(samples)
    sigma = _predicted_sigma(truth, arm.rotation_sensor_to_base(q), noise)
    error = result.to_vector() - truth.to_vector()
    assert np.all(np.abs(error) < 5 * sigma + 1e-12), (error, sigma)
    assert result.urdf == str(arm.urdf_path)


def test_panda_fingers_locked_and_sensor_at_link8(rng):
    arm = load_robot("panda")
    assert arm.nq == 7
    assert arm.joint_names == [f"panda_joint{i}" for i in range(1, 8)]
    q = arm.random_configurations(3, rng)
    for configuration in q:
        rotation, position = arm.frame_placement(configuration, "sensor")
        flange_rotation, flange_position = arm.frame_placement(configuration, "panda_link8")
        np.testing.assert_allclose(rotation, flange_rotation, atol=1e-12)
        np.testing.assert_allclose(position, flange_position, atol=1e-12)


def test_ur5_sensor_offset_composes_with_tool0(rng):
    offset = [0.01, -0.02, 0.035, 0.1, -0.2, 0.3]
    arm = load_robot("ur5", offset)
    assert arm.nq == 6 and arm.sensor_frame == "ft_sensor"
    # Independent composition: tool0 placement times the URDF-rpy offset.
    mount = pin.SE3(pin.rpy.rpyToMatrix(*offset[3:]), np.array(offset[:3]))
    for configuration in arm.random_configurations(4, rng):
        flange_rotation, flange_position = arm.frame_placement(configuration, "tool0")
        rotation, position = arm.frame_placement(configuration, "sensor")
        np.testing.assert_allclose(rotation, flange_rotation @ mount.rotation, atol=1e-12)
        np.testing.assert_allclose(
            position, flange_position + flange_rotation @ mount.translation, atol=1e-12
        )


def test_every_registered_robot_loads():
    for name in ROBOTS:
        arm = load_robot(name)
        assert arm.sensor_frame == ("fr3_hand" if name == "fr3" else "ft_sensor")
        assert arm.model.nq == arm.model.nv >= 6
        assert arm.robot_name == name
        # every robot by name knows its flange, a frame of its own model
        assert flange_frame_name(arm) in arm.frame_names


def test_meshes_resolve_through_share_folder():
    arm = load_robot("ur5")
    assert arm.package_dirs == [str(example_robot_data_share())]
    assert arm.geometry("collision").ngeoms > 0


def test_unknown_robot_lists_known_names():
    with pytest.raises(InvalidInput, match="known robots: .*panda.*ur5"):
        load_robot("ur6")


def test_bad_offset_and_offset_on_bundled_arm():
    with pytest.raises(InvalidInput, match="3 numbers"):
        load_robot("ur5", [0.0, 0.1])
    with pytest.raises(InvalidInput, match="sensor offset must be numeric"):
        load_robot("ur5", ["a", "b", "c"])
    with pytest.raises(InvalidInput, match="3 numbers"):
        load_robot("ur5", [0.0, 0.1, float("nan")])
    with pytest.raises(InvalidInput, match="already has its ft_sensor"):
        load_robot(DEFAULT_ROBOT, [0.0, 0.0, 0.1])


def test_tool_frame_by_name():
    assert load_robot(DEFAULT_ROBOT).tool_frame == "tool"
    assert load_robot("ur5").tool_frame is None
    arm = load_robot("ur5", [0.0, 0.0, 0.05], tool_frame="tool0")
    q = np.zeros(arm.nq)
    # the sensor sits 5 cm out along the flange z; the tool frame is the flange itself
    _, sensor = arm.frame_placement(q, "sensor")
    rotation, flange = arm.frame_placement(q, "tool")
    np.testing.assert_allclose(sensor - flange, rotation @ [0.0, 0.0, 0.05], atol=1e-12)
    with pytest.raises(FrameNotFound, match="'no_such_frame' not found"):
        load_robot("ur5", tool_frame="no_such_frame")


def test_missing_example_robot_data(monkeypatch):
    def missing(name):
        raise importlib.metadata.PackageNotFoundError(name)

    example_robot_data_share.cache_clear()
    monkeypatch.setattr(importlib.metadata, "distribution", missing)
    try:
        with pytest.raises(MissingDependency, match=r"example-robot-data.*ftkin\[robots\]"):
            load_robot("ur5")
    finally:
        monkeypatch.undo()
        example_robot_data_share.cache_clear()


def test_cli_calibrate_with_robot_and_offset(tmp_path, truth, rng):
    offset = [0.0, 0.0, 0.02, 0.0, 0.0, 0.5]
    arm = load_robot("ur10", offset)
    q = arm.random_configurations(10, rng, margin=0.05)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 5)
    csv_path = tmp_path / "ur10.csv"
    header = ["pose", *arm.joint_names, *WRENCH_CHANNELS]
    rows = [
        [int(p), *map(float, c), *map(float, w)]
        for p, c, w in zip(samples.pose_ids, samples.joint_positions, samples.wrenches)
    ]
    write_csv(csv_path, header, rows)
    out = tmp_path / "calib.json"
    args = [
        "calibrate",
        str(csv_path),
        "--robot",
        "ur10",
        "--sensor-offset",
        *map(str, offset),
        "-o",
        str(out),
    ]
    assert main(args) == 0
    loaded = load_calibration(out)
    np.testing.assert_allclose(loaded.tool_weight, truth.tool_weight, atol=0.05)
    # Without the offset's yaw the sensor axes are wrong: the model no longer fits.
    assert main(["calibrate", str(csv_path), "--robot", "ur10", "-o", str(out)]) == 0
    wrong = load_calibration(out)
    assert wrong.residual_rms[:3].max() > 10 * loaded.residual_rms[:3].max()


def test_cli_report_and_view_read_samples_with_the_calibration_robot(tmp_path, truth, rng, capsys):
    pytest.importorskip("matplotlib")
    pytest.importorskip("meshcat")
    arm = load_robot("ur5")
    q = arm.random_configurations(8, rng, margin=0.05)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 3)
    csv_path = tmp_path / "ur5.csv"
    rows = [
        [int(p), *map(float, c), *map(float, w)]
        for p, c, w in zip(samples.pose_ids, samples.joint_positions, samples.wrenches)
    ]
    write_csv(csv_path, ["pose", *[f"q{i + 1}" for i in range(arm.nq)], *WRENCH_CHANNELS], rows)
    calib = tmp_path / "calib.json"
    assert main(["calibrate", str(csv_path), "--robot", "ur5", "-o", str(calib)]) == 0
    capsys.readouterr()
    # the calibration file records --robot ur5: report and view need no robot options repeated
    assert main(["report", str(calib), str(csv_path), "-o", str(tmp_path / "r0.png")]) == 0
    assert main(["view", str(calib), str(csv_path), "--html", str(tmp_path / "v.html")]) == 0
    capsys.readouterr()
    # a file without that record (older ftkin): q1..q6 fit the bundled arm too, the UR5 is not
    # silently swapped for it
    document = json.loads(calib.read_text())
    del document["kinematics"]
    calib.write_text(json.dumps(document))
    for command in (
        ["report", str(calib), str(csv_path), "-o", str(tmp_path / "r.png")],
        ["view", str(calib), str(csv_path), "--no-wait"],
    ):
        assert main(command) == 2
        error = capsys.readouterr().err
        assert (
            error.startswith("ftkin: error: the calibration was made with")
            and "same robot options" in error
        )
        assert "--robot ur5" in error  # the recorded URDF names the robot to give
    assert (
        main(["report", str(calib), str(csv_path), "-o", str(tmp_path / "r.png"), "--robot", "ur5"])
        == 0
    )


def test_cli_offset_errors(capsys):
    assert main(["calibrate", "x.csv", "--sensor-offset", "0", "0", "0.1"]) == 2
    assert "needs --robot" in capsys.readouterr().err
    assert main(["calibrate", "x.csv", "--robot", "ur5", "--sensor-offset", "0", "0.1"]) == 2
    assert "3 numbers" in capsys.readouterr().err


def test_specs_name_existing_flange_frames():
    for spec in ROBOT_SPECS.values():
        arm = load_robot(spec.name)
        assert spec.flange_frame in arm.frame_names
