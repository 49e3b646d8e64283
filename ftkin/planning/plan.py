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

import functools
from dataclasses import dataclass, field, fields

import numpy as np

from ..calibration.observability import check_pose_count
from ..exceptions import InvalidInput
from ..progress import Progress
from ..validation import from_fields, set_checked, whole_number
from .constraints import (
    FeasibilityChecker,
    PoseConstraints,
    check_information,
    check_tilt_observability,
)
from .design import d_optimal_selection, information_factors, log_det
from .drift_order import check_travel_ratio, drift_robust_order
from .evaluation import (
    ExpectedCalibration,
    PoseEvaluation,
    evaluate_poses,
)
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
            f"candidates from {self.sampled_count} sampled",
            f"constraints: {self.constraints.describe()}",
            f"criterion: {self.criterion} = {self.criterion_value:.3f}",
            f"joint travel along the visiting order: {self.joint_travel:.1f} rad",
            self.evaluation.report(),
        ]
        return "\n".join(lines)

    def pose_table(self) -> str:
        """The joint positions [rad] in visiting order, one line per pose (``ftkin plan``
        prints it after :meth:`report`); joint names cut to 12 characters."""
        header = f"{'pose':>4} " + " ".join(f"{name[:12]:>12}" for name in self.joint_names)
        rows = [
            f"{i:>4} " + " ".join(f"{value:>12.4f}" for value in q)
            for i, q in enumerate(self.joint_positions)
        ]
        return "joint positions [rad], in visiting order:\n" + "\n".join([header, *rows])


@dataclass(frozen=True, eq=False)
class PlanSpec:
    """What to plan: how many poses, within which limits, for which calibration, how to search.

    Attributes:
        n: Number of poses (≥ 3).
        constraints: Limits every pose meets (:class:`PoseConstraints`).
        expected: The calibration the poses are for: tool, noise, readings per pose, mount,
            drift (:class:`~ftkin.planning.evaluation.ExpectedCalibration`).
        seed: Random seed; the plan is deterministic for a seed.
        candidates: Feasible configurations to collect for the pool (at least ``n``).
        max_samples: Give up after drawing this many random configurations.
        max_travel_ratio: With a drift rate: the joint travel along the
            drift-robust order stays within this multiple (≥ 1) of the
            short-travel order's (None: unbounded, about 2× on the bundled arm).
    """

    n: int
    constraints: PoseConstraints = field(default_factory=PoseConstraints)
    expected: ExpectedCalibration = field(default_factory=ExpectedCalibration)
    seed: int = 0
    candidates: int = 3000
    max_samples: int = 200_000
    max_travel_ratio: float | None = None

    def __post_init__(self):
        n = whole_number(self.n, "n (number of poses)")
        check_pose_count(n)
        if not isinstance(self.constraints, PoseConstraints):
            raise InvalidInput(f"constraints must be PoseConstraints, got {self.constraints!r}")
        if not isinstance(self.expected, ExpectedCalibration):
            raise InvalidInput(f"expected must be ExpectedCalibration, got {self.expected!r}")
        set_checked(
            self,
            n=n,
            seed=whole_number(self.seed, "seed"),
            candidates=max(whole_number(self.candidates, "candidates", 1), n),
            max_samples=whole_number(self.max_samples, "max_samples", 1),
            max_travel_ratio=check_travel_ratio(self.max_travel_ratio, self.expected.drift_rate),
        )

    @classmethod
    def from_options(cls, n: int, **options) -> "PlanSpec":
        """A spec from flat keywords: the fields of :class:`PoseConstraints` (``margin``,
        ``floor_height``, ``max_tilt``, ``joint_ranges``, ``self_collision``), of
        :class:`~ftkin.planning.evaluation.ExpectedCalibration` (``tool_weight``, ``noise``,
        ``drift_rate``, ...) and of the spec itself (``seed``, ``candidates``, ...).
        """
        parts: dict[type, dict] = {PoseConstraints: {}, ExpectedCalibration: {}, cls: {}}
        for name, value in options.items():
            owner = next((p for p in parts if name in {f.name for f in fields(p) if f.init}), cls)
            parts[owner][name] = value
        return from_fields(
            cls,
            {
                "n": n,
                "constraints": from_fields(
                    PoseConstraints, parts[PoseConstraints], "PoseConstraints"
                ),
                "expected": from_fields(
                    ExpectedCalibration, parts[ExpectedCalibration], "plan_poses"
                ),
                **parts[cls],
            },
            "plan_poses",
        )


