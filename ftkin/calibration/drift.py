"""A sensor bias that drifts with time: the models and the estimated trajectory.

Strain-gauge sensors drift (warm-up after power-on, temperature): when the
samples carry reading times, :func:`~ftkin.calibration.calibrate` can model the
bias ``[F0(t), M0(t)]`` [N, N·m, sensor frame] as a function of time while the
tool weight ``a`` and centre of mass ``P`` stay constant:

* ``"none"``: a constant bias (the static model of METHOD.md §3);
* ``"poly:N"``: a polynomial of degree ``N`` in time (``1 ≤ N ≤ 5``),
  ``b(t) = b(T) + Σ_k c_k ((t − T) / span)^k``;
* ``"random-walk"``: ``b(t) − b(s) ~ N(0, q² |t − s|)`` per channel with a
  drift rate ``q`` [N/√s] shared by the forces and one [N·m/√s] by the torques,
  estimated by maximum marginal likelihood (Kalman filter and
  Rauch–Tung–Striebel smoother, :mod:`ftkin.calibration.random_walk`);
* ``"random-walk+poly:N"``: a random walk around a polynomial trend (a
  warm-up plus wandering);
* ``"auto"``: the candidate with the lowest Bayesian information criterion
  among none, poly:1..3, random-walk and random-walk+poly:1..2 (see
  :mod:`ftkin.calibration.drift_fit`).

In every model the bias reported as ``force_offset``/``torque_offset`` is the
bias at the end of the recording ``T`` (the last pose time): the one to use
when compensating afterwards. :class:`BiasDrift` carries the whole trajectory.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array

MAX_POLY_DEGREE = 5
"""Highest polynomial degree accepted for ``drift="poly:N"``."""

DRIFT_CHOICES = ("auto", "none", "poly:N", "random-walk", "random-walk+poly:N")
"""The ``drift=`` values :func:`~ftkin.calibration.calibrate` accepts (``N`` a degree)."""

_POLY = re.compile(r"^(random-walk\+)?poly:(\d+)$")


def parse_drift(drift: str) -> tuple[str, int]:
    """``("auto"|"none"|"poly"|"random-walk", degree)`` from a ``drift=`` value (degree > 0 with a
    walk: its trend).

    Raises:
        InvalidInput: anything else, or a degree outside ``1..MAX_POLY_DEGREE``.
    """
    if not isinstance(drift, str):
        raise InvalidInput(
            f"drift must be a string ({', '.join(DRIFT_CHOICES)}), got {type(drift).__name__}"
        )
    if drift in ("auto", "none", "random-walk"):
        return drift, 0
    match = _POLY.match(drift)
    if match is None:
        raise InvalidInput(
            f"unknown drift model {drift!r}; expected one of {', '.join(DRIFT_CHOICES)}"
        )
    degree = int(match.group(2))
    if not 1 <= degree <= MAX_POLY_DEGREE:
        raise InvalidInput(
            f"drift polynomial degree must be 1..{MAX_POLY_DEGREE}, got {degree} (poly:0 is "
            "drift='none')"
        )
    return ("random-walk" if match.group(1) else "poly"), degree


def check_model_name(model) -> None:
    """Refuse anything but a fitted model's name (``"none"``, ``"poly:N"``, ``"random-walk"``,
    ``"random-walk+poly:N"``).
    """
    if model == "auto" or not isinstance(model, str):
        raise InvalidInput(
            f"unknown drift model {model!r}; a fitted trajectory is 'none', 'poly:N', "
            "'random-walk' "
            "or 'random-walk+poly:N'"
        )
    parse_drift(model)


@dataclass(frozen=True)
class BiasDrift:
    """The bias trajectory a drift-aware calibration found.

    Attributes:
        model: ``"none"``, ``"poly:N"``, ``"random-walk"`` or ``"random-walk+poly:N"``.
        selected_by: ``"auto"`` (chosen by the information criterion) or ``"given"``.
        times: ``(P,)`` pose times, ascending [s] (mean time of each pose's readings).
        bias: ``(P, 6)`` bias ``[F0, M0]`` at those times [N, N·m, sensor frame].
        bias_std: ``(P, 6)`` its standard deviation (the drift model's
            uncertainty at each time plus that of the end bias) [N, N·m].
        rate: ``(2,)`` random-walk rate [N/√s, N·m/√s] (``"random-walk"``), else None.
        coefficients: ``(N, 6)`` polynomial coefficients ``c_1..c_N`` [N, N·m]
            of ``((t − T) / time_scale)^k`` (``"poly:N"``, or the trend under a
            walk), else None.
        time_scale: ``span`` of the polynomial's time variable [s] (the recording's length).
        criteria: BIC of each candidate model ``auto`` compared (empty otherwise).
        recorded_span: ``(2,)`` first and last reading time of the recording [s]
            (the pose times are means, inside it), or None (the pose times' span).
    """

    model: str
    selected_by: str
    times: np.ndarray
    bias: np.ndarray
    bias_std: np.ndarray
    rate: np.ndarray | None = None
    coefficients: np.ndarray | None = None
    time_scale: float = 1.0
    criteria: dict = field(default_factory=dict)
    recorded_span: np.ndarray | None = None

    def __post_init__(self):
        check_model_name(self.model)
        if self.selected_by not in ("auto", "given"):
            raise InvalidInput(f"selected_by must be 'auto' or 'given', got {self.selected_by!r}")
        if not (np.isfinite(self.time_scale) and self.time_scale > 0):
            raise InvalidInput(f"time_scale must be a finite time > 0 [s], got {self.time_scale!r}")
        times = as_float_array(self.times, "times").reshape(-1).copy()  # frozen below: a copy
        if len(times) == 0 or np.any(np.diff(times) < 0) or not np.all(np.isfinite(times)):
            raise InvalidInput("drift times must be finite, ascending and not empty [s]")
        for name in ("bias", "bias_std"):
            value = as_float_array(
                getattr(self, name), name
            ).copy()  # frozen: a copy, never the caller's array
            if value.shape != (len(times), 6):
                raise InvalidInput(
                    f"drift {name} must have shape ({len(times)}, 6), got {value.shape}"
                )
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        times.setflags(write=False)
        object.__setattr__(self, "times", times)
        if self.rate is not None:
            rate = as_float_array(self.rate, "rate").reshape(-1)
            if rate.shape != (2,) or not np.all(np.isfinite(rate)) or np.any(rate < 0):
                raise InvalidInput(
                    f"rate must be [force N/√s, torque N·m/√s], finite and ≥ 0, got {rate.tolist()}"
                )
            object.__setattr__(self, "rate", rate)
        if self.recorded_span is not None:
            span = as_float_array(self.recorded_span, "recorded_span").reshape(-1)
            if span.shape != (2,) or not np.all(np.isfinite(span)) or span[0] > span[1]:
                raise InvalidInput(
                    f"recorded_span must be [first, last] reading time [s], got {span}"
                )
            object.__setattr__(self, "recorded_span", span)
        if self.coefficients is not None:
            coefficients = as_float_array(self.coefficients, "coefficients")
            if (
                coefficients.ndim != 2
                or coefficients.shape[1] != 6
                or not np.all(np.isfinite(coefficients))
            ):
                raise InvalidInput(
                    "coefficients must be finite, one row of six per degree, got shape "
                    f"{coefficients.shape}"
                )
            object.__setattr__(self, "coefficients", coefficients)

    @property
    def start_time(self) -> float:
        """First pose time [s]."""
        return float(self.times[0])

    @property
    def end_time(self) -> float:
        """Last pose time ``T`` [s]: the bias there is the calibration's
        ``force_offset``/``torque_offset``.
        """
        return float(self.times[-1])

    def covers(self, times) -> np.ndarray:
        """``(N,)`` True where ``times`` [s] fall inside the recording (:attr:`recorded_span`, else
        the pose times).
        """
        first, last = (
            self.recorded_span
            if self.recorded_span is not None
            else (self.times[0], self.times[-1])
        )
        times = as_float_array(times, "times").reshape(-1)
        return (times >= first) & (times <= last)

    @property
    def end_bias(self) -> np.ndarray:
        """``(6,)`` bias at the end of the recording [N, N·m]."""
        return self.bias[-1]

    @property
    def drift_range(self) -> np.ndarray:
        """``(6,)`` largest minus smallest bias over the recording [N, N·m]."""
        return np.ptp(self.bias, axis=0)

    def bias_at(self, times) -> np.ndarray:
        """Bias ``(N, 6)`` [N, N·m] at ``times`` ``(N,)`` [s] (``(6,)`` for a scalar).

        Inside the recorded span: the polynomial, or the smoothed random walk
        (linear between pose times: the exact conditional mean of a random
        walk). Outside: held at the first or last value (no extrapolation).
        """
        times = as_float_array(times, "times")
        single = times.ndim == 0
        times = np.clip(times.reshape(-1), self.times[0], self.times[-1])
        if self.coefficients is not None and self.rate is None:
            tau = (times - self.times[-1]) / self.time_scale
            powers = tau[:, None] ** np.arange(1, len(self.coefficients) + 1)[None, :]
            out = self.end_bias + powers @ self.coefficients
        else:
            out = np.column_stack([np.interp(times, self.times, self.bias[:, c]) for c in range(6)])
        return out[0] if single else out

    def describe(self) -> str:
        """One line: model, how it was chosen, range of the bias over the recording."""
        force_range, torque_range = self.drift_range[:3].max(), self.drift_range[3:].max()
        text = (
            f"{self.model} ({'chosen by BIC' if self.selected_by == 'auto' else 'given'}) over "
            f"{self.end_time - self.start_time:.4g} s; bias range up to {force_range:.4f} N, "
            f"{torque_range:.5f} N·m"
        )
        if self.rate is not None:
            text += f"; rate {self.rate[0]:.3g} N/√s, {self.rate[1]:.3g} N·m/√s"
        return text
