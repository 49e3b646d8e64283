"""Fitting the drift models of :mod:`ftkin.calibration.drift` and choosing among them.

Both drift models extend the maximum-likelihood problem of :mod:`ftkin.calibration.ml`
(per-pose mean readings, per-reading noise ``σ`` per channel) and keep its
parameters ``θ = [a, F0, M0, P]``, with ``F0``, ``M0`` the bias at the end ``T``
of the recording:

* ``poly:N`` adds ``6N`` coefficients (linear in them): ``θ`` and the
  coefficients are fitted together by Gauss–Newton on the whitened residuals,
  and ``θ``'s covariance is its block of the inverse of the full information
  (so the standard errors include what the drift costs).
* ``random-walk`` integrates the walk out: the residuals and the Jacobian of
  ``θ`` are whitened by the Kalman filter (:mod:`ftkin.calibration.random_walk`),
  ``θ`` is the generalized least-squares fit and the rates [N/√s, N·m/√s] (and
  the noise, when neither given nor measured by the spread of repeated readings)
  maximize the marginal likelihood (Nelder–Mead on their logarithms). The
  covariance of ``θ`` is conditional on the rates.

``random-walk+poly:N`` is the walk around a polynomial trend (its
coefficients join ``θ`` in the generalized least squares).

``auto`` compares none, poly:1..3, random-walk and random-walk+poly:1..2 by the Bayesian information
criterion ``BIC = −2 log L + k log(6P)`` (``k`` parameters including the
estimated noise levels and rates, ``P`` poses): a drift must pay for itself, so
on a constant bias ``none`` wins (a slightly looser penalty than cross-validation,
and cheap).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import UnobservableParameters
from .drift import BiasDrift
from .information import SensorNoise, noise_floor
from .model import COMPONENT_NAMES, SensorModel, parameter_jacobian, predict
from .samples import PoseAverages

AUTO_CANDIDATES = (
    "none",
    "poly:1",
    "poly:2",
    "poly:3",
    "random-walk",
    "random-walk+poly:1",
    "random-walk+poly:2",
)
"""Models ``drift="auto"`` compares."""

_GROUPS = (slice(0, 3), slice(3, 6))


@dataclass(frozen=True)
class WhitenedFit:
    """Whitened residuals and hat blocks of a drift fit, in pose order (what the diagnostics
    read).
    """

    residuals: np.ndarray
    hat: np.ndarray

    def whitened_residuals(self, theta=None) -> np.ndarray:
        """``(6P,)`` whitened residuals (``theta`` ignored: they are those of the fit)."""
        return self.residuals.reshape(-1)

    def hat_blocks(self, theta=None) -> np.ndarray:
        """``(P, 6, 6)`` per-pose blocks of the hat matrix."""
        return self.hat


@dataclass(frozen=True)
class DriftFit:
    """A drift model's fit, shaped like :class:`~ftkin.calibration.ml.MlFit` for
    :func:`~ftkin.calibration.fit_quality.diagnose`.

    Attributes:
        model: ``θ`` with the bias at the end of the recording.
        problem: Whitened residuals and hat blocks (:class:`WhitenedFit`).
        channel_std: ``(6,)`` per-reading noise [N, N·m].
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        noise_dof: Degrees of freedom of the noise estimate.
        information: ``(12, 12)`` information of ``θ`` with the drift parameters marginalized.
        parameter_count: Fitted parameters (``θ``, drift coefficients or rates, estimated noise
        levels).
        log_likelihood: Gaussian log-likelihood of the pose means at the fit.
        drift: The bias trajectory.
    """

    model: SensorModel
    problem: WhitenedFit
    channel_std: np.ndarray
    noise_source: str
    noise_dof: float
    information: np.ndarray
    parameter_count: int
    log_likelihood: float
    drift: BiasDrift
    loss: str = "linear"

    @property
    def noise(self) -> SensorNoise:
        """Per-reading noise used [N, N·m]."""
        return SensorNoise(self.channel_std[:3], self.channel_std[3:])

    @property
    def covariance(self) -> np.ndarray:
        """``(12, 12)`` covariance of ``θ``."""
        return np.linalg.inv(self.information)

    @property
    def bic(self) -> float:
        """Bayesian information criterion ``−2 log L + k log(6P)``."""
        return -2.0 * self.log_likelihood + self.parameter_count * np.log(
            self.problem.residuals.size
        )


def predict_with_jacobian(
    theta: np.ndarray, rotations: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The model's prediction ``(P, 6)`` and its Jacobian ``(P, 6, 12)`` for ``θ``."""
    return predict(rotations, theta), parameter_jacobian(rotations, theta[0:3], theta[9:12])


