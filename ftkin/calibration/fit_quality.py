"""How far to trust a maximum-likelihood calibration: fit, outliers, observability.

* **Goodness of fit.** ``χ² = Σ r²`` over the whitened residuals of all poses
  and channels has ``ν = 6P − 12`` degrees of freedom when the model is right
  and the noise is known; ``p < FIT_ALPHA`` flags readings that the model does
  not explain (crosstalk, a contact, noise underestimated). The covariance is
  then scaled by ``χ² / ν`` (Birge ratio) so the standard errors stay honest.
  With noise estimated from the residuals the test does not apply (``χ² = ν``
  by construction).
* **Outlier poses.** Each pose's ``z_i = r_iᵀ (I − H_ii)⁻¹ r_i`` (``H_ii`` its
  6×6 block of the hat matrix) is ``χ²(6)`` under the model. When the noise is
  not known independently (or the fit fails) it is compared with the scatter
  of the *other* poses (an F test), so one bad pose cannot hide itself. A pose
  whose p-value is below ``OUTLIER_ALPHA / P`` is named (family-wise 0.1 %).
* **Observability.** Condition number and weakest direction of the
  information matrix normalized to unit diagonal, and a warning for every
  parameter whose standard error exceeds ``RELATIVE_STD_ERROR_WARNING`` of its
  scale.
"""

import logging
from dataclasses import replace

import numpy as np

from .diagnostics import (
    FIT_ALPHA,
    MIN_COM_SCALE,
    OUTLIER_ALPHA,
    RELATIVE_STD_ERROR_WARNING,
    FitDiagnostics,
)
from .goodness_of_fit import WRENCH_CHANNELS, _f_sf, fit_test
from .information import NOISE_FLOOR_RELATIVE, at_noise_floor
from .model import PARAMETER_NAMES

__all__ = [
    "FIT_ALPHA",
    "OUTLIER_ALPHA",
    "RELATIVE_STD_ERROR_WARNING",
    "FitDiagnostics",
    "diagnose",
    "log_warnings",
]

logger = logging.getLogger(__name__)

MIN_NOISE_DOF = 8
"""Fewest degrees of freedom of a residual-based noise estimate before the standard errors are
called rough.
"""

_ROUNDING_WARNING = (
    "the residuals are at rounding level (noise estimated at its floor, "
    f"{NOISE_FLOOR_RELATIVE:g} of the largest reading): the standard errors, the fit test "
    "and the outlier test rest on that floor; record several readings per pose (a pose "
    "column) or give the noise level (noise=, --noise-force/--noise-torque)"
)
_NOISE_FREE_WARNING = (
    "the repeated readings of each pose are identical and the readings fit the model to "
    f"rounding (noise estimated at its floor, {NOISE_FLOOR_RELATIVE:g} of the largest "
    "reading): noise-free data, e.g. a simulation without sensor noise? The estimates are "
    "exact, but the standard errors, the fit test and the outlier test mean nothing; add "
    "sensor noise to simulated readings or give the noise level (noise=, "
    "--noise-force/--noise-torque)"
)

_UNITS = {
    "gravity_in_base": "N",
    "force_offset": "N",
    "torque_offset": "N·m",
    "center_of_mass": "m",
}


def _chi_square_cdf(chi_square: float, dof: int) -> float:
    """``P(X ≤ chi_square)`` for a chi-square with ``dof`` degrees of freedom."""
    from scipy import special

    return float(special.chdtr(dof, chi_square))


def _block_scales(theta: np.ndarray) -> np.ndarray:
    """``(12,)`` scale each parameter's standard error is judged against."""
    weight = float(np.linalg.norm(theta[0:3]))
    com = max(float(np.linalg.norm(theta[9:12])), MIN_COM_SCALE)
    force, torque = (float(np.linalg.norm(theta[part])) for part in (slice(3, 6), slice(6, 9)))
    return np.repeat(
        np.maximum([weight, max(force, weight), max(torque, weight * com), com], 1e-300), 3
    )


