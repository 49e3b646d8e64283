"""The export registry: a new format from this file alone, the arm checks, flange frames from the
robot table.
"""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

from ftkin import Samples, SensorNoise, calibrate, load_robot, save_calibration
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.io import payload_in_flange
from ftkin.io.export import EXPORT_FORMATS, export_text, register_export_format
from ftkin.io.export_format import ExportFormat, ExportOption, ExportRequest
from ftkin.kinematics.record import KinematicsRecord
from ftkin.kinematics.robots import ROBOT_SPECS, flange_frame_name

yaml = pytest.importorskip("yaml")


class ToolJson(ExportFormat):
    """A format made up for the test: the tool as JSON, rounded to ``--digits``."""

    name = "tool-json"
    summary = "the tool's mass [kg] and centre of mass [m, sensor frame] as JSON"
    options = (
        ExportOption("digits", "--digits", "decimals written", {"type": int, "metavar": "N"}),
    )

    def document(self, request: ExportRequest) -> dict:
        digits = request.option("digits", 6)
        calibration = request.calibration
        return {
            "mass": round(float(calibration.tool_mass), digits),
            "com": [round(float(v), digits) for v in calibration.center_of_mass],
        }

    def text(self, request: ExportRequest) -> str:
        return json.dumps(self.document(request)) + "\n"


@pytest.fixture
def tool_json():
    """``tool-json`` registered for the test, removed after it."""
    yield register_export_format(ToolJson())
    del EXPORT_FORMATS[ToolJson.name]


@pytest.fixture(scope="module")
def calibration_file(tmp_path_factory, tool):
    """A calibration of ``tool`` on the bundled arm, saved."""
    from ftkin import Arm

    arm = Arm.default()
    rng = np.random.default_rng(31)
    q = arm.random_configurations(12, rng, margin=0.3)
    clean = tool.predict(arm.rotation_sensor_to_base(q))
    noise = SensorNoise(0.02, 0.002)
    result = calibrate(
        Samples.from_joint_positions(arm, q, clean + rng.normal(size=clean.shape) * 0.002),
        noise=noise,
    )
    return result, save_calibration(result, tmp_path_factory.mktemp("calib") / "calib.json")


def test_a_format_registered_from_a_test_file_is_a_cli_choice(
    tool_json, calibration_file, tmp_path, capsys
):
    result, path = calibration_file
    out = tmp_path / "tool.json"
    assert (
        main(["export", str(path), "--format", "tool-json", "-o", str(out), "--digits", "3"]) == 0
    )
    written = json.loads(out.read_text())
    assert written["mass"] == round(float(result.tool_mass), 3)  # the same rounding: exact
    np.testing.assert_allclose(written["com"], result.center_of_mass, atol=5e-4)
    assert "wrote tool-json to" in capsys.readouterr().out
    # the option is the format's own: another format refuses it
    assert main(["export", str(path), "--format", "ft-calib", "-o", str(out), "--digits", "3"]) == 2
    assert "ft-calib takes no digits (--digits: --format tool-json); its options: frame_id" in (
        capsys.readouterr().err
    )


def test_registry_refuses_a_taken_name_and_a_non_format(tool_json):
    with pytest.raises(InvalidInput, match="'tool-json' is already registered"):
        register_export_format(ToolJson())
    with pytest.raises(InvalidInput, match="must be an ExportFormat instance, got ABCMeta"):
        register_export_format(ToolJson)
    with pytest.raises(InvalidInput, match="unknown export format 'yaml'; expected one of adm"):
        export_text(None, "yaml")


@pytest.fixture(scope="module")
def panda_calibration(tmp_path_factory, tool):
    """A calibration made on a Panda with the sensor 3 cm out of the flange, with its record."""
    panda = load_robot("panda", [0.0, 0.0, 0.03])
    rng = np.random.default_rng(32)
    q = panda.random_configurations(12, rng, margin=0.3)
    clean = tool.predict(panda.rotation_sensor_to_base(q))
    result = calibrate(
        Samples.from_joint_positions(panda, q, clean + rng.normal(size=clean.shape) * 0.002),
        noise=SensorNoise(0.02, 0.002),
    )
    result = dataclasses.replace(result, kinematics=KinematicsRecord.from_arm(panda))
    return result, panda, save_calibration(result, tmp_path_factory.mktemp("p") / "panda.json")


def test_export_refuses_another_arm_like_compensate(panda_calibration, tmp_path, capsys):
    _, _, path = panda_calibration
    out = tmp_path / "load.yaml"
    command = ["export", str(path), "--format", "franka-load", "-o", str(out)]
    assert main([*command, "--robot", "ur5"]) == 2
    error = capsys.readouterr().err
    assert "not the one the calibration was made with (--robot panda --sensor-offset" in error
    assert "robot 'ur5', calibrated with 'panda'" in error and "--allow-other-arm" in error
    assert not out.exists()
    # a deliberate reuse on a UR: its own controller's format, in its flange tool0
    ur = ["export", str(path), "--format", "ur-payload", "-o", str(out), "--robot", "ur5"]
    assert main([*ur, "--allow-other-arm"]) == 0
    assert "flange frame 'tool0'" in capsys.readouterr().out
    # a Franka payload for a UR arm is refused, naming --flange-frame
    assert main([*command, "--robot", "ur5", "--allow-other-arm"]) == 2
    assert "--flange-frame" in capsys.readouterr().err
    # the ROS formats check the arm too when one is named
    ros = ["export", str(path), "--format", "ft-calib", "-o", str(tmp_path / "f.yaml")]
    assert main([*ros, "--robot", "ur5"]) == 2


