"""The mount, sign and flip at run time: Compensator and JointAdmittance see the real sensor."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, CalibrationResult, Compensator, JointAdmittance, Samples
from ftkin.calibration.conventions import reading_signs
from ftkin.calibration.mount import exp_so3
from ftkin.kinematics import mounted_arm

MOUNT = exp_so3([0.04, -0.02, np.deg2rad(-50.0)])


@pytest.fixture(scope="module")
def mounted_truth(tool):
    """The true sensor as a calibration: mount, reversed sign and reversed y axis."""
    return CalibrationResult(
        tool.force_offset,
        tool.torque_offset,
        tool.gravity_in_base,
        tool.center_of_mass,
        mount_rotation=MOUNT,
        mount_mode="full",
        sensor_sign=-1,
        flip_axis="y",
    )


def _raw(arm, tool, q, contact):
    """What the sensor outputs: (load on the real sensor + contact) with its sign and mirrored
    axis.
    """
    real = arm.rotation_sensor_to_base(q) @ MOUNT.T
    return (tool.predict(real) + contact) * reading_signs(-1, "y")


def test_compensator_recovers_the_contact(arm, tool, mounted_truth):
    rng = np.random.default_rng(31)
    q = arm.random_configurations(6, rng)
    contact = rng.normal(size=(6, 6))
    raw = _raw(arm, tool, q, contact)
    compensator = Compensator(mounted_truth, arm)
    for k in range(len(q)):
        np.testing.assert_allclose(compensator.compensate(q[k], raw[k]), contact[k], atol=1e-12)
    np.testing.assert_allclose(compensator.compensate_batch(q, raw), contact, atol=1e-12)
    np.testing.assert_allclose(
        compensator.compensate_samples(Samples.from_joint_positions(arm, q, raw)),
        contact,
        atol=1e-12,
    )
    real = arm.rotation_sensor_to_base(q) @ MOUNT.T
    np.testing.assert_allclose(compensator.compensate_batch(real, raw), contact, atol=1e-12)
    assert getattr(arm, "mount_rotation", None) is None  # the caller's arm is untouched


def test_plain_calibration_keeps_the_fast_path(arm, tool):
    compensator = Compensator(tool, arm)
    assert compensator.arm is arm
    assert "compensate_unchecked" not in vars(compensator)


def test_joint_admittance_uses_the_real_sensor_frame(arm, tool, mounted_truth):
    rng = np.random.default_rng(32)
    q = arm.random_configurations(1, rng, margin=0.4)[0]
    contact = np.array([1.0, -2.0, 3.0, 0.1, 0.2, -0.1])
    controller = JointAdmittance(arm, Admittance(k2=0.001), Compensator(mounted_truth, arm))
    np.testing.assert_allclose(
        controller.arm.rotation_sensor_to_base(q),
        arm.rotation_sensor_to_base(q) @ MOUNT.T,
        atol=1e-14,
    )
    controller.step(q, _raw(arm, tool, q, contact), 0.001)
    np.testing.assert_allclose(controller.last_status.contact_wrench, contact, atol=1e-12)
    # the same command as a controller on an arm mounted by hand, fed corrected readings of a
    # mount-free model
    reference = JointAdmittance(mounted_arm(arm, MOUNT), Admittance(k2=0.001), Compensator(tool))
    expected = reference.step(
        q, tool.predict(arm.rotation_sensor_to_base(q) @ MOUNT.T) + contact, 0.001
    )
    np.testing.assert_allclose(controller.last_status.dq, expected, atol=1e-12)