def _pose_statistics(whitened, hat, fit_ok, source, noise_dof, dof):
    """Per-pose studentized statistics: normalized residual [σ] and p-value.

    ``hat`` holds the ``(P, 6, 6)`` diagonal blocks of the hat matrix, ``dof`` the fit's degrees
    of freedom.
    """
    eigenvalues, eigenvectors = np.linalg.eigh(np.eye(6) - hat)
    kept = eigenvalues > 1e-8
    projected = np.einsum("pi,pij->pj", whitened, eigenvectors)
    z = np.sum(np.where(kept, projected**2 / np.where(kept, eigenvalues, 1.0), 0.0), axis=1)
    rank = np.maximum(np.sum(kept, axis=1).astype(float), 1.0)
    scale, denominator_dof = 1.0, np.full(len(z), noise_dof)
    if source == "residuals" or not fit_ok:  # against the scatter of the other poses
        denominator_dof = dof - rank
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = (float(np.sum(whitened**2)) - z) / denominator_dof
        if source != "residuals":
            scale = np.maximum(scale, 1.0)
        # No scatter left to judge a pose by: no degrees of freedom beyond it, or a robust fit
        # whose deletion residual (a least-squares formula) takes the whole chi-square: not judged
        # (NaN), where a floor at 1e-300 made it a 1e150σ outlier.
        scale = np.where((denominator_dof > 0) & (scale > 0), scale, np.nan)
    normalized = np.sqrt(z / rank / scale)
    valid = np.isfinite(normalized) & (denominator_dof > 0)
    return normalized, np.where(
        valid,
        _f_sf(np.where(valid, normalized, 0.0) ** 2, rank, np.where(valid, denominator_dof, 1.0)),
        np.nan,
    )


def diagnose(
    fit,
    pose_ids,
    dropped_pose_ids=(),
    parameter_count: int | None = None,
    log: bool = True,
    wrenches=None,
    noise_free: bool = False,
    fit_name: str = "the static fit",
) -> tuple[FitDiagnostics, np.ndarray]:
    """Assess a fit (:class:`~ftkin.calibration.ml.WhitenedFit`: the ML or a drift model's);
    returns its diagnostics and the (scaled) covariance.

    ``parameter_count``: parameters fitted (default: the problem's, 12 for ``θ``
    plus any mount angles; more with a drift
    model, :class:`~ftkin.calibration.drift_fit.DriftFit`), for the degrees of freedom.
    ``log``: False keeps the warnings out of the log (for a fit that may be
    replaced; :func:`log_warnings` sends them later).
    ``wrenches``: the pose-mean readings ``(P, 6)``; with them, a noise
    estimated at its floor (:func:`~ftkin.calibration.information.noise_floor`:
    readings that fit the model to rounding, e.g. noise-free simulated data)
    is said in a warning, and no pose is called an outlier for a rounding error.
    ``noise_free``: the raw readings themselves are noise-free (repeated readings
    identical); only then does the warning call the data noise-free.
    ``fit_name``: how the misfit warning names the fit (``"the static fit from joints"``).

    The chi-square, its degrees of freedom, p-value and per-channel chi-square are those of
    :func:`~ftkin.calibration.goodness_of_fit.fit_test` (every calibration kind's one test, kept
    as :attr:`FitDiagnostics.fit_test` with this function's outlier poses).

    Warnings are also sent to the ``ftkin.calibration.fit_quality`` logger.
    """
    theta, source, whitened, hat = fit.model.to_vector(), fit.noise_source, fit.whitened, fit.hat
    test = fit_test(
        fit_name,
        whitened,
        channel_names=WRENCH_CHANNELS,
        noise_source=source,
        noise_dof=fit.noise_dof,
        group_ids=pose_ids,
        leverage=np.einsum("pkk->pk", hat),
        information=fit.information,
        parameter_count=parameter_count or fit.problem.parameter_count,
        log=False,
        noise_advice="record several readings per pose (a pose column: their spread gives the "
        "noise) or give the noise (noise=, --noise-force/--noise-torque) to have it tested",
    )
    dof, chi_square, channel_chi_square = test.dof, test.chi_square, test.channel_chi_square
    # the fit test does not apply to noise from the residuals or without degrees of freedom
    p_value = np.nan if test.p_value is None else test.p_value
    fit_ok = test.fits
    normalized, pose_p = _pose_statistics(whitened, hat, fit_ok, source, fit.noise_dof, dof)
    scale = chi_square / dof if (not fit_ok and chi_square > dof) else 1.0
    covariance = fit.covariance * scale
    # condition number and weakest direction (largest entry positive), unit-diagonal information
    diagonal = np.sqrt(np.diag(fit.information))
    eigenvalues, eigenvectors = np.linalg.eigh(fit.information / np.outer(diagonal, diagonal))
    weakest = eigenvectors[:, 0] * np.sign(eigenvectors[np.argmax(np.abs(eigenvectors[:, 0])), 0])
    pose_ids = np.asarray(pose_ids)
    exact = noise_free or (
        wrenches is not None
        and source == "residuals"
        and at_noise_floor(fit.noise.channel_std, wrenches)
    )
    outliers = () if exact else pose_ids[pose_p < OUTLIER_ALPHA / max(len(whitened), 1)]
    scales = _block_scales(theta)
    diagnostics = FitDiagnostics(
        loss=fit.loss,
        noise=fit.noise,
        noise_source=source,
        noise_dof=fit.noise_dof,
        chi_square=chi_square,
        dof=dof,
        p_value=p_value,
        channel_chi_square=channel_chi_square,
        covariance_scale=float(scale),
        pose_ids=pose_ids,
        pose_normalized_residuals=normalized,
        pose_p_values=pose_p,
        outlier_pose_ids=tuple(int(i) for i in outliers),
        dropped_pose_ids=tuple(int(i) for i in dropped_pose_ids),
        condition_number=float(eigenvalues[-1] / eigenvalues[0]),
        weakest_direction=weakest,
        relative_std_errors=np.sqrt(np.clip(np.diag(covariance), 0.0, None)) / scales,
        warnings=(),
        # the studentized pose test above (full 6×6 hat blocks) names the outliers
        fit_test=replace(test, outliers=tuple(int(i) for i in outliers)),
    )
    diagnostics = replace(diagnostics, warnings=_warnings(diagnostics, exact, noise_free, scales))
    if log:
        log_warnings(diagnostics)
    return diagnostics, covariance


