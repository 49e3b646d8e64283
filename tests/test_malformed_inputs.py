"""Malformed arguments at the public API are ftkin errors (regressions of the input review)."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Compensator, InvalidInput, PoseConstraints, SensorNoise, SimulatedSensor
from ftkin.calibration import cross_validate
from ftkin.control import max_stable_k1
from ftkin.io.csv_table import Table
from ftkin.io.samples_csv import detect_orientation
from ftkin.kinematics.rotations import gravity_in_base_from_tilt, tilt_from_gravity_in_base
from ftkin.planning import ExcitationSpec
from ftkin.sim.sensor import paper_like_truth


@pytest.fixture(scope="module")
def compensator(arm):
    return Compensator(paper_like_truth(), arm)


# a "rotation" of any magnitude: 1e300 overflowed the check to inf − inf = NaN, which passed
HUGE = [
    np.array([[0.6, -0.8, 0.0], [0.8, 0.6, 0.0], [0.0, 0.0, 1.0]]) * 1e300,
    np.array([[1e300, -1e300, 0], [1e300, 1e300, 0], [0, 0, 1.0]]),
]


@pytest.mark.parametrize("rotation", HUGE, ids=["scaled", "mixed signs"])
def test_a_huge_matrix_is_not_a_rotation(compensator, rotation):
    for call in (
        lambda: compensator.compensate_rotation(rotation, np.zeros(6)),
        lambda: compensator.compensate_batch(rotation[None], np.zeros((1, 6))),
        lambda: compensator.rezero(rotation, np.zeros(6)),
    ):
        with pytest.raises(InvalidInput, match="not a rotation matrix"):
            call()


@pytest.mark.parametrize(
    "raw", [np.full(6, 1e308), [1e308, -1e308, 0, 0, 0, 0], [0, 0, 0, 0, 0, 2e6]]
)
def test_absurd_readings_are_refused_on_every_compensation_path(compensator, arm, raw):
    """1e308 N came out as 1e308 (or inf) instead of the readers' refusal."""
    q, rotation = np.zeros(arm.nq), arm.rotation_sensor_to_base(np.zeros(arm.nq)[None])[0]
    calls = (
        lambda: compensator.compensate(q, raw),
        lambda: compensator.compensate_rotation(rotation, raw),
        lambda: compensator.compensate_rotation(rotation, np.asarray(raw, dtype=float)),
        lambda: compensator.compensate_batch(rotation, raw),
        lambda: compensator.compensate_batch(q, raw),
        lambda: compensator.rezero(rotation, raw),
        lambda: compensator.set_bias(raw),
    )
    for call in calls:
        with pytest.raises(InvalidInput, match=r"beyond ±1e\+06"):
            call()


def test_large_plausible_readings_still_compensate(compensator, arm):
    """Six entries within ±1e6 whose norm is beyond it take the checked path and pass."""
    rotation = arm.rotation_sensor_to_base(np.zeros(arm.nq)[None])[0]
    raw = np.full(6, 9e5)
    np.testing.assert_allclose(
        compensator.compensate_rotation(rotation, raw),
        compensator.compensate_unchecked(rotation, raw),
        rtol=1e-12,
    )
    np.testing.assert_allclose(
        compensator.compensate(np.zeros(arm.nq), raw),
        compensator.compensate_batch(rotation, raw)[0],
        rtol=1e-12,
    )


@pytest.mark.parametrize("stiffness", ["a", None, [1e4]])
def test_max_stable_k1_refuses_a_non_number(stiffness):
    with pytest.raises(InvalidInput, match="max_stable_k1 needs"):
        max_stable_k1(stiffness, 100.0, 1e-3, 5.0)


@pytest.mark.parametrize("samples", [[1, 2], None, np.zeros((4, 6))])
def test_cross_validate_refuses_what_is_not_samples(samples):
    with pytest.raises(InvalidInput, match="samples must be an ftkin.Samples"):
        cross_validate(samples)


@pytest.mark.parametrize(
    ("keywords", "match"), [({"drifts": 5}, "distinct drift"), ({"seed": "x"}, "seed")]
)
def test_cross_validate_refuses_a_bad_drifts_or_seed(tool, rotations, keywords, match):
    samples = SimulatedSensor(tool, SensorNoise(0.03, 0.0015)).samples(
        rotations, np.random.default_rng(0)
    )
    with pytest.raises(InvalidInput, match=match):
        cross_validate(samples, **keywords)