def plan_poses(arm, spec: PlanSpec | int, *, progress: bool | None = None, **options) -> PosePlan:
    """Plan calibration poses for ``arm`` (see the module docstring).

    Two ways to call it: ``plan_poses(arm, PlanSpec(12, constraints=..., expected=...))``, or
    the shortcut ``plan_poses(arm, 12, floor_height=0.3, max_tilt=1.0, seed=0)`` with any field
    of :class:`PlanSpec`, :class:`PoseConstraints` and
    :class:`~ftkin.planning.evaluation.ExpectedCalibration` as a keyword
    (:meth:`PlanSpec.from_options`).

    Args:
        arm: :class:`~ftkin.kinematics.arm.Arm` with the sensor frame (and optionally a tool frame).
        spec: The plan specification, or the number of poses.
        progress: Draw a progress bar (default: when stderr is a terminal).
        **options: With a number of poses: the specification's fields by name.

    With a drift rate, the poses are visited in the order that keeps the most information with
    the drift integrated out (:func:`~ftkin.planning.drift_order.drift_robust_order`; longer
    joint travel), and the predicted standard errors include the drift.

    Raises:
        UnobservableParameters: ``n < 3``, or the constraints leave a
            parameter undetermined (the error names it and says why).
        InvalidInput: bad arguments, or too few feasible configurations
            (the message names the constraints and what rejected them).
    """
    if not isinstance(spec, PlanSpec):
        spec = PlanSpec.from_options(spec, **options)
    elif options:
        raise InvalidInput("give a PlanSpec or the number of poses with keywords, not both")
    expected = spec.expected
    checker = FeasibilityChecker(arm, spec.constraints)
    rng = np.random.default_rng(spec.seed)
    factors = functools.partial(
        information_factors,
        gravity_in_base=expected.model.gravity_in_base,
        center_of_mass=expected.model.center_of_mass,
        channel_std=expected.noise.channel_std,
        readings_per_pose=expected.readings_per_pose,
        estimate_mount=expected.estimate_mount,
    )

    check_tilt_observability(checker, factors)
    pool_q, pool_rotations, sampled = _candidate_pool(
        checker, rng, spec.candidates, spec.max_samples, spec.n, progress
    )
    pool_factors = factors(pool_rotations)
    check_information(pool_factors, spec.constraints)
    chosen, _ = d_optimal_selection(pool_factors, spec.n)
    q, rotations = _refine(checker, pool_q[chosen], pool_rotations[chosen], factors, rng, progress)
    q = unwind_revolute(q, checker.lower, checker.upper, revolute_mask(arm.model))
    order = _visiting_order(q, rotations, spec, rng)
    q, rotations = q[order], rotations[order]
    evaluation = evaluate_poses(rotations, expected)
    drifting = expected.drift_rate is not None
    factor = factors(rotations)
    return PosePlan(
        joint_positions=q,
        joint_names=tuple(arm.joint_names),
        evaluation=evaluation,
        criterion=DRIFT_CRITERION if drifting else CRITERION,
        criterion_value=log_det(
            evaluation.information if drifting else np.einsum("nki,nkj->ij", factor, factor)
        ),
        seed=spec.seed,
        constraints=spec.constraints,
        candidate_count=len(pool_q),
        sampled_count=sampled,
    )


def _visiting_order(q, rotations, spec: PlanSpec, rng) -> np.ndarray:
    """Short joint travel; with a drift rate, the drift-robust order (within the travel bound)."""
    order, expected = short_travel_order(q), spec.expected
    if expected.drift_rate is None:
        return order
    distances, ratio = joint_distances(q), spec.max_travel_ratio
    order, _ = drift_robust_order(
        expected.model,
        rotations,
        rate=expected.drift_rate,
        noise_std=expected.noise.channel_std,
        readings_per_pose=expected.readings_per_pose,
        pose_interval=expected.pose_interval,
        rng=rng,
        initial_order=order,
        distances=distances,
        max_length=None if ratio is None else ratio * path_length(distances, order),
    )
    return order


def _candidate_pool(checker, rng, wanted, max_samples, n, progress):
    kept_q, kept_rotations, sampled = [], [], 0
    with Progress(wanted, "sampling poses", enabled=progress) as bar:
        while len(kept_q) < wanted and sampled < max_samples:
            for q in checker.sample(min(SAMPLE_BATCH, max_samples - sampled), rng):
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
                values = log_det(without + candidates)
                for best in np.argsort(-values, kind="stable"):
                    if not values[best] > current:
                        break
                    if not checker.in_collision(feasible[best][0]):
                        q[slot], rotations[slot] = feasible[best]
                        contributions[slot] = candidates[best]
                        information = without + candidates[best]
                        break
    return q, rotations
