"""Sign and handedness: a reversed sign or axis is named; a ceiling mount calibrates when stated."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Samples, SensorModel, SensorNoise, calibrate
from ftkin.calibration import detect_sign_and_handedness
from ftkin.calibration.conventions import reading_signs
from ftkin.calibration.mount import exp_so3
from ftkin.exceptions import SuspectConvention

NOISE = SensorNoise(0.02, 0.002)


@pytest.fixture(scope="module")
def poses(arm):
    rng = np.random.default_rng(11)
    q = arm.random_configurations(12, rng, margin=0.3)
    return q, arm.rotation_sensor_to_base(q)


def _samples(arm, q, rotations, model, factors, seed=0, mount=None):
    rng = np.random.default_rng(seed)
    clean = model.predict(rotations if mount is None else rotations @ mount.T)
    return Samples.from_joint_positions(
        arm, q, (clean + rng.normal(size=clean.shape) * NOISE.channel_std) * factors
    )


def test_reading_signs_by_hand():
    np.testing.assert_array_equal(reading_signs(), np.ones(6))
    np.testing.assert_array_equal(reading_signs(-1), -np.ones(6))
    np.testing.assert_array_equal(reading_signs(1, "y"), [1, -1, 1, 1, -1, 1])
    np.testing.assert_array_equal(reading_signs(-1, "z"), [-1, -1, 1, -1, -1, 1])
    with pytest.raises(ValueError, match="sensor_sign"):
        reading_signs(0)
    with pytest.raises(ValueError, match="flip_axis"):
        reading_signs(1, "w")


def test_reversed_sign_is_named_and_fixed(arm, poses, tool):
    q, rotations = poses
    samples = _samples(arm, q, rotations, tool, -np.ones(6))
    with pytest.raises(SuspectConvention) as caught:
        calibrate(samples, noise=NOISE)
    message = str(caught.value)
    assert (
        "--sensor-sign -1" in message
        and "--base-mount ceiling" in message
        and "reaction" in message
    )
    assert caught.value.sensor_sign == -1 and caught.value.flip_axis is None
    result = calibrate(samples, noise=NOISE, sensor_sign=-1)
    assert result.sensor_sign == -1
    assert np.all(
        np.abs(result.gravity_in_base - tool.gravity_in_base)
        < 3 * result.std_errors["gravity_in_base"]
    )


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_reversed_axis_is_named_and_fixed(arm, poses, tool, axis):
    q, rotations = poses
    samples = _samples(arm, q, rotations, tool, reading_signs(1, axis))
    with pytest.raises(
        SuspectConvention, match=f"the sensor's {axis} axis reversed: --flip-axis {axis}"
    ) as caught:
        calibrate(samples, noise=NOISE)
    assert caught.value.flip_axis == axis
    result = calibrate(samples, noise=NOISE, flip_axis=axis)
    assert np.all(
        np.abs(result.center_of_mass - tool.center_of_mass)
        < 3 * result.std_errors["center_of_mass"]
    )


def test_reversed_axis_with_a_yaw_mount_names_x_and_y(arm, poses, tool):
    q, rotations = poses
    samples = _samples(
        arm, q, rotations, tool, reading_signs(1, "y"), mount=exp_so3([0.0, 0.0, 0.5])
    )
    check = detect_sign_and_handedness(samples, estimate_mount="yaw")
    assert check.flip_suspected and {check.best_flip, *check.equivalent_flips} == {"x", "y"}
    with pytest.raises(SuspectConvention, match="180° about z"):
        calibrate(samples, estimate_mount="yaw", noise=NOISE)


def test_ceiling_mount_calibrates_when_stated(arm, poses, tool):
    q, rotations = poses
    hanging = SensorModel(
        tool.force_offset, tool.torque_offset, -tool.gravity_in_base, tool.center_of_mass
    )
    samples = _samples(arm, q, rotations, hanging, np.ones(6))
    with pytest.raises(SuspectConvention, match="ceiling"):
        calibrate(samples, noise=NOISE)
    result = calibrate(samples, noise=NOISE, base_mount="ceiling")
    assert result.gravity_in_base[2] > 0 and result.sensor_sign == 1
    assert calibrate(samples, noise=NOISE, expected_gravity=[0, 0, 1]).tool_weight == pytest.approx(
        result.tool_weight
    )
    calibrate(samples, noise=NOISE, base_mount="wall")  # no direction to check against


def test_correct_convention_raises_nothing(arm, poses, tool):
    q, rotations = poses
    check = detect_sign_and_handedness(_samples(arm, q, rotations, tool, np.ones(6)))
    assert not check.flip_suspected and not check.sign_suspected
    assert check.best_flip is None and check.gravity_angle_deg < 1.0