def test_export_that_omits_the_recorded_sensor_offset_is_refused(
    panda_calibration, tmp_path, capsys
):
    result, panda, path = panda_calibration
    out = tmp_path / "load.yaml"
    command = ["export", str(path), "--format", "franka-load", "-o", str(out)]
    assert main([*command, "--robot", "panda"]) == 2
    error = capsys.readouterr().err
    assert "recorded the sensor offset --sensor-offset 0 0 0.03 0 0 0 on panda_link8" in error
    assert "the centre of mass would be off by 30.0 mm" in error and not out.exists()
    # the same options, or none (the arm rebuilt from the record): the COM through the offset
    for options in (["--robot", "panda", "--sensor-offset", "0", "0", "0.03"], []):
        assert main([*command, *options]) == 0
        com = yaml.safe_load(out.read_text())["center_of_mass"]
        expected = np.asarray(result.center_of_mass) + [0.0, 0.0, 0.03]  # flange axes = sensor's
        np.testing.assert_allclose(com, expected, rtol=0, atol=1e-12)
    # the library refuses it the same way
    with pytest.raises(InvalidInput, match="off by 30.0 mm"):
        export_text(result, "franka-load", load_robot("panda"))
    assert export_text(result, "franka-load", panda)


@pytest.mark.parametrize("name", sorted(ROBOT_SPECS))
def test_flange_frames_come_from_the_robot_table(name, tool):
    arm = load_robot(name)
    assert flange_frame_name(arm) == ROBOT_SPECS[name].flange_frame
    payload = payload_in_flange(tool, arm)
    assert payload.flange_frame == ROBOT_SPECS[name].flange_frame
    np.testing.assert_allclose(payload.center_of_mass, tool.center_of_mass, atol=1e-12)


def test_a_urdf_arms_flange_is_the_controllers_rule_or_refused(tool):
    """Never guessed: an arm from a URDF gets its flange from the payload's controller rule
    (Franka: <prefix>_link8, UR: tool0); without a controller, or with no such frame, it is
    refused naming --flange-frame."""
    from ftkin import Arm
    from ftkin.kinematics.fr3 import fr3_urdf_path

    fr3 = Arm.from_urdf(fr3_urdf_path(), "fr3_hand")  # not loaded by name
    assert flange_frame_name(fr3, "franka") == "fr3_link8"
    with pytest.raises(InvalidInput, match="--flange-frame"):
        flange_frame_name(fr3)
    with pytest.raises(InvalidInput, match="no such frame.*--flange-frame"):
        flange_frame_name(fr3, "ur")
    with pytest.raises(InvalidInput, match="--flange-frame"):
        payload_in_flange(tool, Arm.from_urdf(fr3_urdf_path(), "fr3_hand"))
    # the hand frame is the flange turned by −45° about z: the centre of mass turns with it
    payload = payload_in_flange(tool, fr3, controller="franka")
    c, s = np.cos(-np.pi / 4), np.sin(-np.pi / 4)
    hand_to_flange = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    np.testing.assert_allclose(
        payload.center_of_mass, hand_to_flange @ tool.center_of_mass, atol=1e-12
    )


def test_export_without_a_recorded_arm_is_refused(tmp_path, capsys, tool):
    """A calibration made from orientations records no arm: a payload needs one named."""
    from ftkin.calibration.result import CalibrationResult

    result = CalibrationResult(
        tool.force_offset, tool.torque_offset, tool.gravity_in_base, tool.center_of_mass
    )
    path = save_calibration(result, tmp_path / "no-arm.json")
    out = tmp_path / "load.yaml"
    command = ["export", str(path), "--format", "franka-load", "-o", str(out)]
    assert main(command) == 2
    assert "records none" in capsys.readouterr().err and not out.exists()
    assert main([*command, "--robot", "fr3"]) == 0
    assert "'fr3_link8'" in capsys.readouterr().out


@pytest.mark.parametrize(
    "kind, good, bad",
    [
        ("node", ["a", "_b1", "/ns/node", "/**"], ["", "1a", "a-b", "a__b", "/ns/", "a b", 3]),
        ("frame", ["base_link", "robot1/tool0"], ["/base_link", "a//b", "tool0/", "0link", "a.b"]),
        ("topic", ["/ft/wrench", "wrench"], ["//x", "x/", "/1x", "x__y"]),
    ],
)
def test_ros_name_rules(kind, good, bad):
    from ftkin.validation import as_ros_name

    for name in good:
        assert as_ros_name(name, kind, "name") == name
    for name in bad:
        with pytest.raises(InvalidInput, match=f"ROS {kind} name"):
            as_ros_name(name, kind, "name")


def test_cli_refuses_a_bad_ros_name_before_writing(calibration_file, tmp_path, capsys):
    _, path = calibration_file
    out = tmp_path / "a.yaml"
    command = ["export", str(path), "--format", "admittance", "-o", str(out)]
    assert main([*command, "--node-name", "admittance controller"]) == 2
    assert "--node-name 'admittance controller' is not a valid ROS node name" in (
        capsys.readouterr().err
    )
    assert main([*command, "--frame-id", "/ft_sensor"]) == 2
    assert "no leading '/'" in capsys.readouterr().err and not out.exists()