def invert_information(information: np.ndarray, names: list[str]) -> np.ndarray:
    """Inverse of an information matrix, or :class:`UnobservableParameters` when it is singular."""
    scale = np.sqrt(np.diag(information))
    if np.any(scale == 0):
        raise UnobservableParameters(
            [names[i] for i in np.flatnonzero(scale == 0)],
            "the poses carry no information about them",
        )
    eigenvalues, eigenvectors = np.linalg.eigh(information / np.outer(scale, scale))
    if eigenvalues[0] <= 1e-12 * eigenvalues[-1]:
        weakest = eigenvectors[:, 0]
        raise UnobservableParameters(
            [names[i] for i in np.flatnonzero(np.abs(weakest) > 0.3)],
            "the drift model cannot be told apart from them with these poses and times (record the "
            "poses in a "
            "mixed order, or choose a simpler drift model)",
            singular_values=eigenvalues[::-1],
        )
    return (eigenvectors / eigenvalues) @ eigenvectors.T / np.outer(scale, scale)


def _leverage_dof(
    whitened_jacobian: np.ndarray, covariance: np.ndarray
) -> tuple[np.ndarray, float]:
    """Per-pose hat blocks ``(P, 6, 6)`` and the smaller channel group's ``Σ (1 − h)``."""
    hat = whitened_jacobian @ covariance @ np.transpose(whitened_jacobian, (0, 2, 1))
    leverage = np.diagonal(hat, axis1=1, axis2=2)
    return hat, float(min(np.sum(1.0 - leverage[:, group]) for group in _GROUPS))


def _gaussian_log_likelihood(residuals: np.ndarray, variance: np.ndarray) -> float:
    return float(-0.5 * np.sum(residuals**2 / variance + np.log(2.0 * np.pi * variance)))


