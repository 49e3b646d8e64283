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

import numpy as np

from ..calibration.mount import mount_jacobian

REGULARIZATION = 1e-9
"""Ridge added to the scale-normalized information (each parameter scaled so
that a pool pose's mean information on it is 1) so that designs with fewer
poses than needed for full rank can still be compared while the greedy start
builds up. The normalization keeps the ridge relative: without it, a quiet
sensor or many readings per pose (information ~1e8) next to an absolute
ridge would make the first greedy steps numerically singular."""


def information_factors(
    rotations: np.ndarray,
    gravity_in_base,
    center_of_mass,
    channel_std,
    readings_per_pose=1,
    estimate_mount: str = "none",
):
    """Weighted Jacobians ``L_i`` ``(N, 6, 12 + k)`` so that the information of pose ``i`` is ``L_iᵀ
    L_i``.

    ``k`` is 0, or the number of mount angles when ``estimate_mount`` is ``"yaw"`` (1) or ``"full"``
    (3).
    """
    jacobian = mount_jacobian(rotations, gravity_in_base, center_of_mass, estimate_mount)
    return jacobian / np.asarray(channel_std, float)[None, :, None] * np.sqrt(readings_per_pose)


def log_det(information: np.ndarray):
    """``log det`` of a symmetric positive (semi)definite matrix; ``-inf`` when singular.

    A stack ``(..., n, n)`` gives an array of them; one matrix, a float.
    """
    sign, value = np.linalg.slogdet(information)
    return np.where(sign > 0, value, -np.inf)[()]


def _gains(entries: np.ndarray, information: np.ndarray) -> np.ndarray:
    """``log det(M + L_iᵀ L_i) - log det(M)`` for every candidate ``i``.

    Computed as ``log det(I₆ + L_i M⁻¹ L_iᵀ)``, the 6×6 determinants from
    Cholesky factors computed entry-wise over the batch (LU's ``slogdet`` if
    rounding makes one of them indefinite). ``entries``: the factors ``L``
    as ``(6, 12, M)`` (``entries[a, k]`` is ``L[:, a, k]``, contiguous), so
    that ``M⁻¹ Lᵀ`` is six matrix products and each entry of the 6×6 matrices
    one dot product over the batch.
    """
    rows = entries.shape[0]
    solved = np.linalg.inv(information) @ entries  # (6, 12, M): (M⁻¹ L_iᵀ) column by column
    inner = np.empty((rows, rows, entries.shape[2]))
    for a in range(rows):
        for b in range(a + 1):
            np.einsum("kn,kn->n", entries[a], solved[b], out=inner[a, b])
        inner[a, a] += 1.0
    value = _cholesky_log_det(inner)
    if value is None:
        lower = np.tril_indices(rows, -1)
        inner[lower[1], lower[0]] = inner[lower]  # the upper triangle, for LU
        return log_det(np.transpose(inner, (2, 0, 1)))
    return value


def _cholesky_log_det(entries: np.ndarray) -> np.ndarray | None:
    """``log det`` of symmetric positive definite matrices by a Cholesky factorisation; None if one
    is not.

    ``entries``: ``(n, n, M)``, ``entries[i, j]`` the ``(M,)`` values of entry
    ``(i, j)``; only the lower triangle (``i ≥ j``) is read.

    The factorisation runs on the ``(M,)`` arrays of the matrix entries, one
    entry at a time (Cholesky–Banachiewicz): for many small matrices this is a
    few times faster than LAPACK's batched ``cholesky`` (a call per matrix).
    ``log det`` is the log of the product of the pivots (one ``log``), or
    their sum of logs if the product leaves the float range.
    """
    n = entries.shape[0]
    lower: list[list[np.ndarray]] = [[] for _ in range(n)]
    pivots = []
    for j in range(n):
        pivot = (
            entries[j, j] - sum(value * value for value in lower[j]) if j else entries[j, j].copy()
        )
        if not np.all(pivot > 0.0):  # also NaN
            return None
        pivots.append(pivot)
        root = np.sqrt(pivot)
        for i in range(j + 1, n):
            off = (
                entries[i, j] - sum(a * b for a, b in zip(lower[i], lower[j]))
                if j
                else entries[i, j]
            )
            lower[i].append(off / root)
    with np.errstate(over="ignore"):
        product = np.prod(pivots, axis=0)
    if np.all(np.isfinite(product) & (product > 0.0)):
        return np.log(product)
    return np.log(pivots).sum(axis=0)


def d_optimal_selection(
    factors: np.ndarray, count: int, max_passes: int = 20
) -> tuple[np.ndarray, float]:
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
    scale = 1.0 / np.sqrt(
        np.maximum(np.mean(np.sum(factors**2, axis=1), axis=0), np.finfo(float).tiny)
    )
    factors = factors * scale  # log det changes by the constant 2 Σ log scale: same choices
    contributions = np.transpose(factors, (0, 2, 1)) @ factors
    entries = np.ascontiguousarray(np.transpose(factors, (1, 2, 0)))
    ridge = REGULARIZATION * np.eye(factors.shape[2])
    chosen: list[int] = []
    information = ridge.copy()
    available = np.ones(len(factors), dtype=bool)
    for _ in range(count):
        best = int(np.argmax(np.where(available, _gains(entries, information), -np.inf)))
        chosen.append(best)
        available[best] = False
        information = information + contributions[best]
    for _ in range(max_passes):
        swapped = False
        for slot in range(count):
            without = information - contributions[chosen[slot]]
            gains = np.where(available, _gains(entries, without), -np.inf)
            best = int(np.argmax(gains))
            if log_det(without) + gains[best] > log_det(information) + 1e-9:
                available[chosen[slot]] = True
                available[best] = False
                chosen[slot] = best
                information = without + contributions[best]
                swapped = True
        if not swapped:
            break
    return np.array(chosen), log_det(information - ridge) - 2.0 * float(np.sum(np.log(scale)))
