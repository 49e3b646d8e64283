"""A calibration made in Python from joint angles records its arm, whichever fit made it (issue 37
item 3): static, with a mount, with a drifting bias, fused with the IMU, dynamic from joints.
Before, only the CLI and ``calibrate_on_robot`` recorded it, so a calibration made with
``calibrate(Samples.from_joint_positions(...))`` passed every later arm check.

The expectation is the arm the samples were read with: its robot name and its kinematics (no
difference from that arm, and the differences another arm has).
"""

from __future__ import annotations

import numpy as np
import pytest

import ftkin
from ftkin import Samples, calibrate, load_calibration, load_robot, save_calibration
from ftkin.calibration.fused_samples import FusedSamples
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.model import SensorModel
from ftkin.calibration.regressor import MotionSamples
from ftkin.cli import main
from ftkin.io.export import export_text
from ftkin.sim.sensor import SimulatedSensor, recording_times

NOISE = SensorNoise(0.02, 0.001)  # [N], [N·m]


@pytest.fixture(scope="module")
def poses(arm):
    return arm.random_configurations(12, np.random.default_rng(21), margin=0.3)


def static_samples(arm, tool, poses, **options) -> Samples:
    return SimulatedSensor(tool, NOISE).samples_at_configurations(
        arm, poses, np.random.default_rng(4), 5, **options
    )


def fused_samples(arm, tool, poses) -> Samples:
    """With an IMU aligned with the sensor frame: at rest it reads ``g`` upward, ``R_BSᵀ·(−ĝ)·g``
    (the weight's direction is down; hand-computed, not ftkin's IMU model)."""
    samples = static_samples(arm, tool, poses)
    up_in_base = -np.asarray(tool.gravity_in_base) / np.linalg.norm(tool.gravity_in_base)
    specific_force = tool.g * np.einsum("nji,j->ni", samples.rotations, up_in_base)
    noise = np.random.default_rng(6).normal(0.0, 0.01, specific_force.shape)  # [m/s²]
    return FusedSamples.from_arrays(samples, specific_force + noise)


def dynamic_samples(arm, tool) -> MotionSamples:
    """A slow sinusoidal motion of every joint (derivatives by hand), readings from MuJoCo
    (independent of ftkin's regressor)."""
    from ftkin.sim.mujoco.recording import MujocoRecorder, ToolInertia

    inertia = ToolInertia(tool.tool_mass, tool.center_of_mass, np.diag([0.006, 0.005, 0.002]))
    recorder = MujocoRecorder(joint_names=arm.joint_names, tool=inertia)
    times = np.arange(0.0, 6.0, 0.01)  # [s]
    middle = (arm.lower_limits + arm.upper_limits) / 2.0
    amplitude = np.full(arm.nq, 0.8)  # [rad], inside every joint's range
    omega = 2.0 * np.pi * np.linspace(0.2, 0.45, arm.nq)  # [rad/s], a frequency per joint
    phase = omega[None, :] * times[:, None]
    q = middle + amplitude * np.sin(phase)
    dq = amplitude * omega * np.cos(phase)
    ddq = -amplitude * omega**2 * np.sin(phase)
    wrenches = recorder.wrenches(q, dq, ddq)
    return MotionSamples.from_joint_trajectory(arm, q, dq, ddq, wrenches, times)


KINDS = ("static", "mount", "drift", "fused", "dynamic")


def calibration_of(kind, arm, tool, poses):
    if kind == "static":
        return calibrate(static_samples(arm, tool, poses))
    if kind == "mount":
        return calibrate(static_samples(arm, tool, poses), estimate_mount="yaw")
    if kind == "drift":
        times = recording_times(len(poses), 5, 600.0, 0.01)
        return calibrate(static_samples(arm, tool, poses, times=times), drift="poly:1")
    if kind == "fused":
        return calibrate(fused_samples(arm, tool, poses))
    return ftkin.calibrate_dynamic(dynamic_samples(arm, tool))


@pytest.mark.parametrize("kind", KINDS)
def test_every_calibration_from_joint_angles_records_its_arm(kind, arm, tool, poses, tmp_path):
    result = calibration_of(kind, arm, tool, poses)
    record = result.kinematics
    assert record is not None, kind
    assert record.robot == "ftkin_c4" and record.sensor_frame == "ft_sensor"
    assert record.joints == tuple(arm.joint_names)
    assert record.mismatches(arm) == []
    assert record.mismatches(load_robot("panda"))  # another arm differs
    loaded = load_calibration(save_calibration(result, tmp_path / "c.json"))
    assert loaded.kinematics == record  # and the file keeps it


