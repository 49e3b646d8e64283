"""Compensation: a known contact wrench comes back out, on every entry point."""

from __future__ import annotations

import numpy as np
import pytest

import ftkin
from ftkin import Compensator, SensorModel


@pytest.fixture
def poses(arm, rng):
    """Random configurations, their sensor orientations, contact wrenches and raw readings."""
    configurations = arm.random_configurations(25, rng)
    rotations = arm.rotation_sensor_to_base(configurations)
    contact = rng.normal(scale=[5, 5, 5, 0.3, 0.3, 0.3], size=(25, 6))
    return configurations, rotations, contact


def _by_hand(model, rotation, raw):
    """Independent METHOD.md §4 with np.cross: F' = F - F0 - Rᵀa, M' = M - M0 - P × Rᵀa."""
    gravity_in_sensor = rotation.T @ model.gravity_in_base
    force = raw[:3] - model.force_offset - gravity_in_sensor
    torque = raw[3:] - model.torque_offset - np.cross(model.center_of_mass, gravity_in_sensor)
    return np.concatenate([force, torque])


def test_known_contact_is_recovered_on_every_entry_point(arm, truth, poses):
    configurations, rotations, contact = poses
    raw = truth.predict(rotations) + contact
    compensator = Compensator(truth, arm)
    from_q = np.array([compensator.compensate(q, w) for q, w in zip(configurations, raw)])
    from_rotation = np.array(
        [compensator.compensate_rotation(r, w) for r, w in zip(rotations, raw)]
    )
    batch_rotation = compensator.compensate_batch(rotations, raw)
    batch_q = compensator.compensate_batch(configurations, raw)
    for recovered in (from_q, from_rotation, batch_rotation, batch_q):
        assert recovered.shape == (25, 6)
        np.testing.assert_allclose(recovered, contact, atol=1e-12)
    np.testing.assert_allclose(from_q, batch_q, atol=1e-14)
    np.testing.assert_allclose(from_rotation, batch_rotation, atol=1e-14)


def test_matches_hand_computation(arm, rng, truth, poses):
    _, rotations, _ = poses
    model = SensorModel(
        force_offset=rng.normal(size=3),
        torque_offset=rng.normal(scale=0.1, size=3),
        gravity_in_base=rng.normal(scale=5.0, size=3),
        center_of_mass=rng.normal(scale=0.1, size=3),
    )
    raw = rng.normal(scale=10.0, size=(len(rotations), 6))
    expected = np.array([_by_hand(model, r, w) for r, w in zip(rotations, raw)])
    compensator = Compensator(model)
    np.testing.assert_allclose(compensator.compensate_batch(rotations, raw), expected, atol=1e-12)
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotations[3], raw[3]), expected[3], atol=1e-12
    )


def test_compensating_a_no_contact_reading_gives_zero(arm, truth, poses):
    configurations, rotations, _ = poses
    compensator = Compensator(truth, arm)
    np.testing.assert_allclose(
        compensator.compensate_batch(configurations, truth.predict(rotations)),
        0.0,
        atol=1e-12,
    )


def test_compensate_samples(arm, rng, truth, poses):
    configurations, rotations, contact = poses
    samples = ftkin.Samples.from_joint_positions(
        arm, configurations, truth.predict(rotations) + contact
    )
    np.testing.assert_allclose(Compensator(truth).compensate_samples(samples), contact, atol=1e-12)


def test_inputs_are_not_modified(arm, truth, poses):
    configurations, rotations, contact = poses
    raw = truth.predict(rotations) + contact
    kept = raw.copy()
    compensator = Compensator(truth, arm)
    compensator.compensate(configurations[0], raw[0])
    compensator.compensate_rotation(rotations[0], raw[0])
    compensator.compensate_batch(rotations, raw)
    np.testing.assert_array_equal(raw, kept)


