"""The random-walk drift fit, and ``drift="auto"``: which drift model the data support.

See :mod:`ftkin.calibration.drift_fit` for the models' likelihoods and the
information criterion, :mod:`ftkin.calibration.random_walk` for the filter.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from ..exceptions import UnobservableParameters
from .drift import BiasDrift
from .drift_fit import (
    AUTO_CANDIDATES,
    DriftFit,
    SortedPoses,
    constant_log_likelihood,
    finish_fit,
    fit_polynomial,
    invert_information,
    polynomial_columns,
    predict_with_jacobian,
    trend_std,
)
from .information import noise_floor
from .random_walk import log_likelihood, smooth, walk_gains, whiten
from .samples import PoseAverages

MAX_AUTO_WALK_POSES = 500
"""Above this many poses, ``auto`` compares the polynomial models only (``drift="random-walk"``
still fits the walk):
a stream without a pose column makes every reading a pose, and the walk's search would take
minutes.
"""
SEARCH_ITERATIONS = 2
"""Gauss–Newton steps of ``θ`` per likelihood evaluation while the rates are searched
(warm-started).
"""

FINAL_ITERATIONS = 20
"""Most Gauss–Newton steps of ``θ`` at the chosen rates."""

RATE_GRID = 10.0 ** np.arange(-4.0, 1.5, 1.0)
"""Multiples of the reference rate (per-pose noise over √(pose spacing)) tried before the
Nelder–Mead search.
"""


def _profile(
    data: SortedPoses,
    theta: np.ndarray,
    rate: np.ndarray,
    std: np.ndarray,
    iterations: int,
    trend: np.ndarray,
):
    """Gauss–Newton on ``[θ, c]`` at fixed rates ``(6,)`` and noise ``(6,)`` (``trend``: ``(P, 6,
    6K)`` columns of ``c``).

    Returns ``(log L, [θ, c], whitened residuals (P, 6), whitened Jacobian (P, 6, 12 + 6K),
    gains)``. During the
    search (``iterations ≤ SEARCH_ITERATIONS``) the residuals after the last step are linearized, so
    an
    evaluation costs one filter pass per step.
    """
    gains = walk_gains(data.times, std[None, :] ** 2 / data.counts[:, None], rate)

    def whitened(theta):
        prediction, jacobian = predict_with_jacobian(theta[:12], data.rotations)
        prediction = prediction + trend @ theta[12:]
        columns = whiten(
            gains,
            np.concatenate([(data.wrenches - prediction)[:, :, None], jacobian, trend], axis=2),
        )
        return columns[:, :, 0], columns[:, :, 1:]

    search = iterations <= SEARCH_ITERATIONS
    for _ in range(iterations):
        residuals, whitened_jacobian = whitened(theta)
        step = np.linalg.lstsq(
            whitened_jacobian.reshape(-1, len(theta)), residuals.reshape(-1), rcond=None
        )[0]
        theta = theta + step
        change = whitened_jacobian @ step
        if np.sum(change**2) < 1e-12 * (1.0 + np.sum(residuals**2)):
            break
    if search:
        residuals = residuals - change
    else:
        residuals, whitened_jacobian = whitened(theta)
    return log_likelihood(gains, residuals), theta, residuals, whitened_jacobian, gains


def fit_random_walk(
    poses: PoseAverages,
    theta0: np.ndarray,
    channel_std: np.ndarray,
    source: str,
    selected_by: str = "given",
    degree: int = 0,
) -> DriftFit:
    """Fit ``θ`` with a random-walk bias; the rates (and the noise when ``source == "residuals"``)
    by maximum likelihood.

    ``degree > 0`` adds a polynomial trend of that degree under the walk (a
    warm-up that a walk alone would take for a fast one).
    """
    data = SortedPoses(poses)
    powers, trend, scale, names = polynomial_columns(data, degree)
    estimate_noise = source == "residuals"
    floor = noise_floor(data.wrenches)
    per_pose = np.asarray(channel_std) / np.sqrt(np.median(data.counts))
    spacing = max(float(np.median(np.diff(data.times))) if len(data.times) > 1 else 1.0, 1e-9)
    reference = np.log(np.array([per_pose[:3].mean(), per_pose[3:].mean()]) / np.sqrt(spacing))
    log_noise = np.log([channel_std[:3].mean(), channel_std[3:].mean()])
    best = {"theta": np.concatenate([theta0, np.zeros(6 * degree)]), "value": np.inf}

    def unpack(parameters):
        rate = np.repeat(np.exp(parameters[:2]), 3)
        std = (
            np.maximum(np.repeat(np.exp(parameters[2:4]), 3), floor)
            if estimate_noise
            else np.asarray(channel_std, dtype=float)
        )
        return rate, std

    def objective(parameters):
        value, theta = _profile(data, best["theta"], *unpack(parameters), SEARCH_ITERATIONS, trend)[
            :2
        ]
        value = -value if np.isfinite(value) else np.inf
        if value < best["value"]:
            best.update(theta=theta, value=value)
        return value

    noise_part = log_noise if estimate_noise else np.zeros(0)
    grid = [
        objective(np.concatenate([reference + np.log(factor), noise_part])) for factor in RATE_GRID
    ]
    start = np.concatenate([reference + np.log(RATE_GRID[int(np.argmin(grid))]), noise_part])
    from scipy.optimize import minimize  # scipy loads where it is used (import ftkin stays light)

    solution = minimize(
        objective,
        start,
        method="Nelder-Mead",
        options={"xatol": 0.05, "fatol": 0.01, "maxfev": 40 * len(start)},
    )
    rate, std = unpack(solution.x)
    log_l, phi, residuals, whitened_jacobian, gains = _profile(
        data, best["theta"], rate, std, FINAL_ITERATIONS, trend
    )
    count = 12 + 6 * degree
    covariance = invert_information(
        whitened_jacobian.reshape(-1, count).T @ whitened_jacobian.reshape(-1, count), names
    )
    coefficients = phi[12:].reshape(degree, 6)
    trend_bias = powers @ coefficients
    walk, variance = smooth(
        gains,
        data.times,
        data.wrenches - predict_with_jacobian(phi[:12], data.rotations)[0] - trend_bias,
        rate,
    )
    bias_std = np.sqrt(variance + trend_std(powers, covariance) ** 2)
    name = "random-walk" + (f"+poly:{degree}" if degree else "")
    drift = BiasDrift(
        name,
        selected_by,
        data.times,
        phi[3:9] + trend_bias + walk,
        bias_std,
        rate=rate[[0, 3]],
        coefficients=coefficients if degree else None,
        time_scale=scale,
    )
    return finish_fit(
        data,
        phi[:12],
        std,
        source,
        residuals,
        whitened_jacobian,
        covariance,
        count + 2 + 2 * estimate_noise,
        log_l,
        drift,
    )


def fit_drift(
    poses: PoseAverages, ml_fit, kind: str, degree: int = 0
) -> tuple[DriftFit | None, dict[str, float]]:
    """Fit the drift model ``kind`` (``"poly"``, ``"random-walk"`` or ``"auto"``) from a
    constant-bias ML fit.

    Returns the fit (None when ``auto`` keeps the constant bias) and, for
    ``auto``, the BIC of every candidate tried (a candidate the poses cannot
    determine is left out).
    """
    fit, criteria = _fit_drift(poses, ml_fit, kind, degree)
    if fit is not None and ml_fit.noise_source == "spread":
        fit = replace(
            fit, noise_dof=ml_fit.noise_dof
        )  # the spread's degrees of freedom, as for the constant fit
    return fit, criteria


def _fit_drift(
    poses: PoseAverages, ml_fit, kind: str, degree: int
) -> tuple[DriftFit | None, dict[str, float]]:
    theta0, std, source = (
        ml_fit.model.to_vector(),
        np.asarray(ml_fit.problem.channel_std),
        ml_fit.noise_source,
    )
    if kind == "poly":
        return fit_polynomial(poses, theta0, std, source, degree), {}
    if kind == "random-walk":
        return fit_random_walk(poses, theta0, std, source, degree=degree), {}
    estimated = source == "residuals"
    observations = 6 * len(poses)
    criteria = {
        "none": -2.0 * constant_log_likelihood(poses, theta0, std, estimated)
        + (12 + 2 * estimated) * np.log(observations)
    }
    fits = {}
    for name in AUTO_CANDIDATES[1:]:
        walk, _, degree = name.partition("poly:")
        degree = int(degree or 0)
        if walk and len(poses) > MAX_AUTO_WALK_POSES:
            # the walk's profile likelihood costs a Python pass per pose and evaluation:
            # seconds per 100 poses
            continue
        parameters = 12 + 6 * degree + 2 * bool(walk) + 2 * estimated
        if parameters > observations - 6:
            continue
        try:
            fit = (
                fit_random_walk(poses, theta0, std, source, degree=degree)
                if walk
                else fit_polynomial(poses, theta0, std, source, degree)
            )
        except UnobservableParameters:
            continue
        fits[name], criteria[name] = fit, fit.bic
    choice = min(criteria, key=criteria.get)
    if choice == "none":
        return None, criteria
    fit = fits[choice]
    return replace(fit, drift=replace(fit.drift, selected_by="auto", criteria=criteria)), criteria