def test_samples_from_orientations_record_no_arm(arm, tool, poses):
    samples = static_samples(arm, tool, poses)
    assert calibrate(Samples.from_rotations(samples.rotations, samples.wrenches)).kinematics is None


@pytest.fixture(scope="module")
def python_calibration(arm, tool, poses, tmp_path_factory):
    """``calibrate(Samples.from_joint_positions(Arm.default(), Q, W, ids))``, saved: the issue's
    steps."""
    clean = tool.predict(arm.rotation_sensor_to_base(poses))
    noisy = clean + np.random.default_rng(9).normal(size=clean.shape) * 0.01
    ids = np.arange(len(poses))
    result = calibrate(Samples.from_joint_positions(ftkin.Arm.default(), poses, noisy, ids))
    return result, save_calibration(result, tmp_path_factory.mktemp("c") / "calib.json")


def test_export_for_another_arm_refuses_a_calibration_made_in_python(
    python_calibration, tmp_path, capsys
):
    result, path = python_calibration
    out = tmp_path / "load.yaml"
    argv = ["export", str(path), "--robot", "panda", "--format", "franka-load", "-o", str(out)]
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert "not the one the calibration was made with (--robot ftkin_c4)" in error
    assert "7 joints (panda_joint1" in error and "calibrated with 6 (joint1" in error
    assert "Traceback" not in error and not out.exists()
    # the library refuses it the same way
    with pytest.raises(ftkin.InvalidInput, match="calibrated with 6"):
        export_text(result, "franka-load", load_robot("panda"))
    # a deliberate reuse is still possible
    assert main([*argv, "--allow-other-arm"]) == 0 and out.exists()


def test_compensator_defaults_to_the_recorded_arm(python_calibration, arm, tool, poses):
    result, _ = python_calibration
    compensator = ftkin.Compensator(result)  # no arm given: the calibration's own
    assert compensator.arm is not None and compensator.arm.robot_name == "ftkin_c4"
    raw = tool.predict(arm.rotation_sensor_to_base(poses[:1]))[0]
    expected = raw - result.predict(arm.rotation_sensor_to_base(poses[0]))  # contact = 0 + noise
    np.testing.assert_allclose(compensator.compensate(poses[0], raw), expected, atol=1e-12)
    with pytest.raises(ftkin.InvalidInput, match="calibrated with 6"):
        ftkin.Compensator(result, load_robot("panda"))


def test_a_model_without_a_record_keeps_no_arm(tool):
    compensator = ftkin.Compensator(SensorModel.from_vector(tool.to_vector(), tool.g))
    assert compensator.arm is None
    with pytest.raises(ftkin.InvalidInput, match="pass arm= to use joint angles"):
        compensator.compensate(np.zeros(6), np.zeros(6))


def test_a_record_that_cannot_be_rebuilt_leaves_the_compensator_without_arm(
    arm, tool, poses, tmp_path
):
    """A URDF deleted since: R_BS still works; joint angles say why there is no arm."""
    copy = tmp_path / "copy.urdf"
    copy.write_bytes(arm.urdf_path.read_bytes())
    moved = ftkin.Arm.from_urdf(copy, "ft_sensor")
    result = calibrate(static_samples(moved, tool, poses))
    assert result.kinematics.urdf == str(copy.resolve())
    copy.unlink()
    compensator = ftkin.Compensator(result)
    assert compensator.arm is None
    rotation = arm.rotation_sensor_to_base(poses[0])
    raw = tool.predict(rotation)
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotation, raw), raw - result.predict(rotation), atol=1e-12
    )
    with pytest.raises(ftkin.InvalidInput, match="cannot be rebuilt .*is not there any more"):
        compensator.compensate(poses[0], raw)


def test_a_payload_export_in_python_defaults_to_the_recorded_arm(tool):
    """A Panda with the sensor 3 cm out of the flange, axes as the flange's: the COM in
    panda_link8 is the sensor-frame COM plus 3 cm on z (by hand)."""
    import yaml

    panda = load_robot("panda", [0.0, 0.0, 0.03])
    q = panda.random_configurations(12, np.random.default_rng(32), margin=0.3)
    result = calibrate(
        Samples.from_joint_positions(panda, q, tool.predict(panda.rotation_sensor_to_base(q))),
        method="linear",
    )
    written = yaml.safe_load(export_text(result, "franka-load"))  # no arm given
    expected = np.asarray(result.center_of_mass) + [0.0, 0.0, 0.03]
    np.testing.assert_allclose(written["center_of_mass"], expected, rtol=0, atol=1e-9)
