"""What recorded poses leave undetermined, and the next pose: against the information computed
directly, the ideal bound by hand, and the spread of repeated calibrations."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.calibration.information import SensorNoise, fisher_information
from ftkin.planning.coverage import (
    DOWN,
    assess_coverage,
    fibonacci_sphere,
    rotations_from_gravity,
    turn_between,
)
from ftkin.planning.evaluation import ExpectedCalibration, evaluate_poses

NOISE = SensorNoise(0.02, 0.001)
EXPECTED = ExpectedCalibration(
    tool_weight=12.0, center_of_mass=[0.02, -0.01, 0.09], noise=NOISE, readings_per_pose=50
)


def yaw(angle):
    return Rotation.from_euler("z", angle).as_matrix()


def test_turns_take_one_direction_to_the_other():
    rng = np.random.default_rng(0)
    pairs = [rng.normal(size=(2, 3)) for _ in range(20)] + [np.array([[0, 0, 1.0], [0, 0, -1.0]])]
    for start, end in pairs:
        start, end = start / np.linalg.norm(start), end / np.linalg.norm(end)
        turn = turn_between(start, end)
        np.testing.assert_allclose(turn @ start, end, atol=1e-12)
        np.testing.assert_allclose(turn.T @ turn, np.eye(3), atol=1e-12)
        np.testing.assert_allclose(np.linalg.det(turn), 1.0, atol=1e-12)
    directions = fibonacci_sphere(64)
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0, atol=1e-12)
    rotations = rotations_from_gravity(directions)
    np.testing.assert_allclose(np.einsum("nji,j->ni", rotations, DOWN), directions, atol=1e-12)


def test_poses_turned_about_the_vertical_leave_the_centre_of_mass_open():
    coverage = assess_coverage([yaw(0.0), yaw(2.0), yaw(4.0)], EXPECTED)
    assert not coverage.determined and coverage.ratios is None and coverage.worst is None
    # gravity along −z in each: the weight's z and the force bias's z trade, the torque bias
    # and the centre of mass across gravity trade, the centre of mass along it is unseen
    expected = {"gravity_in_base[z]", "force_offset[z]", "center_of_mass[z]"}
    expected |= {"torque_offset[x]", "torque_offset[y]", "center_of_mass[x]", "center_of_mass[y]"}
    assert set(coverage.weakest) == expected
    angle = np.degrees(np.arccos(coverage.next_gravity @ DOWN))
    assert angle > 45.0 and coverage.next_angle == pytest.approx(np.radians(angle), abs=1e-9)
    assert "undetermined" in coverage.describe() and "next: gravity along" in coverage.describe()


def test_predictions_are_the_evaluations_and_the_ideal_is_the_bound_by_hand():
    rotations = Rotation.random(6, random_state=3).as_matrix()
    coverage = assess_coverage(rotations, EXPECTED)
    evaluation = evaluate_poses(rotations, EXPECTED)
    np.testing.assert_allclose(coverage.evaluation.vector_std, evaluation.vector_std, rtol=1e-12)
    # ideal per entry, with N poses of r readings: σ/√(N r); the centre of mass σ_M/(G √(N r))
    weight, count, readings = 12.0, 6, 50
    force, torque = 0.02, 0.001
    ideal = np.repeat([force, force, torque, torque / weight], 3) / np.sqrt(count * readings)
    np.testing.assert_allclose(coverage.ratios * ideal, evaluation.vector_std, rtol=1e-6)
    name, std, ratio, unit = coverage.worst
    assert ratio == pytest.approx(coverage.ratios.max()) and ratio >= 1.0


def test_the_next_pose_adds_the_most_information_of_the_candidates():
    """The choice against ``log det`` of the information computed directly for each candidate
    pose (unscaled: the scaling adds a constant; no ridge: these poses determine everything)."""
    rotations = Rotation.random(5, random_state=4).as_matrix()
    coverage = assess_coverage(rotations, EXPECTED, candidates=64)
    last = rotations[-1]
    gains = []
    for direction in fibonacci_sphere(64):
        candidate = last @ turn_between(direction, last.T @ DOWN)
        information = fisher_information(
            EXPECTED.model, np.concatenate([rotations, candidate[None]]), NOISE, 50
        )
        gains.append(np.linalg.slogdet(information)[1])
    best = fibonacci_sphere(64)[int(np.argmax(gains))]
    np.testing.assert_allclose(coverage.next_gravity, best, atol=1e-12)
    # one more pose: no parameter gets worse, the predicted errors with it computed directly
    chosen = last @ turn_between(best, last.T @ DOWN)
    information = fisher_information(
        EXPECTED.model, np.concatenate([rotations, chosen[None]]), NOISE, 50
    )
    direct = np.sqrt(np.diag(np.linalg.inv(information)))
    np.testing.assert_allclose(coverage.next_std, direct, rtol=1e-6)
    assert np.all(coverage.next_std <= coverage.evaluation.vector_std * (1 + 1e-9))
    assert f"it would bring {coverage.worst[0]} to ±" in coverage.describe()


def test_predicted_standard_errors_match_the_spread_of_repeated_calibrations():
    """Readings from first principles at six poses, calibrated 120 times (the ML fit, noise
    given): the spread of the estimates is the prediction, within what 120 repeats resolve."""
    from ftkin import Samples, calibrate

    rotations = Rotation.random(6, random_state=5).as_matrix()
    mass, com, bias = (
        12.0 / 9.80665,
        np.array([0.02, -0.01, 0.09]),
        np.array([1, -2, 3, 0.1, 0, -0.1]),
    )
    weight = -mass * 9.80665 * np.einsum("nji,j->ni", rotations, [0.0, 0.0, 1.0])
    clean = bias + np.hstack([weight, np.cross(com, weight)])
    readings, repeats = 20, 120
    rng = np.random.default_rng(6)
    expected = ExpectedCalibration(
        tool_weight=12.0, center_of_mass=com, noise=NOISE, readings_per_pose=readings
    )
    predicted = assess_coverage(rotations, expected).evaluation.vector_std
    estimates = []
    for _ in range(repeats):
        noisy = np.repeat(clean, readings, axis=0) + rng.normal(size=(6 * readings, 6)) * np.repeat(
            [0.02, 0.001], 3
        )
        samples = Samples(
            noisy, np.repeat(rotations, readings, axis=0), np.repeat(np.arange(6), readings)
        )
        estimates.append(calibrate(samples, noise=NOISE, drift="none").to_vector())
    spread = np.std(estimates, axis=0, ddof=1)
    np.testing.assert_allclose(spread, predicted, rtol=0.25)  # χ with 119 dof: ±13 % at 2σ


def test_bad_input_is_refused():
    from ftkin.exceptions import InvalidInput

    with pytest.raises(InvalidInput, match="at least one pose"):
        assess_coverage(np.zeros((0, 3, 3)), EXPECTED)
    with pytest.raises(InvalidInput):
        assess_coverage(np.ones((2, 3, 3)), EXPECTED)
