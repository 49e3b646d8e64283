"""Does each static pose agree with the others? A leave-one-out check robust to one gross error.

A reading taken while something touches the tool or the arm (a cable, a link, a hand) is off by
the contact wrench, and a least-squares fit that keeps it spreads the error over every
parameter: its own residual shrinks, the noise estimate grows, and a 130 N contact can pass as a
2σ outlier. Left out, it cannot hide. For each pose ``i`` of the pose means
(:class:`~ftkin.calibration.samples.PoseAverages`):

1. fit the static model (the paper's linear least squares, :func:`~ftkin.calibration.linear.
   fit_linear`) to the other poses;
2. the pose's prediction residual ``r_i = w_i − predict(R_i)`` [N, N·m];
3. the scale of that fit: the median over the other poses of their residual norms, force and
   torque apart, at least ``force_floor`` [N] / ``torque_floor`` [N·m] (the smallest
   disagreement worth a second look: a noise-free fit has no scale);
4. the score ``max(|r_F| / scale_F, |r_M| / scale_M)``.

A median ignores one wild pose among the others, and the worst pose is taken out first: the
pose with the largest score is flagged when its score exceeds ``threshold`` (default
:data:`THRESHOLD` = 6), then the others are scored again without it, until none exceeds it or
fewer than :data:`MIN_POSES` remain. For Gaussian residuals the median of a 3-vector's norm is
1.54 σ, so a score of 6 is a residual of 9.2 σ (leaving a pose out inflates its residual by about
``1/√(1 − 12/(6 (n−1)))``, 1.1 for twelve poses): a 3 σ deviation scores about 2, and a clean
pose is flagged far less often than once in a million sessions.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, UnobservableParameters
from .linear import fit_linear
from .model import STANDARD_GRAVITY
from .samples import PoseAverages

THRESHOLD = 6.0
"""A pose whose left-out residual exceeds this many times the others' median is flagged."""
FORCE_FLOOR = 0.1
"""Smallest force scale of the check [N]."""
TORQUE_FLOOR = 0.01
"""Smallest torque scale of the check [N·m]."""
MIN_POSES = 6
"""Fewest poses the check scores (five left in each fit: 30 equations for 12 parameters)."""


@dataclass(frozen=True)
class PoseConsistency:
    """The leave-one-out check of a set of poses.

    Attributes:
        pose_ids: ``(P,)`` the poses, in the order given.
        force_residuals: ``(P,)`` norm of each pose's force residual left out [N] (NaN: not
            scored, fewer than :data:`MIN_POSES` poses).
        torque_residuals: ``(P,)`` the same for the torque [N·m].
        scores: ``(P,)`` residual over the scale (see the module docstring); the score of a
            flagged pose is the one it was flagged with.
        flagged: Pose ids that do not fit the others, worst first.
        threshold: The score above which a pose is flagged.
    """

    pose_ids: np.ndarray
    force_residuals: np.ndarray
    torque_residuals: np.ndarray
    scores: np.ndarray
    flagged: tuple
    threshold: float

    @property
    def holds(self) -> bool:
        """True when no pose is flagged."""
        return not self.flagged

    def describe(self, pose_id) -> str:
        """One pose's residuals and score, e.g. ``pose 3: 130 N, 0.02 N·m off (score 212)``."""
        i = int(np.flatnonzero(self.pose_ids == pose_id)[0])
        return (
            f"pose {pose_id}: {self.force_residuals[i]:.3g} N, {self.torque_residuals[i]:.3g} "
            f"N·m off the others' fit (score {self.scores[i]:.3g}, limit {self.threshold:g})"
        )


def check_pose_consistency(
    poses: PoseAverages,
    *,
    threshold: float = THRESHOLD,
    force_floor: float = FORCE_FLOOR,
    torque_floor: float = TORQUE_FLOOR,
    g: float = STANDARD_GRAVITY,
) -> PoseConsistency:
    """Score each pose against a fit of the others (module docstring); flag those that do not fit.

    Args:
        poses: Per-pose mean readings and orientations (raw readings, sensor frame).
        threshold: Flag a pose whose score exceeds this (> 1).
        force_floor: Smallest force scale [N] (> 0).
        torque_floor: Smallest torque scale [N·m] (> 0).
        g: Gravity [m/s²] (the fit's tool mass; the residuals do not depend on it).

    Returns:
        The scores (NaN and nothing flagged with fewer than :data:`MIN_POSES` poses).
    """
    if not isinstance(poses, PoseAverages):
        raise InvalidInput(f"poses must be ftkin PoseAverages, got {type(poses).__name__}")
    for name, value, low in (
        ("threshold", threshold, 1.0),
        ("force_floor", force_floor, 0.0),
        ("torque_floor", torque_floor, 0.0),
    ):
        if not (isinstance(value, int | float) and np.isfinite(value) and value > low):
            raise InvalidInput(f"{name} must be a finite number above {low:g}, got {value!r}")
    count = len(poses)
    force, torque, scores = (np.full(count, np.nan) for _ in range(3))
    flagged: list = []
    kept = np.arange(count)
    while len(kept) >= MIN_POSES:
        residuals = [_left_out(poses, kept, k, force_floor, torque_floor, g) for k in kept]
        values = np.array(residuals)  # (len(kept), 3): force, torque, score
        force[kept], torque[kept] = values[:, 0], values[:, 1]
        scores[kept] = np.where(np.isfinite(values[:, 2]), values[:, 2], np.nan)
        worst = int(np.argmax(values[:, 2]))
        if not values[worst, 2] > threshold:
            break
        flagged.append(poses.pose_ids[kept[worst]])
        kept = np.delete(kept, worst)
    return PoseConsistency(
        np.asarray(poses.pose_ids), force, torque, scores, tuple(flagged), float(threshold)
    )


def _left_out(poses, kept, index, force_floor, torque_floor, g) -> tuple[float, float, float]:
    """``(|r_F| [N], |r_M| [N·m], score)`` of pose ``index`` against a fit of the other ``kept``."""
    others = poses.subset(kept[kept != index])
    try:
        model = fit_linear(others, g)
    except UnobservableParameters:  # the others cannot determine the model: no verdict
        return np.nan, np.nan, -np.inf
    fitted = others.wrenches - model.predict(others.rotations)
    own = poses.wrenches[index] - model.predict(poses.rotations[index : index + 1])[0]
    scale_force = max(float(np.median(np.linalg.norm(fitted[:, :3], axis=1))), force_floor)
    scale_torque = max(float(np.median(np.linalg.norm(fitted[:, 3:], axis=1))), torque_floor)
    residual_force, residual_torque = np.linalg.norm(own[:3]), np.linalg.norm(own[3:])
    score = max(residual_force / scale_force, residual_torque / scale_torque)
    return float(residual_force), float(residual_torque), float(score)
