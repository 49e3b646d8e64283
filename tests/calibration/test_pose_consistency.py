"""The leave-one-out check of a session's poses (ftkin.calibration.pose_consistency).

The readings are written by hand from the model (raw = F0 + R_BSᵀ a, M0 + c × R_BSᵀ a): noise
free, every fit of the other poses is exact, its scale is the floor and a pose's score is its
own perturbation over the floor — the threshold is tested on both sides of it. With noise, one
gross error among twelve is flagged, a 3σ deviation is not.
"""

import numpy as np
import pytest

from ftkin.calibration.pose_consistency import (
    FORCE_FLOOR,
    MIN_POSES,
    THRESHOLD,
    TORQUE_FLOOR,
    check_pose_consistency,
)
from ftkin.calibration.samples import PoseAverages
from ftkin.exceptions import InvalidInput

G = 9.81
MASS = 1.66  # [kg]
COM = np.array([0.01, -0.02, 0.08])  # [m], sensor frame
F0 = np.array([1.5, -0.8, 2.2])  # [N]
M0 = np.array([0.05, -0.03, 0.02])  # [N·m]


def random_rotations(rng, count: int) -> np.ndarray:
    """Uniform rotations from unit quaternions (w, x, y, z)."""
    q = rng.normal(size=(count, 4))
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    ).transpose(2, 0, 1)


def poses(count: int = 12, seed: int = 0, noise=(0.0, 0.0)) -> PoseAverages:
    """``count`` pose means of a 1.66 kg tool, with Gaussian noise (force [N], torque [N·m])."""
    rng = np.random.default_rng(seed)
    rotations = random_rotations(rng, count)
    weight = np.einsum("nji,j->ni", rotations, [0.0, 0.0, -MASS * G])  # R_BSᵀ a
    wrenches = np.hstack([F0 + weight, M0 + np.cross(COM, weight)])
    wrenches += np.repeat(noise, 3) * rng.standard_normal((count, 6))
    return PoseAverages(
        np.arange(count), rotations, wrenches, np.full(count, 30), np.zeros((count, 6))
    )


def perturbed(base: PoseAverages, pose: int, delta) -> PoseAverages:
    wrenches = base.wrenches.copy()
    wrenches[pose] += delta
    return PoseAverages(base.pose_ids, base.rotations, wrenches, base.counts, base.spread)


def test_clean_poses_are_not_flagged():
    check = check_pose_consistency(poses(), g=G)
    assert check.holds and check.flagged == ()
    np.testing.assert_allclose(check.scores, 0.0, atol=1e-6)  # exact fits over the floor


@pytest.mark.parametrize(
    ("channel", "size", "floor"),
    [
        (0, 0.59, FORCE_FLOOR),
        (0, 0.61, FORCE_FLOOR),
        (4, 0.059, TORQUE_FLOOR),
        (4, 0.061, TORQUE_FLOOR),
    ],
)
def test_the_threshold_from_both_sides(channel, size, floor):
    """Noise free: the left-out fit is exact, the scale is the floor, the score is size/floor
    (5.9 or 6.1 against the threshold 6)."""
    assert THRESHOLD == 6.0 and FORCE_FLOOR == 0.1 and TORQUE_FLOOR == 0.01  # the hand numbers
    delta = np.zeros(6)
    delta[channel] = size
    check = check_pose_consistency(perturbed(poses(), 5, delta), g=G)
    np.testing.assert_allclose(check.scores[5], size / floor, rtol=1e-6)
    assert check.flagged == ((5,) if size / floor > 6.0 else ())


@pytest.mark.parametrize("seed", range(10))
def test_one_gross_error_among_twelve_is_flagged_and_only_it(seed):
    """130 N on one pose's force (a link on the hand), noise 0.05 N / 0.004 N·m: flagged, alone."""
    base = poses(seed=seed, noise=(0.05, 0.004))
    assert check_pose_consistency(base, g=G).flagged == ()
    contact = np.array([0.0, 130.0 / np.sqrt(2), 130.0 / np.sqrt(2), 0.0, 0.0, 0.0])
    check = check_pose_consistency(perturbed(base, seed, contact), g=G)
    assert check.flagged == (seed,)
    np.testing.assert_allclose(check.force_residuals[seed], 130.0, atol=0.5)


@pytest.mark.parametrize("seed", range(10))
def test_a_three_sigma_deviation_is_not_flagged(seed):
    """3σ on one force channel of one pose: a residual near 3σ over a median of about 1.5σ."""
    sigma = 0.2  # [N], above the floor so that the median, not the floor, is the scale
    base = poses(seed=seed, noise=(sigma, 0.004))
    check = check_pose_consistency(perturbed(base, 3, [3 * sigma, 0, 0, 0, 0, 0]), g=G)
    assert check.flagged == ()
    assert check.scores[3] < 4.0


def test_too_few_poses_are_not_scored():
    check = check_pose_consistency(perturbed(poses(MIN_POSES - 1), 0, [130, 0, 0, 0, 0, 0]))
    assert check.flagged == () and np.all(np.isnan(check.scores))


@pytest.mark.parametrize(
    "keywords", [{"threshold": 1.0}, {"force_floor": 0.0}, {"torque_floor": float("nan")}]
)
def test_bad_settings_are_refused(keywords):
    with pytest.raises(InvalidInput, match=next(iter(keywords))):
        check_pose_consistency(poses(), **keywords)
    with pytest.raises(InvalidInput, match="PoseAverages"):
        check_pose_consistency(np.zeros((12, 6)))
