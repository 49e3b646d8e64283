"""Visit calibration poses in an order that a drifting bias cannot spoil.

With a bias that wanders as a random walk of rate ``q`` [N/√s, N·m/√s]
(:mod:`ftkin.calibration.random_walk`), what the recording tells about the
tool depends on *when* each pose is visited, not only on which poses there are.
The tool's weight shows as the difference between readings with gravity in
opposite directions in the sensor frame; when those poses are minutes apart,
the bias has moved in between and the difference carries the drift too. On a
sensor drifting like :meth:`ftkin.sim.SensorDrift.typical`, 40 random poses in a
random order over 20 minutes lose about 40 % in the mass's standard error to
the drift (the bound with the walk integrated out, over the drift-free one);
visited in the order below, about 15–20 %.

:func:`drift_robust_order` maximizes the D-criterion of the Fisher
information of ``θ = [a, F0, M0, P]`` with the walk integrated out (the
readings whitened by the Kalman filter of :func:`~ftkin.calibration.random_walk.whiten`,
the information a ``random-walk`` calibration uses), the poses visited one every
``pose_interval`` seconds:

1. start from the better of the given order and a greedy one where each next
   pose turns gravity in the sensor frame as far as possible from the last;
2. then, in rounds, try :data:`SWAPS_PER_ROUND` random swaps of two poses at
   once (one batched filter pass) and keep the best one that raises the
   criterion; stop after :data:`PATIENCE` rounds without a gain or
   :data:`MAX_ROUNDS` rounds.

Poses that turn gravity around are far apart in joint space, so the arm moves
more between them: on the bundled arm about twice the joint travel of the
short-travel order. ``max_length`` bounds the path (the sum of joint-space
distances between consecutive poses [rad]); swaps beyond it are not taken,
and a greedy start beyond it is not used. Without a drift rate,
:func:`ftkin.plan_poses` orders for short travel instead.
"""

import numpy as np

from ..calibration.random_walk import walk_gains, whiten
from ..exceptions import InvalidInput
from ..validation import as_float_array, as_in_range
from .design import log_det
from .order import nearest_neighbour

SWAPS_PER_ROUND = 64
"""Random pair swaps tried together in one round."""
PATIENCE = 12
"""Rounds without a gain before the search stops."""
MAX_ROUNDS = 400
"""Upper bound on the rounds of the search."""
DEFAULT_POSE_INTERVAL = 10.0
"""Time from one calibration pose to the next [s] when not given: a move, settling and a few
readings.
"""


def check_drift_options(
    drift_rate, pose_interval, estimate_mount: str
) -> tuple[np.ndarray | None, float]:
    """``(rate (6,) or None, pose_interval [s])`` checked; a drift with a mount estimate is
    refused.

    The rate, ``[force N/√s, torque N·m/√s]``, is given per channel: each finite, ≥ 0 and one > 0;
    the time between poses, between 1 ms and a day.
    """
    if drift_rate is None:
        return None, pose_interval
    if estimate_mount != "none":
        raise InvalidInput(
            "a drifting bias and an estimated mount cannot be planned together "
            "(a drift-aware calibration keeps the mount fixed): drop drift_rate or estimate_mount"
        )
    rate = as_float_array(drift_rate, "drift_rate")
    if rate.shape != (2,):
        raise InvalidInput(
            f"drift_rate must be [force N/√s, torque N·m/√s] (two numbers), got shape {rate.shape}"
        )
    if (
        not np.all(np.isfinite(rate))
        or np.any(rate < 0)
        or not np.any(rate > 0)
        or np.any(rate > 100.0)
    ):
        raise InvalidInput(
            f"drift_rate must be two finite rates between 0 and 100 [N/√s, N·m/√s], not both 0, "
            f"got {rate.tolist()}"
        )
    return np.repeat(rate, 3), as_in_range(pose_interval, "pose_interval", 1e-3, 86400.0, "s")


def check_travel_ratio(value, drift_rate) -> float | None:
    """A bound on the drift order's joint travel, as a ratio to the short-travel order's (1 to 100),
    or None.
    """
    if value is None:
        return None
    if drift_rate is None:
        raise InvalidInput(
            "max_travel_ratio bounds the drift-robust order: it applies with drift_rate"
        )
    return as_in_range(
        value, "max_travel_ratio", 1.0, 100.0, "(× the short-travel order's joint travel)"
    )


