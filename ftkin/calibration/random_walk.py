"""The random-walk drift ``"random-walk"``: Kalman filter and Rauch–Tung–Striebel smoother.

Per channel ``c`` the per-pose mean reading is ``y_i = f_c(θ, R_i) + w_c(t_i) + e_i``
with ``e_i ~ N(0, σ_c² / n_i)`` and ``w_c`` a random walk of rate ``q_c``
[N/√s, N·m/√s]: ``w(t) − w(s) ~ N(0, q_c² |t − s|)``. The walk is anchored at
the last pose time ``T`` (``w(T) = 0``), so the bias in ``θ`` is the bias at the
end of the recording, the one to use afterwards.

The filter runs backwards in time from ``T`` (a random walk is reversible) and
starts exactly known (``w(T) = 0``, variance 0), so no diffuse prior is needed.
Its innovations ``ν_i`` with variances ``S_i`` are the residuals whitened by the
full covariance of the readings (a Cholesky factor in time order): they give the
exact Gaussian log-likelihood ``−½ Σ (ν²/S + log 2πS)`` and, applied to the
columns of ``∂f/∂θ``, the whitened Jacobian of a generalized least-squares fit
of ``θ`` with the walk integrated out. The smoother then gives the bias at every
pose time. Everything here works on poses sorted by time and on all six
channels at once. With a zero rate the filter is plain weighting by the noise
(gain 0): the fits of :mod:`ftkin.calibration.drift_fit` use the same code for
every model.

The model itself registers as ``"random-walk"`` in :mod:`ftkin.calibration.drift_walk`
(``"random-walk+poly:N"`` is a walk around a polynomial trend: a warm-up that a walk alone
would take for a fast one); this module is the filter alone, below every drift model, so
that :meth:`~ftkin.calibration.drift.DriftModel.information` and the fit use it without
importing a model.
"""

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class WalkGains:
    """Kalman gains of the backward filter (they depend on the variances only, not on the data).

    Attributes:
        innovation_variance: ``(P, 6)`` ``S_i``.
        gain: ``(P, 6)`` ``K_i = P⁻_i / S_i``.
        predicted_variance: ``(P, 6)`` ``P⁻_i`` (before the update at pose ``i``).
        filtered_variance: ``(P, 6)`` ``P⁺_i`` (after it).
    """

    innovation_variance: np.ndarray
    gain: np.ndarray
    predicted_variance: np.ndarray
    filtered_variance: np.ndarray


def walk_gains(times: np.ndarray, noise_variance: np.ndarray, rate: np.ndarray) -> WalkGains:
    """Gains for poses at ascending ``times`` ``(P,)`` [s], ``noise_variance`` ``(P, 6)``, ``rate``
    ``(6,)``.
    """
    count = len(times)
    if not np.any(rate):  # no walk: plain weighting by the noise
        zeros = np.zeros((count, 6))
        return WalkGains(np.asarray(noise_variance, dtype=float), zeros, zeros, zeros)
    growth = np.vstack([np.outer(np.diff(times), rate**2), np.zeros((1, 6))])  # from pose i+1 to i
    predicted, variance = np.empty((count, 6)), np.zeros(6)
    for i in range(count - 1, -1, -1):
        variance = variance + growth[i]
        predicted[i] = variance
        variance = variance * noise_variance[i] / (variance + noise_variance[i])  # the update
    innovation = predicted + noise_variance
    filtered = predicted * noise_variance / innovation  # the variances after each update
    return WalkGains(innovation, predicted / innovation, predicted, filtered)


def whiten(gains: WalkGains, columns: np.ndarray) -> np.ndarray:
    """Innovations ``ν_i / √S_i`` of ``columns`` ``(..., P, 6, m)`` (the filter is linear: one pass
    for all columns).

    Leading axes are independent sets of columns (e.g. candidate pose orders), whitened together.
    """
    if not np.any(gains.gain):  # no walk: the innovations are the columns
        return columns / np.sqrt(gains.innovation_variance)[:, :, None]
    out = np.empty_like(columns)
    state = np.zeros(columns.shape[:-3] + columns.shape[-2:])
    gain = gains.gain[:, :, None]
    scale = 1.0 / np.sqrt(gains.innovation_variance)[:, :, None]
    for i in range(columns.shape[-3] - 1, -1, -1):
        innovation = columns[..., i, :, :] - state
        out[..., i, :, :] = innovation * scale[i]
        state = state + gain[i] * innovation
    return out


def log_likelihood(gains: WalkGains, whitened_residuals: np.ndarray) -> float:
    """Gaussian log-likelihood of the readings from their whitened innovations ``(P, 6)``."""
    return float(
        -0.5
        * (np.sum(whitened_residuals**2) + np.sum(np.log(2.0 * np.pi * gains.innovation_variance)))
    )


def smooth(
    gains: WalkGains, times: np.ndarray, residuals: np.ndarray, rate: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """RTS-smoothed walk ``w(t_i)`` ``(P, 6)`` and its variance, from ``residuals = y − f(θ)`` ``(P,
    6)``.
    """
    # the filtered walk: the filter's state after pose i is y_i − (1 − K_i) ν_i
    innovations = whiten(gains, residuals[:, :, None])[:, :, 0] * np.sqrt(gains.innovation_variance)
    filtered = residuals - (1.0 - gains.gain) * innovations
    mean, variance = filtered.copy(), gains.filtered_variance.copy()
    steps = np.diff(times)
    for i in range(1, len(times)):
        # the filter moved from pose i to pose i-1; smooth pose i from pose i-1
        predicted_variance = gains.filtered_variance[i] + rate**2 * steps[i - 1]
        with np.errstate(invalid="ignore", divide="ignore"):
            gain = np.where(
                predicted_variance > 0.0, gains.filtered_variance[i] / predicted_variance, 0.0
            )
        mean[i] = filtered[i] + gain * (mean[i - 1] - filtered[i])
        variance[i] = gains.filtered_variance[i] + gain**2 * (variance[i - 1] - predicted_variance)
    return mean, np.clip(variance, 0.0, None)
