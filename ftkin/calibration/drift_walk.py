"""The random-walk drift ``"random-walk"``: ``b(t) − b(s) ~ N(0, q² |t − s|)`` per channel.

The walk needs no basis: :class:`~ftkin.calibration.drift.DriftModel` with ``walk=True`` is
the whole model (its bias between poses, its planning information, its file entries), and
the fit estimates the rates ``q`` [N/√s, N·m/√s] with the Kalman filter and smoother of
:mod:`ftkin.calibration.random_walk`. ``"random-walk+poly:N"`` is a walk around a polynomial
trend (a warm-up that a walk alone would take for a fast one). This module registers it,
like :mod:`ftkin.calibration.drift_poly` registers ``"poly:N"``.
"""

from .drift import DriftModel, register_drift_model, without_argument

register_drift_model(
    "random-walk",
    without_argument(DriftModel("random-walk", walk=True)),
    auto=("random-walk", "random-walk+poly:1", "random-walk+poly:2"),
    walk=True,
)