def walk_information(jacobians: np.ndarray, gains) -> np.ndarray:
    """Fisher information ``(..., 12, 12)`` of ``θ`` from per-pose ``jacobians`` ``(..., P, 6, 12)``
    in visiting order.

    The leading axes are independent candidate orders; ``gains`` are the
    walk's Kalman gains for the ``P`` visiting slots
    (:func:`~ftkin.calibration.random_walk.walk_gains`).
    """
    whitened = whiten(gains, jacobians)
    return np.einsum("...pki,...pkj->...ij", whitened, whitened)


def drift_robust_order(
    model,
    rotations,
    *,
    rate,
    noise_std,
    readings_per_pose: int,
    pose_interval: float,
    rng: np.random.Generator,
    initial_order=None,
    distances=None,
    max_length: float | None = None,
) -> tuple[np.ndarray, float]:
    """Visiting order of poses that keeps the most information under a random-walk bias.

    Args:
        model: Expected tool (:class:`~ftkin.calibration.model.SensorModel`);
            its biases play no role.
        rotations: ``(P, 3, 3)`` sensor orientations ``R_BS`` of the poses.
        rate: ``(6,)`` expected walk rate [N/√s, N·m/√s] per channel.
        noise_std: ``(6,)`` noise of one reading [N, N·m] per channel.
        readings_per_pose: Readings averaged at each pose.
        pose_interval: Time from one pose to the next [s].
        rng: Random generator of the swap search (the order is deterministic for a seed).
        initial_order: Order to start from (default: as given); it must keep
            within ``max_length``.
        distances: ``(P, P)`` joint-space distances between the poses [rad]
            (with ``max_length``).
        max_length: Longest path through the poses [rad], or None (unbounded).

    Returns:
        The order (indices into ``rotations``) and its criterion, ``log det`` of
        the walk-integrated information of ``θ``.
    """
    rotations = np.asarray(rotations, dtype=float)
    count = len(rotations)
    if max_length is not None and distances is None:
        raise InvalidInput("max_length needs the distances between the poses")
    jacobians = model.parameter_jacobian(rotations)
    variance = np.asarray(noise_std, dtype=float) ** 2 / readings_per_pose
    gains = walk_gains(
        np.arange(count) * pose_interval, np.tile(variance, (count, 1)), np.asarray(rate, float)
    )
    gravity = np.einsum("nji,j->ni", rotations, model.gravity_in_base)
    gravity /= np.linalg.norm(gravity, axis=1, keepdims=True)
    starts = [np.arange(count) if initial_order is None else np.asarray(initial_order)]
    # Greedy orders where each next pose has gravity most opposite to the last one's.
    cosines = gravity @ gravity.T
    starts += [
        nearest_neighbour(cosines, start) for start in (starts[0][0], int(np.argmax(gravity[:, 2])))
    ]

    def admissible(orders: np.ndarray) -> np.ndarray:
        if max_length is None:
            return np.ones(len(orders), dtype=bool)
        return distances[orders[:, :-1], orders[:, 1:]].sum(axis=1) <= max_length * (1.0 + 1e-12)

    starts = np.array(starts)
    values = np.where(
        admissible(starts), log_det(walk_information(jacobians[starts], gains)), -np.inf
    )
    values[0] = log_det(walk_information(jacobians[starts[0]], gains))  # the given order counts
    order, best = starts[int(np.argmax(values))].copy(), float(np.max(values))
    if count < 2:
        return order, best
    idle = 0
    for _ in range(MAX_ROUNDS):
        pairs = np.sort(rng.integers(0, count, size=(SWAPS_PER_ROUND, 2)), axis=1)
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]
        candidates = np.tile(order, (len(pairs), 1))
        candidates[np.arange(len(pairs))[:, None], pairs] = order[pairs[:, ::-1]]
        values = np.where(
            admissible(candidates),
            log_det(walk_information(jacobians[candidates], gains)),
            -np.inf,
        )
        winner = int(np.argmax(values)) if len(values) else 0
        if len(values) and values[winner] > best + 1e-9:
            order, best, idle = candidates[winner], float(values[winner]), 0
        else:
            idle += 1
            if idle >= PATIENCE:
                break
    return order, best
