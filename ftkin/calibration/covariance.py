"""Covariance of a fit: the information inverted once, what it cannot determine named by one rule.

Every fit (static ``ml``, drift, IMU, fused, dynamic from joints or from the IMU) and every
observability check reads its parameters' determination here, from its **whitened Jacobian**
``J``. ftkin has one sign for it: ``J`` is the derivative of the whitened *prediction*,
``∂(f(x) · w)/∂x`` with ``w = sqrt(n) / σ`` per channel; the whitened residuals
``(measured − f(x)) · w`` have ``−J`` as theirs (what a solver is handed). Every problem's
``whitened_jacobian`` follows it (tested against finite differences of its ``predict``).

* The information ``JᵀJ`` is inverted in unit-diagonal scaling (``J``'s columns at unit norm),
  so parameters in N, N·m, m, kg and rad weigh alike. It is singular when its smallest eigenvalue
  is at most :data:`RCOND` times its largest: a relative singular value of ``J`` of
  ``sqrt(RCOND)`` = 1e-6, where rounding starts to decide the covariance.
* An observability check (which refuses poses that *barely* determine a parameter) reads the
  same spectrum with its own, larger threshold
  (:data:`~ftkin.calibration.observability.MIN_RELATIVE_SINGULAR_VALUE`).
* Either way the error names the parameters whose component in an open direction (one below
  the threshold, in unit scaling) is above :data:`NAMED_SHARE` of that direction's largest
  component (the union over the open directions), and carries the weakest direction in the
  parameters' own units (:attr:`~ftkin.exceptions.UnobservableParameters.combination`), e.g.
  ``+1 gravity_in_base[x] −1 force_offset[x]`` for poses that only turn about the sensor's x
  axis.

Derived quantities (mass, centre of mass, tilt, inertia) get their covariance by the delta
method, :func:`delta_method`; a rotation increment is turned into the sensor's axes by
:func:`covariance_in_sensor_axes`.
"""

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from ..exceptions import UnobservableParameters

RCOND = 1e-12
"""Smallest eigenvalue of the unit-diagonal information, relative to its largest, that is still
inverted (a relative singular value of the whitened Jacobian of 1e-6)."""

NAMED_SHARE = 0.3
"""A parameter is named undetermined when its component in an open direction (unit scaling) is
above this share of that direction's largest component."""

DELTA_METHOD_STEP = 1e-6
"""Relative central-difference step of :func:`delta_method` (times ``max(1, |x_i|)``)."""


@dataclass(frozen=True)
class WeakestDirections:
    """How well a whitened Jacobian determines its parameters.

    Attributes:
        singular_values: ``(n,)`` singular values of the Jacobian with unit-norm columns,
            relative to the largest, largest first.
        names: The parameters the open directions involve (:data:`NAMED_SHARE` rule); those of
            the weakest direction when none is open.
        combination: The weakest direction in the parameters' own units, ``((name,
            coefficient), ...)`` over its named entries, the first coefficient 1.
    """

    singular_values: np.ndarray
    names: tuple[str, ...]
    combination: tuple[tuple[str, float], ...]

    @property
    def relative(self) -> float:
        """The smallest relative singular value."""
        return float(self.singular_values[-1])

    def error(self, reason: str, names=None) -> UnobservableParameters:
        """The :class:`~ftkin.exceptions.UnobservableParameters` for these directions (``names``
        replaces :attr:`names`, e.g. by their groups)."""
        return UnobservableParameters(
            self.names if names is None else names,
            reason,
            singular_values=self.singular_values,
            combination=self.combination,
        )


def _directions(relative, vectors, scale, names, threshold, named) -> WeakestDirections:
    """``relative`` ``(n,)`` ascending, ``vectors`` ``(n, n)`` its directions as columns (unit
    scaling); only the first ``named`` parameters are named (the rest are nuisance)."""
    count = len(names) if named is None else named
    open_ = relative <= threshold
    if not open_.any():
        open_[0] = True
    picked = set()
    for direction in np.abs(vectors[:count][:, open_]).T:
        if direction.max() > 0.0:
            picked |= set(np.flatnonzero(direction > NAMED_SHARE * direction.max()))
    weakest = vectors[:count, 0]
    own = np.flatnonzero(np.abs(weakest) > NAMED_SHARE * np.abs(weakest).max())
    physical = weakest / scale[:count]
    combination = tuple((names[i], float(physical[i] / physical[own[0]])) for i in own)
    return WeakestDirections(
        relative[::-1].copy(), tuple(names[i] for i in sorted(picked)), combination
    )


