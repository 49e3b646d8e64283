"""D-optimal choice of poses from a candidate pool (greedy start + Fedorov exchange).

Each candidate pose ``i`` contributes ``L_iᵀ L_i`` to the Fisher information of
``θ = [a, F0, M0, P]``, with ``L_i = W^{1/2} J_i`` (``(6, 12)``: the parameter
Jacobian of one reading weighted by the channel noise, see
:func:`ftkin.calibration.information.fisher_information`). A design is a set of distinct
candidates; its information is the sum of their contributions.

The criterion is D-optimality, ``log det`` of the information: it does not
depend on the units of the parameters (rescaling a parameter adds a
constant), so forces [N], torques [N·m] and lengths [m] need no weights, and
it minimizes the volume of the joint confidence ellipsoid. Adding candidate
``i`` to a design with information ``M`` changes ``log det`` by
``log det(I₆ + L_i M⁻¹ L_iᵀ)`` (matrix determinant lemma), which is
evaluated for the whole pool at once.
"""

from __future__ import annotations

import numpy as np

from ..calibration.mount import mount_jacobian

REGULARIZATION = 1e-9
"""Ridge added to the (scale-normalized) information so that designs with
fewer poses than needed for full rank can still be compared while the
greedy start builds up."""


def information_factors(rotations: np.ndarray, gravity_in_base, center_of_mass, channel_std, readings_per_pose=1,
                        estimate_mount: str = "none"):
    """Weighted Jacobians ``L_i`` ``(N, 6, 12 + k)`` so that the information of pose ``i`` is ``L_iᵀ L_i``.

    ``k`` is 0, or the number of mount angles when ``estimate_mount`` is ``"yaw"`` (1) or ``"full"`` (3).
    """
    jac = mount_jacobian(rotations, gravity_in_base, center_of_mass, estimate_mount)
    return jac / np.asarray(channel_std, float)[None, :, None] * np.sqrt(readings_per_pose)


def log_det(information: np.ndarray) -> float:
    """``log det`` of a symmetric positive (semi)definite matrix; ``-inf`` when singular."""
    sign, value = np.linalg.slogdet(information)
    return float(value) if sign > 0 else -np.inf


def _gains(factors: np.ndarray, information: np.ndarray, factors_t: np.ndarray | None = None) -> np.ndarray:
    """``log det(M + L_iᵀ L_i) - log det(M)`` for every candidate ``i``.

    Computed as ``log det(I₆ + L_i M⁻¹ L_iᵀ)``, the 6×6 determinants from
    batched Cholesky factors (LU's ``slogdet`` if rounding makes one of them
    indefinite). ``factors_t``: the factors transposed ``(M, 12, 6)``, contiguous, if at hand.
    """
    if factors_t is None:
        factors_t = np.transpose(factors, (0, 2, 1))
    inner = factors @ np.linalg.inv(information) @ factors_t
    rows = np.arange(inner.shape[1])
    inner[:, rows, rows] += 1.0
    try:
        diagonals = np.linalg.cholesky(inner).diagonal(axis1=1, axis2=2)
    except np.linalg.LinAlgError:
        sign, value = np.linalg.slogdet(inner)
        return np.where(sign > 0, value, -np.inf)
    return 2.0 * np.log(diagonals).sum(axis=1)


def d_optimal_selection(factors: np.ndarray, count: int, max_passes: int = 20) -> tuple[np.ndarray, float]:
    """Choose ``count`` distinct candidates maximizing ``log det`` of their information.

    Greedy forward selection, then Fedorov exchange passes (swap a chosen
    pose for the best unchosen candidate while that raises the criterion)
    until a pass makes no swap. Deterministic for a given pool.

    Args:
        factors: ``(M, 6, 12)`` weighted Jacobians of the candidates
            (:func:`information_factors`), in any fixed parameter scaling.
        count: Number of poses to choose (``≤ M``).
        max_passes: Upper bound on exchange passes.

    Returns:
        Indices of the chosen candidates ``(count,)`` and the criterion
        ``log det`` of their (unregularized) information.
    """
    size = factors.shape[2]
    factors_t = np.ascontiguousarray(np.transpose(factors, (0, 2, 1)))
    contributions = factors_t @ factors
    ridge = REGULARIZATION * np.eye(size)
    chosen: list[int] = []
    information = ridge.copy()
    available = np.ones(len(factors), dtype=bool)
    for _ in range(count):
        gains = _gains(factors, information, factors_t)
        gains[~available] = -np.inf
        best = int(np.argmax(gains))
        chosen.append(best)
        available[best] = False
        information = information + contributions[best]
    for _ in range(max_passes):
        swapped = False
        for slot in range(count):
            current = log_det(information)
            without = information - contributions[chosen[slot]]
            gains = _gains(factors, without, factors_t)
            gains[~available] = -np.inf
            best = int(np.argmax(gains))
            if log_det(without) + gains[best] > current + 1e-9:
                available[chosen[slot]] = True
                available[best] = False
                chosen[slot] = best
                information = without + contributions[best]
                swapped = True
        if not swapped:
            break
    return np.array(chosen), log_det(information - ridge)
