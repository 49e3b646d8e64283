"""Calibration pose planning: few poses, most accurate calibration, any URDF.

:func:`plan_poses` chooses ``n`` joint configurations that maximize the
Fisher information of ``θ = [a, F0, M0, P]`` (D-optimality, see
:mod:`ftkin.planning.design`) under :class:`~ftkin.planning.constraints.PoseConstraints`:

1. sample a pool of random configurations and keep the feasible ones
   (limits with a margin, floor, tool tilt, self-collision);
2. greedy D-optimal selection from the pool, then Fedorov exchange;
3. refine each pose by small random joint perturbations that stay feasible
   and raise the criterion (shrinking steps);
4. order the poses for short joint travel (:mod:`ftkin.planning.order`), or,
   for a sensor whose bias drifts (``drift_rate``), in the order that keeps the
   most information with the drift integrated out
   (:mod:`ftkin.planning.drift_order`).

Only the sensor orientation carries information. With noise ``σ`` per channel
and ``N`` poses no design beats ``σ/√N`` for each bias channel; a good design
reaches it, and lowers the other parameters' errors with it.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.mount import check_mount_mode
from ..calibration.observability import check_pose_count
from ..exceptions import InvalidInput
from ..progress import Progress
from .constraints import (
    DEFAULT_MARGIN,
    FeasibilityChecker,
    PoseConstraints,
    check_information,
    check_tilt_observability,
)
from .design import d_optimal_selection, information_factors, log_det
from .drift_order import (
    DEFAULT_POSE_INTERVAL,
    check_drift_options,
    check_travel_ratio,
    drift_robust_order,
)
from .evaluation import PoseEvaluation, evaluate_poses, expected_tool
from .order import joint_distances, path_length, revolute_mask, short_travel_order, unwind_revolute

CRITERION = (
    "D-optimality: log det of the Fisher information of θ = [a, F0, M0, P] (and the mount angles, "
    "if estimated; SI units)"
)
REFINE_STEPS = (0.2, 0.08, 0.03, 0.01)
"""Standard deviations [rad] of the joint perturbations in the refinement rounds."""
REFINE_TRIES = 25
"""Perturbations drawn per pose and refinement round."""
DRIFT_CRITERION = (
    "D-optimality: log det of the Fisher information of θ = [a, F0, M0, P] with the bias's random "
    "walk "
    "integrated out, poses visited in order (SI units)"
)
SAMPLE_BATCH = 2000


@dataclass(frozen=True)
class PosePlan:
    """Planned calibration poses and their predicted accuracy.

    Attributes:
        joint_positions: ``(n, nq)`` configurations [rad], in visiting order.
        joint_names: URDF joint names, the columns of ``joint_positions``.
        evaluation: Predicted information and standard errors of the set.
        criterion: What was maximized.
        criterion_value: Its value for the final set.
        seed: Seed of the random generator; the same seed gives the same plan.
        constraints: The constraints every pose meets.
        candidate_count: Feasible configurations in the pool.
        sampled_count: Random configurations drawn to fill the pool.
    """

    joint_positions: np.ndarray
    joint_names: tuple[str, ...]
    evaluation: PoseEvaluation
    criterion: str
    criterion_value: float
    seed: int
    constraints: PoseConstraints
    candidate_count: int
    sampled_count: int

    @property
    def rotations(self) -> np.ndarray:
        """``(n, 3, 3)`` sensor orientations ``R_BS`` of the poses."""
        return self.evaluation.rotations

    @property
    def standard_errors(self) -> dict:
        """Predicted standard errors (keys of
        :func:`ftkin.calibration.information.standard_errors`).
        """
        return self.evaluation.standard_errors

    @property
    def pose_count(self) -> int:
        """Number of poses."""
        return len(self.joint_positions)

    @property
    def joint_travel(self) -> float:
        """Joint-space path length through the poses in visiting order [rad] (Euclidean norm of each
        move).
        """
        return float(np.sum(np.linalg.norm(np.diff(self.joint_positions, axis=0), axis=1)))

    def report(self) -> str:
        """Human-readable summary: constraints and predicted standard errors."""
        lines = [
            f"{self.pose_count} poses (seed {self.seed}); {self.candidate_count} feasible "
            "candidates "
            f"from {self.sampled_count} sampled",
            f"constraints: {self.constraints.describe()}",
            f"criterion: {self.criterion} = {self.criterion_value:.3f}",
            f"joint travel along the visiting order: {self.joint_travel:.1f} rad",
        ]
        return "\n".join(lines) + "\n" + self.evaluation.report()


def plan_poses(
    arm,
    n: int,
    *,
    margin: float = DEFAULT_MARGIN,
    floor_height: float | None = None,
    max_tilt: float | None = None,
    joint_ranges: Mapping | None = None,
    self_collision: bool = True,
    tool_weight: float | None = None,
    center_of_mass=None,
    noise: SensorNoise | None = None,
    readings_per_pose: int = 1,
    seed: int = 0,
    candidates: int = 3000,
    max_samples: int = 200_000,
    progress: bool | None = None,
    estimate_mount: str = "none",
    drift_rate=None,
    pose_interval: float = DEFAULT_POSE_INTERVAL,
    max_travel_ratio: float | None = None,
) -> PosePlan:
    """Plan ``n`` calibration poses for ``arm``.

    Args:
        arm: :class:`~ftkin.kinematics.arm.Arm` with the sensor frame (and optionally a tool frame).
        n: Number of poses (≥ 3).
        margin: Distance kept from the joint limits [rad].
        floor_height: Sensor and tool origins stay above this base-frame height [m].
        max_tilt: Largest angle of the tool axis from straight down [rad].
        joint_ranges: ``{joint name: (lower, upper)}`` extra limits [rad].
        self_collision: Reject self-colliding configurations (URDF collision geometry).
        tool_weight: Expected tool weight [N] (default 3.15 N, the paper's).
        center_of_mass: Expected tool COM in the sensor frame [m] (default 47 mm along z).
        noise: Sensor noise per reading (default :meth:`SensorNoise.paper`).
        readings_per_pose: Independent readings averaged at each pose.
        seed: Random seed; the plan is deterministic for a seed.
        candidates: Feasible configurations to collect for the pool.
        max_samples: Give up after drawing this many random configurations.
        progress: Draw a progress bar (default: when stderr is a terminal).
        estimate_mount: ``"yaw"`` or ``"full"``: plan for a calibration that
            also estimates the sensor's mount (D-optimality over ``[θ, mount
            angles]``, the mount assumed near identity).
        drift_rate: ``[force N/√s, torque N·m/√s]``, the expected random-walk
            rate of the bias (e.g. a past calibration's ``drift.rate``): the
            poses are then visited in the order that keeps the most
            information with the drift integrated out
            (:func:`~ftkin.planning.drift_order.drift_robust_order`; longer
            joint travel), and the predicted standard errors include the
            drift. Not with ``estimate_mount``.
        pose_interval: Time from one pose to the next [s] (with ``drift_rate``).
        max_travel_ratio: With ``drift_rate``: the joint travel along the
            drift-robust order stays within this multiple (≥ 1) of the
            short-travel order's (None: unbounded, about 2× on the bundled arm).

    Raises:
        UnobservableParameters: ``n < 3``, or the constraints leave a
            parameter undetermined (the error names it and says why).
        InvalidInput: bad arguments, or too few feasible configurations
            (the message names the constraints and what rejected them).
    """
    n = _integer(n, "n (number of poses)")
    check_pose_count(n)
    readings_per_pose = _integer(readings_per_pose, "readings_per_pose", minimum=1)
    candidates = max(_integer(candidates, "candidates", minimum=1), n)
    max_samples = _integer(max_samples, "max_samples", minimum=1)
    seed = _integer(seed, "seed", minimum=0)
    if noise is not None and not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin.SensorNoise, got {type(noise).__name__}")
    check_mount_mode(estimate_mount)
    drift_rate, pose_interval = check_drift_options(drift_rate, pose_interval, estimate_mount)
    max_travel_ratio = check_travel_ratio(max_travel_ratio, drift_rate)
    constraints = PoseConstraints(
        margin, floor_height, max_tilt, joint_ranges or (), self_collision
    )
    model = expected_tool(tool_weight, center_of_mass)
    noise = noise if noise is not None else SensorNoise.paper()
    checker = FeasibilityChecker(arm, constraints)
    rng = np.random.default_rng(seed)

    channel_std = noise.channel_std

    def factors(rotations):
        return information_factors(
            rotations,
            model.gravity_in_base,
            model.center_of_mass,
            channel_std,
            readings_per_pose,
            estimate_mount,
        )

    check_tilt_observability(checker, factors)
    pool_q, pool_rotations, sampled = _candidate_pool(
        checker, rng, candidates, max_samples, n, progress
    )
    pool_factors = factors(pool_rotations)
    check_information(pool_factors, constraints)
    chosen, _ = d_optimal_selection(pool_factors, n)
    q, rotations = pool_q[chosen].copy(), pool_rotations[chosen].copy()
    q, rotations = _refine(checker, q, rotations, factors, rng, progress)
    q = unwind_revolute(q, checker.lower, checker.upper, revolute_mask(arm.model))
    order = short_travel_order(q)
    criterion = CRITERION
    if drift_rate is not None:
        distances = joint_distances(q)
        max_length = (
            None if max_travel_ratio is None else max_travel_ratio * path_length(distances, order)
        )
        order, _ = drift_robust_order(
            model,
            rotations,
            rate=drift_rate,
            noise_std=channel_std,
            readings_per_pose=readings_per_pose,
            pose_interval=pose_interval,
            rng=rng,
            initial_order=order,
            distances=distances,
            max_length=max_length,
        )
        criterion = DRIFT_CRITERION
    q, rotations = q[order], rotations[order]
    evaluation = evaluate_poses(
        rotations,
        tool_weight=tool_weight,
        center_of_mass=center_of_mass,
        noise=noise,
        readings_per_pose=readings_per_pose,
        estimate_mount=estimate_mount,
        drift_rate=None if drift_rate is None else drift_rate[[0, 3]],
        pose_interval=pose_interval,
    )
    full_information = (
        evaluation.information
        if drift_rate is not None
        else np.einsum("nki,nkj->ij", *(2 * (factors(rotations),)))
    )
    return PosePlan(
        joint_positions=q,
        joint_names=tuple(arm.joint_names),
        evaluation=evaluation,
        criterion=criterion,
        criterion_value=log_det(full_information),
        seed=seed,
        constraints=constraints,
        candidate_count=len(pool_q),
        sampled_count=sampled,
    )


def _integer(value, name: str, minimum: int | None = None) -> int:
    """``value`` as an int (no bools, no fractions), at least ``minimum``."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise InvalidInput(f"{name} must be an integer, got {value!r}")
    if minimum is not None and value < minimum:
        raise InvalidInput(f"{name} must be at least {minimum}, got {value}")
    return int(value)


def _candidate_pool(checker, rng, wanted, max_samples, n, progress):
    kept_q, kept_rotations, sampled = [], [], 0
    with Progress(wanted, "sampling poses", enabled=progress) as bar:
        while len(kept_q) < wanted and sampled < max_samples:
            batch = checker.sample(min(SAMPLE_BATCH, max_samples - sampled), rng)
            for q in batch:
                sampled += 1
                rotation = checker.check(q)
                if rotation is not None:
                    kept_q.append(q)
                    kept_rotations.append(rotation)
                    bar.advance()
                    if len(kept_q) >= wanted:
                        break
    if len(kept_q) < n:
        rejected = ", ".join(f"{name}: {count}" for name, count in checker.rejected.items())
        raise InvalidInput(
            f"found only {len(kept_q)} feasible configuration(s) of {sampled} sampled, need {n}; "
            f"rejected by {rejected}; constraints: {checker.constraints.describe()}. "
            "Loosen the floor height, tilt limit or joint ranges"
        )
    return np.array(kept_q), np.array(kept_rotations), sampled


def _refine(checker, q, rotations, factors, rng, progress):
    """Perturb each pose at random; keep the best feasible change that raises ``log det``.

    Per pose and step size, :data:`REFINE_TRIES` perturbations are drawn and
    evaluated together (their information and ``log det`` as batches); the
    costly self-collision test runs last, on the best improving ones only.
    """
    contributions = np.array([f.T @ f for f in factors(rotations)])
    information = contributions.sum(axis=0)
    with Progress(len(REFINE_STEPS) * len(q), "refining poses", enabled=progress) as bar:
        for step in REFINE_STEPS:
            for slot in range(len(q)):
                current = log_det(information)
                without = information - contributions[slot]
                tried = q[slot] + rng.normal(0.0, step, size=(REFINE_TRIES, q.shape[1]))
                tried = tried[np.all((tried >= checker.lower) & (tried <= checker.upper), axis=1)]
                feasible = [
                    (x, rotation)
                    for x in tried
                    if (rotation := checker.check(x, collision=False)) is not None
                ]
                bar.advance()
                if not feasible:
                    continue
                factor = factors(np.array([rotation for _, rotation in feasible]))
                candidates = np.transpose(factor, (0, 2, 1)) @ factor
                sign, values = np.linalg.slogdet(without + candidates)
                values = np.where(sign > 0, values, -np.inf)
                for best in np.argsort(-values, kind="stable"):
                    if not values[best] > current:
                        break
                    if not checker.in_collision(feasible[best][0]):
                        q[slot], rotations[slot] = feasible[best]
                        contributions[slot] = candidates[best]
                        information = without + candidates[best]
                        break
    return q, rotations