def _profiled_std(residuals: np.ndarray, counts: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """ML per-reading noise ``(6,)`` (forces and torques pooled) from raw residuals of pose means,
    at least the floor.
    """
    scaled = residuals**2 * counts[:, None]
    std = np.concatenate([np.full(3, np.sqrt(np.mean(scaled[:, group]))) for group in _GROUPS])
    return np.maximum(std, noise_floor(wrenches))


def constant_log_likelihood(
    poses: PoseAverages, theta: np.ndarray, channel_std: np.ndarray, estimated: bool
) -> float:
    """Log-likelihood of the constant-bias fit ``θ`` (at the ML noise when the noise is
    ``estimated``).
    """
    residuals = poses.wrenches - predict_with_jacobian(theta, poses.rotations)[0]
    counts = np.asarray(poses.counts, dtype=float)
    std = _profiled_std(residuals, counts, poses.wrenches) if estimated else channel_std
    return _gaussian_log_likelihood(residuals, std[None, :] ** 2 / counts[:, None])


class SortedPoses:
    """Poses in time order, and the permutation back."""

    def __init__(self, poses: PoseAverages):
        self.order = np.argsort(poses.times, kind="stable")
        self.times = np.asarray(poses.times)[self.order]
        self.rotations = poses.rotations[self.order]
        self.wrenches = poses.wrenches[self.order]
        self.counts = np.asarray(poses.counts, dtype=float)[self.order]
        self.span = float(self.times[-1] - self.times[0])

    def unsort(self, array: np.ndarray) -> np.ndarray:
        out = np.empty_like(array)
        out[self.order] = array
        return out


def finish_fit(
    data: SortedPoses,
    theta,
    channel_std,
    source,
    whitened,
    jacobian,
    covariance,
    count,
    log_l,
    drift,
) -> DriftFit:
    hat, dof = _leverage_dof(jacobian, covariance)
    information = np.linalg.inv(covariance[:12, :12])
    return DriftFit(
        SensorModel.from_vector(theta),
        WhitenedFit(data.unsort(whitened), data.unsort(hat)),
        channel_std,
        source,
        dof if source == "residuals" else np.inf,
        information,
        count,
        log_l,
        drift,
    )


def polynomial_columns(
    data: SortedPoses, degree: int
) -> tuple[np.ndarray, np.ndarray, float, list[str]]:
    """Powers ``((t − T)/span)^k`` ``(P, K)``, their Jacobian columns ``(P, 6, 6K)``, the span [s]
    and the parameter names.
    """
    scale = data.span if data.span > 0 else 1.0
    powers = ((data.times - data.times[-1]) / scale)[:, None] ** np.arange(1, degree + 1)[None, :]
    columns = np.zeros((len(data.times), 6, 6 * degree))
    for k in range(degree):
        columns[:, :, 6 * k : 6 * k + 6] = powers[:, k, None, None] * np.eye(6)
    names = list(COMPONENT_NAMES) + [
        f"drift c{k + 1}[{c}]" for k in range(degree) for c in range(6)
    ]
    return powers, columns, scale, names


def trend_std(powers: np.ndarray, covariance: np.ndarray) -> np.ndarray:
    """``(P, 6)`` standard deviation of ``b(T) + Σ c_k τ^k`` from the covariance of ``[θ, c]``."""
    degree = powers.shape[1]
    rows = np.column_stack([np.ones(len(powers)), powers])
    out = np.empty((len(powers), 6))
    for c in range(6):
        indices = [3 + c] + [12 + 6 * k + c for k in range(degree)]
        block = covariance[np.ix_(indices, indices)]
        out[:, c] = np.sqrt(np.clip(np.einsum("ni,ij,nj->n", rows, block, rows), 0.0, None))
    return out


def fit_polynomial(
    poses: PoseAverages,
    theta0: np.ndarray,
    channel_std: np.ndarray,
    source: str,
    degree: int,
    selected_by: str = "given",
) -> DriftFit:
    """Fit ``θ`` and a degree-``degree`` polynomial bias drift (noise re-estimated from the
    residuals if ``source`` says so).
    """
    data = SortedPoses(poses)
    powers, drift_jacobian, scale, names = polynomial_columns(data, degree)
    count = 12 + 6 * degree
    phi = np.concatenate([theta0, np.zeros(6 * degree)])
    std = np.array(channel_std, dtype=float)
    for _ in range(4 if source == "residuals" else 1):
        weights = np.sqrt(data.counts)[:, None] / std[None, :]
        for _ in range(30):
            prediction, jacobian = predict_with_jacobian(phi[:12], data.rotations)
            residuals = data.wrenches - prediction - powers @ phi[12:].reshape(degree, 6)
            full = np.concatenate([jacobian, drift_jacobian], axis=2) * weights[:, :, None]
            whitened = residuals * weights
            step = np.linalg.lstsq(full.reshape(-1, count), whitened.reshape(-1), rcond=None)[0]
            phi = phi + step
            if np.sum((full.reshape(-1, count) @ step) ** 2) < 1e-12 * (1.0 + np.sum(whitened**2)):
                break
        prediction, jacobian = predict_with_jacobian(phi[:12], data.rotations)
        residuals = data.wrenches - prediction - powers @ phi[12:].reshape(degree, 6)
        full = np.concatenate([jacobian, drift_jacobian], axis=2) * weights[:, :, None]
        covariance = invert_information(full.reshape(-1, count).T @ full.reshape(-1, count), names)
        if source != "residuals":
            break
        hat, _ = _leverage_dof(full, covariance)
        leverage = np.diagonal(hat, axis1=1, axis2=2)
        scaled = residuals**2 * data.counts[:, None]
        new = np.concatenate(
            [
                np.full(3, np.sqrt(np.sum(scaled[:, g]) / max(np.sum(1.0 - leverage[:, g]), 1e-12)))
                for g in _GROUPS
            ]
        )
        new = np.maximum(new, noise_floor(data.wrenches))
        converged = np.allclose(new, std, rtol=1e-3)
        std = new
        if converged:
            break
    estimated = source == "residuals"
    log_l_std = _profiled_std(residuals, data.counts, data.wrenches) if estimated else std
    log_l = _gaussian_log_likelihood(residuals, log_l_std[None, :] ** 2 / data.counts[:, None])
    bias = phi[3:9] + powers @ phi[12:].reshape(degree, 6)
    drift = BiasDrift(
        f"poly:{degree}",
        selected_by,
        data.times,
        bias,
        trend_std(powers, covariance),
        coefficients=phi[12:].reshape(degree, 6),
        time_scale=scale,
    )
    return finish_fit(
        data,
        phi[:12],
        std,
        source,
        residuals * weights,
        full,
        covariance,
        count + 2 * estimated,
        log_l,
        drift,
    )
