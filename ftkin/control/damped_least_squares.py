"""Twist to joint velocities near singularities: damped least squares (Nakamura–Hanafusa).

One LAPACK ``dposv`` call factors ``J Jᵀ`` and solves, and its Cholesky factor
gives the manipulability for free (no SVD on the control path).
"""

import math

import numpy as np

_posv = None
"""LAPACK's ``dposv`` (Cholesky factor and solve in one call), loaded with scipy on first use."""


def damped_least_squares(
    jacobian: np.ndarray,
    twist: np.ndarray,
    manipulability_threshold: float = 0.005,
    max_damping: float = 0.05,
) -> tuple[np.ndarray, float, float]:
    """``dq = Jᵀ(J Jᵀ + λ² I)⁻¹ V`` with λ growing near singularities.

    The damping follows Nakamura and Hanafusa: with the manipulability
    ``w = sqrt(det(J Jᵀ))``, ``λ² = λ_max² (1 − w/w₀)²`` for ``w < w₀``, else 0.
    ``w`` comes free from the Cholesky factor of ``J Jᵀ`` (no SVD on the hot path).

    Args:
        jacobian: ``(6, nq)`` [m/rad, 1] (``[v; ω] = J dq``).
        twist: ``(6,)`` ``[v; ω]`` wanted [m/s, rad/s] (an array or six floats).
        manipulability_threshold: ``w₀``.
        max_damping: ``λ_max``.

    Returns:
        ``dq`` ``(nq,)`` [rad/s], the manipulability ``w`` and ``λ``.
    """
    global _posv
    if _posv is None:
        from scipy.linalg.lapack import dposv as _posv
    gram = np.dot(jacobian, jacobian.T)
    factor, solution, info = _posv(
        gram, twist
    )  # one factorisation (gram kept); w from its diagonal
    manipulability = math.prod(factor.diagonal().tolist()) if info == 0 else 0.0
    if manipulability >= manipulability_threshold:
        return (
            np.dot(solution, jacobian),
            manipulability,
            0.0,
        )  # Jᵀ x (np.dot: less overhead than @ on 6×6)
    damping = max_damping * (1.0 - manipulability / manipulability_threshold)
    gram.flat[::7] += damping * damping
    return np.dot(_posv(gram, twist, overwrite_a=True)[1], jacobian), manipulability, damping