def _warnings(
    diagnostics: FitDiagnostics, exact: bool, noise_free: bool, scales: np.ndarray
) -> tuple[str, ...]:
    """The warnings the diagnostics call for, one sentence each (``exact``: noise at its floor;
    ``noise_free``: the repeated raw readings are identical).
    """
    d = diagnostics
    relative, sigma = d.relative_std_errors, d.relative_std_errors * scales
    weakest = ", ".join(f"{weight:+.2f} {label}" for label, weight in d.weakest_components)
    worst = ", ".join(
        f"{i} ({d.pose_normalized_residuals[d.pose_ids == i][0]:.1f}σ, "
        f"p = {d.pose_p_values[d.pose_ids == i][0]:.1e})"
        for i in d.outlier_pose_ids
    )
    blocks = [(name, slice(3 * k, 3 * k + 3)) for k, name in enumerate(PARAMETER_NAMES)]
    unjudged = [int(i) for i in d.pose_ids[np.isnan(d.pose_p_values)]]
    rules = [
        (exact, _NOISE_FREE_WARNING if noise_free else _ROUNDING_WARNING),
        (
            d.p_value < FIT_ALPHA,
            f"{d.fit_test.warning if d.fit_test is not None else 'the readings do not fit'}. "
            "The readings do not fit the model within their noise: a sensor mounted otherwise "
            "than the URDF says (estimate_mount='yaw' or 'full', "
            "--estimate-mount), a reading convention (ftkin doctor), sensor crosstalk, a "
            "contact or cable at some poses, or noise underestimated; standard errors scaled by "
            f"{np.sqrt(d.covariance_scale):.2f}",
        ),
        (
            d.noise_too_large,
            f"the readings fit far better than the noise given says they can (chi-square "
            f"{d.chi_square:.3g} for {d.dof} degrees of freedom, lower-tail p = "
            f"{_chi_square_cdf(d.chi_square, d.dof):.1e}): the noise given is about "
            f"{1.0 / max(np.sqrt(d.chi_square / d.dof), 1e-12):.3g}× what the residuals show "
            "(check its unit: one reading's standard deviation, N and N·m), so the standard "
            "errors are too large by as much; leave it out to have it measured",
        ),
        (
            bool(d.outlier_pose_ids),
            f"outlier pose(s), far outside the noise: {worst} (RMS normalized residual over the "
            f"six channels; threshold p < {d.outlier_threshold:.1e}); check them or "
            "refit without them (drop_outliers=True, --drop-outliers)",
        ),
        *(
            (
                np.any(relative[part] > RELATIVE_STD_ERROR_WARNING),
                f"{name} is poorly determined: standard errors "
                f"[{', '.join(f'{s:.3g}' for s in sigma[part])}] "
                f"{_UNITS[name]} are up to {100 * relative[part].max():.0f} % of its scale "
                f"{scales[part.start]:.3g} {_UNITS[name]}; add poses that turn gravity into other "
                f"sensor directions (condition number {d.condition_number:.3g}, weakest "
                f"direction {weakest})",
            )
            for name, part in blocks
        ),
        (
            not exact and bool(unjudged),
            f"pose(s) {', '.join(map(str, unjudged))} not tested for outliers: the other poses "
            "leave no residual scatter to judge them by (too few poses or readings for the "
            "parameters, or a robust loss that put the misfit on them); add poses, record "
            "several readings per pose, or give the noise",
        ),
        (
            d.noise_source == "residuals" and d.noise_dof < MIN_NOISE_DOF,
            f"the noise levels come from the residuals with only {d.noise_dof:.1f} degrees of "
            "freedom, so the standard errors are rough; record several readings per pose (pose "
            "column), add poses, or give the noise",
        ),
    ]
    return tuple(message for warned, message in rules if warned)


def log_warnings(diagnostics: FitDiagnostics) -> None:
    """Send the diagnostics' warnings to the ``ftkin.calibration.fit_quality`` logger."""
    for message in diagnostics.warnings:
        logger.warning(message)