def test_calibration_result_from_calibrate_compensates(arm, rng, truth):
    configurations = arm.random_configurations(8, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(configurations)
    result = ftkin.calibrate(
        ftkin.Samples.from_rotations(rotations, truth.predict(rotations)), method="linear"
    )
    contact = np.array([1.5, -0.8, -4.0, 0.05, 0.02, -0.01])  # N, N·m
    q = arm.random_configurations(1, rng)[0]
    raw = truth.predict(arm.rotation_sensor_to_base(q)) + contact
    np.testing.assert_allclose(Compensator(result, arm).compensate(q, raw), contact, atol=1e-9)


def test_payload_weight_of_a_held_load(arm, truth, poses):
    configurations, rotations, _ = poses
    load_weight = 2.214  # N, Table 4's second load
    # the load hangs from the tool: the environment (gravity on the load) pulls along gravity
    load_in_base = load_weight * truth.gravity_in_base / truth.tool_weight
    held = np.zeros((len(rotations), 6))
    held[:, :3] = np.einsum("nji,j->ni", rotations, load_in_base)
    raw = truth.predict(rotations) + held
    compensator = Compensator(truth, arm)
    weights = Compensator.payload_weight(compensator.compensate_batch(rotations, raw))
    assert weights.shape == (len(rotations),)
    np.testing.assert_allclose(weights, load_weight, atol=1e-12)
    single = compensator.payload_weight(compensator.compensate(configurations[0], raw[0]))
    assert isinstance(single, float) and single == pytest.approx(load_weight, abs=1e-12)


# ------------------------------------------------------------- bad inputs
@pytest.fixture
def compensator(arm, truth):
    return Compensator(truth, arm)


TOOL_DOWN = np.array([0.0, 0.0, -0.5236, 0.0, -1.0472, 0.0])


@pytest.mark.parametrize(
    ("q", "raw", "pattern"),
    [
        (TOOL_DOWN[:5], np.zeros(6), r"q of shape \(6,\).*got \(5,\)"),
        (TOOL_DOWN, np.zeros(7), r"raw_wrench of shape \(6,\).*\(7,\)"),
        (TOOL_DOWN, np.zeros((1, 6)), r"raw_wrench of shape \(6,\)"),
        (np.where(np.arange(6) == 2, np.nan, TOOL_DOWN), np.zeros(6), "finite"),
        (TOOL_DOWN, [0, 0, np.inf, 0, 0, 0], "finite"),
    ],
)
def test_compensate_refuses_bad_input(compensator, q, raw, pattern):
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        compensator.compensate(q, raw)


def test_compensate_refuses_text(compensator):
    with pytest.raises(ftkin.InvalidInput, match="must be numeric"):
        compensator.compensate(TOOL_DOWN, ["a"] * 6)  # regression: a numpy ValueError leaked


def test_joint_angle_entry_points_need_an_arm(truth):
    compensator = Compensator(truth)
    with pytest.raises(ftkin.InvalidInput, match="no Arm: pass arm="):
        compensator.compensate(TOOL_DOWN, np.zeros(6))
    with pytest.raises(ftkin.InvalidInput, match="no Arm"):
        compensator.compensate_batch(TOOL_DOWN[None], np.zeros((1, 6)))


def test_rotation_entry_points_refuse_bad_input(compensator):
    rotation = np.eye(3)
    with pytest.raises(ftkin.InvalidInput, match="one .3, 3. rotation and one .6,. wrench"):
        compensator.compensate_rotation(np.stack([rotation, rotation]), np.zeros(6))
    with pytest.raises(ftkin.InvalidInput, match="not a rotation matrix"):
        compensator.compensate_rotation(2 * rotation, np.zeros(6))
    with pytest.raises(ftkin.InvalidInput, match="raw_wrench.*finite"):
        compensator.compensate_rotation(rotation, [np.nan] * 6)
    with pytest.raises(ftkin.InvalidInput, match="3 orientations but 2 wrenches"):
        compensator.compensate_batch(np.stack([rotation] * 3), np.zeros((2, 6)))
    with pytest.raises(
        ftkin.InvalidInput, match=r"raw_wrenches must have shape \(6,\) or \(N, 6\)"
    ):
        compensator.compensate_batch(np.stack([rotation] * 2), np.zeros((2, 3)))
    with pytest.raises(ftkin.InvalidInput, match="finite"):
        compensator.compensate_batch(np.full((2, 3, 3), np.nan), np.zeros((2, 6)))


def test_joint_positions_batch_refuses_bad_input(compensator):
    with pytest.raises(ftkin.InvalidInput, match=r"shape \(6,\) or \(N, 6\)"):
        compensator.compensate_batch(np.zeros((2, 5)), np.zeros((2, 6)))
    with pytest.raises(ftkin.InvalidInput, match="finite"):
        compensator.compensate_batch(np.full((2, 6), np.nan), np.zeros((2, 6)))
    with pytest.raises(ftkin.InvalidInput, match="2 orientations but 3 wrenches"):
        compensator.compensate_batch(np.zeros((2, 6)), np.zeros((3, 6)))


def test_calibration_must_be_a_sensor_model(arm):
    with pytest.raises(ftkin.InvalidInput, match="SensorModel or CalibrationResult, got dict"):
        Compensator({"force_offset": [0, 0, 0]}, arm)


@pytest.mark.parametrize(
    ("wrench", "pattern"),
    [
        (np.zeros(5), r"shape \(6,\) or \(N, 6\)"),
        (np.zeros((2, 3)), r"shape \(6,\) or \(N, 6\)"),
        ([np.nan, 0, 0, 0, 0, 0], "finite"),
    ],
)
def test_payload_weight_refuses_bad_input(wrench, pattern):
    # regression: a (5,) wrench gave a norm, NaN went through
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        Compensator.payload_weight(wrench)


@pytest.mark.parametrize(
    ("rotation", "raw"),
    [
        (np.eye(3), ["1.5", 0, 0, 0, 0, 0]),  # text is not a number here
        (np.eye(3), [True, 0.0, 0.0, 0.0, 0.0, 0.0]),  # True is not 1 N
        ([[True, 0, 0], [0, 1, 0], [0, 0, 1]], np.zeros(6)),
    ],
)
def test_one_sample_compensation_refuses_text_and_booleans(truth, rotation, raw):
    from ftkin.exceptions import InvalidInput

    with pytest.raises(InvalidInput, match="numeric"):
        Compensator(truth).compensate_rotation(rotation, raw)


REMOVED_METHODS = (
    "compensate_rotation_unchecked",
    "compensate_joint_positions",
    "compensate_batch_unchecked",
    "compensate_tracked",
    "rezero_rotation",
    "driver_zeroed_at_rotation",
)
"""Names of an unreleased draft of the class (ftkin was never published: no forwarding)."""


def test_one_method_per_input_kind_and_no_old_names(arm, truth):
    """At most four public per-sample compensate* methods; the names of the unreleased draft
    are plain AttributeErrors on the class and on an instance, with no FutureWarning."""
    import inspect
    import warnings

    public = [
        name
        for name, _ in inspect.getmembers(Compensator, inspect.isfunction)
        if name.startswith("compensate") and not name.startswith("_")
    ]
    per_sample = [name for name in public if name not in ("compensate_batch", "compensate_samples")]
    assert sorted(per_sample) == ["compensate", "compensate_rotation", "compensate_unchecked"]
    compensator = Compensator(truth, arm)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for name in (*REMOVED_METHODS, "compensate_nothing"):
            assert not hasattr(Compensator, name), name
            with pytest.raises(AttributeError, match=f"has no attribute '{name}'"):
                getattr(compensator, name)
