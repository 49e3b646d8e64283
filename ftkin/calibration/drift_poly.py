"""The polynomial drift ``"poly:N"``: ``b(t) = b(T) + Σ_k c_k ((t − T) / span)^k``, ``k = 1..N``.

The coefficients ``c_k`` [N, N·m] enter the prediction linearly: they are
fitted with ``θ`` by Gauss–Newton, and ``θ``'s covariance is its block of the
inverse of the full information, so every standard error includes what the
drift costs (:mod:`ftkin.calibration.drift_fit`).
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from .drift import DriftModel, register_drift_model

MAX_POLY_DEGREE = 5
"""Highest polynomial degree accepted for ``drift="poly:N"``."""


@dataclass(frozen=True)
class PolynomialDrift(DriftModel):
    """A polynomial trend of degree :attr:`columns`."""

    def basis(self, tau: np.ndarray) -> np.ndarray:
        return np.asarray(tau, dtype=float)[:, None] ** np.arange(1, self.columns + 1)


def polynomial(argument: str | None) -> PolynomialDrift:
    """``PolynomialDrift`` of the degree in ``argument`` (``"2"`` for ``poly:2``)."""
    if argument is None or not argument.isdigit():
        raise InvalidInput(f"drift 'poly' needs its degree: poly:N with N in 1..{MAX_POLY_DEGREE}")
    degree = int(argument)
    if not 1 <= degree <= MAX_POLY_DEGREE:
        raise InvalidInput(
            f"drift polynomial degree must be 1..{MAX_POLY_DEGREE}, got {degree} (poly:0 is "
            "drift='none')"
        )
    return PolynomialDrift(f"poly:{degree}", degree)


register_drift_model("poly", polynomial, usage="poly:N", auto=("poly:1", "poly:2", "poly:3"))