def _unit_scale(norms: np.ndarray) -> np.ndarray:
    """Column norms, a column without information kept at 1 (it then shows as an exactly zero
    direction, named by the same rule)."""
    return np.where(norms > 0.0, norms, 1.0)


def weakest_directions(
    jacobian, names: Sequence[str], threshold: float = np.sqrt(RCOND), named: int | None = None
) -> WeakestDirections:
    """The spectrum of a whitened Jacobian ``(rows, n)`` with unit-norm columns (its SVD), the
    directions below ``threshold`` (relative singular value) named; ``named``: only the first
    ``named`` parameters may be named (the others are per-pose nuisance)."""
    jacobian = np.asarray(jacobian, dtype=float)
    scale = _unit_scale(np.linalg.norm(jacobian, axis=0))
    wide = jacobian.shape[0] < jacobian.shape[1]  # fewer rows than parameters: the rest is open
    _, singular, vt = np.linalg.svd(jacobian / scale, full_matrices=wide)
    singular = np.concatenate([singular, np.zeros(len(vt) - len(singular))])
    relative = singular / singular[0] if singular[0] > 0.0 else singular
    return _directions(relative[::-1], vt[::-1].T, scale, names, threshold, named)


def check_determined(
    jacobian, names: Sequence[str], reason: str, threshold: float, named: int | None = None
) -> WeakestDirections:
    """:func:`weakest_directions`, or :class:`~ftkin.exceptions.UnobservableParameters` when the
    smallest relative singular value is below ``threshold`` (``reason`` says why)."""
    directions = weakest_directions(jacobian, names, threshold, named)
    if directions.relative < threshold:
        raise directions.error(
            f"{reason} (smallest relative singular value {directions.relative:.1e}, need at least "
            f"{threshold:.0e})"
        )
    return directions


def invert_information(
    information, names: Sequence[str], reason: str, named: int | None = None
) -> np.ndarray:
    """Inverse of an information matrix ``JᵀJ`` over the parameters ``names`` (in unit-diagonal
    scaling, module docstring), or :class:`~ftkin.exceptions.UnobservableParameters` naming the
    first ``named`` parameters' undetermined ones and the combination (``reason`` says why)."""
    information = np.asarray(information, dtype=float)
    scale = _unit_scale(np.sqrt(np.clip(np.diag(information), 0.0, None)))
    values, vectors = np.linalg.eigh(information / np.outer(scale, scale))
    if values[-1] > 0.0 and values[0] > RCOND * values[-1]:
        return (vectors / values) @ vectors.T / np.outer(scale, scale)
    relative = np.sqrt(np.clip(values, 0.0, None) / max(values[-1], 1e-300))
    raise _directions(relative, vectors, scale, names, np.sqrt(RCOND), named).error(reason)


def delta_method(
    function: Callable[[np.ndarray], np.ndarray], x, covariance
) -> tuple[np.ndarray, np.ndarray]:
    """``(gradient, G C Gᵀ)``: the covariance of ``function(x)`` from ``x``'s ``covariance`` ``C``
    by the delta method, ``G`` ``(m, n)`` by central differences (steps
    :data:`DELTA_METHOD_STEP` ``· max(1, |x_i|)``)."""
    x = np.asarray(x, dtype=float)
    gradient = np.empty((len(np.atleast_1d(function(x))), len(x)))
    for i in range(len(x)):
        step = np.zeros(len(x))
        step[i] = DELTA_METHOD_STEP * max(1.0, abs(x[i]))
        gradient[:, i] = (function(x + step) - function(x - step)) / (2.0 * step[i])
    return gradient, gradient @ covariance @ gradient.T


def covariance_in_sensor_axes(covariance, rotation0, start: int | None) -> np.ndarray:
    """``covariance`` with the rotation increment ``δ`` at entries ``start:start + 3`` (of ``R =
    R0 Exp(δ)``) turned into the sensor's axes (``R0 Exp(δ) = Exp(R0 δ) R0``); unchanged when
    ``start`` is None (the rotation was not estimated)."""
    covariance = np.array(covariance, dtype=float)
    if start is None:
        return covariance
    transform = np.eye(len(covariance))
    transform[start : start + 3, start : start + 3] = rotation0
    return transform @ covariance @ transform.T