@pytest.mark.parametrize("gravity", [[1.0], None, "abc", [1, 2, "x"], [[1, 2, 3]], [np.nan, 0, 1]])
def test_tilt_from_gravity_checks_its_vector(gravity):
    with pytest.raises(InvalidInput, match="gravity_in_base"):
        tilt_from_gravity_in_base(gravity)


def test_gravity_from_tilt_checks_its_numbers():
    with pytest.raises(InvalidInput, match="weight"):
        gravity_in_base_from_tilt("a", 0.0, 0.0)
    with pytest.raises(InvalidInput, match="V"):
        gravity_in_base_from_tilt(1.0, 0.0, [0.1, 0.2])


@pytest.mark.parametrize(
    ("keywords", "match"),
    [
        ({"harmonics": None}, "harmonics must be an integer"),
        ({"harmonics": "5"}, "harmonics must be an integer"),
        ({"harmonics": 2.5}, "harmonics must be an integer"),
        ({"harmonics": True}, "harmonics must be an integer"),
        ({"harmonics": 1}, "harmonics must be at least 2"),
        ({"harmonics": 10**9}, "harmonics must be at most"),
        ({"candidates": "x"}, "candidates"),
        ({"max_iterations": -1}, "max_iterations"),
        ({"seed": 0.5}, "seed"),
        ({"constraints": "none"}, "constraints must be"),
        ({"noise": 0.1}, "noise a SensorNoise"),
        ({"optimize": "no"}, "optimize True or False"),
    ],
)
def test_excitation_spec_checks_its_counts_and_types(keywords, match):
    with pytest.raises(InvalidInput, match=match):
        ExcitationSpec(10.0, **keywords)


def test_excitation_spec_keeps_whole_floats():
    harmonics = ExcitationSpec(10.0, harmonics=4.0).harmonics
    assert harmonics == 4 and type(harmonics) is int


@pytest.mark.parametrize(
    ("joint_ranges", "match"),
    [
        (5, "joint_ranges must be"),
        (((3, -1.0, 1.0),), "joint name"),
        ((("joint1", -1.0),), "joint name"),
        ((("joint1", "low", 1.0),), "joint range of 'joint1'"),
        ((("joint1", True, 1.0),), "joint range of 'joint1'"),
        ({"joint1": 5}, "joint_ranges must be"),
    ],
)
def test_pose_constraints_refuse_malformed_joint_ranges(joint_ranges, match):
    with pytest.raises(InvalidInput, match=match):
        PoseConstraints(joint_ranges=joint_ranges)


def test_pose_constraints_refuse_a_non_boolean_self_collision():
    with pytest.raises(InvalidInput, match="self_collision"):
        PoseConstraints(self_collision="no")


def test_detect_orientation_takes_any_sequence_of_names(arm):
    table = Table("t.csv", [*arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"], [], [])
    expected = ("joints", list(arm.joint_names))
    for names in (np.array(arm.joint_names), tuple(arm.joint_names), iter(arm.joint_names)):
        assert detect_orientation(table, names) == expected
    for names in ("joint1", [1, 2], 5):
        with pytest.raises(InvalidInput, match="joint_names must be a sequence of strings"):
            detect_orientation(table, names)


def test_absurd_readings_are_refused_by_the_dynamic_paths(arm):
    from ftkin import DynamicCompensator
    from ftkin.calibration.regressor import MotionSamples

    dynamic = DynamicCompensator(paper_like_truth(), arm)
    zeros, raw = np.zeros(arm.nq), np.full(6, 1e308)
    with pytest.raises(InvalidInput, match=r"beyond ±1e\+06"):
        dynamic.compensate_moving(zeros, zeros, zeros, raw)
    with pytest.raises(InvalidInput, match=r"beyond ±1e\+06"):
        MotionSamples.from_joint_trajectory(arm, zeros, zeros, zeros, raw)
    with pytest.raises(InvalidInput, match="dq must be finite"):
        dynamic.compensate_moving(zeros, zeros + np.nan, zeros, np.zeros(6))
