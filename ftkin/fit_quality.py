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

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from scipy import stats

from .information import SensorNoise
from .model import COMPONENT_NAMES, PARAMETER_NAMES

logger = logging.getLogger(__name__)

FIT_ALPHA = 1e-3
"""p-value below which the chi-square test says the model does not fit."""

OUTLIER_ALPHA = 1e-3
"""Family-wise false-alarm rate of the outlier test (per pose: ``OUTLIER_ALPHA / P``)."""

RELATIVE_STD_ERROR_WARNING = 0.02
"""Warn when a parameter's standard error exceeds this fraction of its block's scale."""

MIN_COM_SCALE = 0.01
"""Smallest scale [m] the centre of mass is judged against (a COM near the sensor origin)."""

_UNITS = {"gravity_in_base": "N", "force_offset": "N", "torque_offset": "N·m", "center_of_mass": "m"}


@dataclass(frozen=True)
class FitDiagnostics:
    """Fit quality, outliers and observability of a calibration (all floats SI).

    Attributes:
        loss: Loss function of the fit.
        noise: Per-reading noise used for the weights [N, N·m].
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        noise_dof: Degrees of freedom of the noise estimate (``inf`` if given).
        chi_square: ``Σ r²`` over all whitened residuals.
        dof: ``6P − 12``.
        p_value: Of the chi-square test (NaN when noise came from the residuals).
        channel_chi_square: ``(6,)`` reduced chi-square per channel fx..mz.
        covariance_scale: Factor applied to the covariance (1, or ``χ²/ν`` when the fit fails).
        pose_ids: ``(P,)`` poses the fit used.
        pose_normalized_residuals: ``(P,)`` RMS studentized residual per pose [σ].
        pose_p_values: ``(P,)`` p-value of each pose's outlier test.
        outlier_pose_ids: Poses flagged as outliers.
        dropped_pose_ids: Poses removed as outliers before the final fit.
        condition_number: Of the unit-diagonal information matrix.
        weakest_direction: ``(12,)`` its eigenvector of the smallest eigenvalue.
        relative_std_errors: ``(12,)`` standard error over the block's scale.
        warnings: Human-readable warnings (also logged).
    """

    loss: str
    noise: SensorNoise
    noise_source: str
    noise_dof: float
    chi_square: float
    dof: int
    p_value: float
    channel_chi_square: np.ndarray
    covariance_scale: float
    pose_ids: np.ndarray
    pose_normalized_residuals: np.ndarray
    pose_p_values: np.ndarray
    outlier_pose_ids: tuple[int, ...]
    dropped_pose_ids: tuple[int, ...]
    condition_number: float
    weakest_direction: np.ndarray
    relative_std_errors: np.ndarray
    warnings: tuple[str, ...]

    @property
    def fit_ok(self) -> bool:
        """False when the chi-square test rejects the model (always True with residual-based noise)."""
        return not (self.p_value < FIT_ALPHA)

    @property
    def outlier_threshold(self) -> float:
        """Per-pose p-value below which a pose is an outlier."""
        return OUTLIER_ALPHA / max(len(self.pose_ids), 1)

    @property
    def weakest_components(self) -> list[tuple[str, float]]:
        """Main entries ``(name, weight)`` of the weakest direction, largest first."""
        order = np.argsort(-np.abs(self.weakest_direction))
        return [(COMPONENT_NAMES[i], float(self.weakest_direction[i])) for i in order if abs(self.weakest_direction[i]) > 0.3]

    @property
    def poorly_determined(self) -> tuple[str, ...]:
        """Parameter components whose relative standard error exceeds the warning level."""
        return tuple(COMPONENT_NAMES[i] for i in np.flatnonzero(self.relative_std_errors > RELATIVE_STD_ERROR_WARNING))

    def to_dict(self) -> dict:
        """Plain-Python form for the calibration file (non-finite numbers written as null)."""
        return {
            "loss": self.loss,
            "noise_force_std": _json_floats(self.noise.force_std),
            "noise_torque_std": _json_floats(self.noise.torque_std),
            "noise_source": self.noise_source,
            "noise_dof": _json_float(self.noise_dof),
            "chi_square": _json_float(self.chi_square),
            "dof": int(self.dof),
            "p_value": _json_float(self.p_value),
            "channel_chi_square": _json_floats(self.channel_chi_square),
            "covariance_scale": _json_float(self.covariance_scale),
            "pose_ids": self.pose_ids.tolist(),
            "pose_normalized_residuals": _json_floats(self.pose_normalized_residuals),
            "pose_p_values": _json_floats(self.pose_p_values),
            "outlier_pose_ids": list(self.outlier_pose_ids),
            "dropped_pose_ids": list(self.dropped_pose_ids),
            "condition_number": _json_float(self.condition_number),
            "weakest_direction": _json_floats(self.weakest_direction),
            "relative_std_errors": _json_floats(self.relative_std_errors),
            "warnings": list(self.warnings),
        }

    @classmethod
    def from_dict(cls, data: dict) -> FitDiagnostics:
        """Inverse of :meth:`to_dict`; raises KeyError/TypeError/ValueError on malformed input."""

        def number(key):
            return np.nan if data[key] is None else float(data[key])

        def floats(key):
            return np.array([np.nan if v is None else v for v in data[key]], dtype=float)

        return cls(
            loss=str(data["loss"]),
            noise=SensorNoise(data["noise_force_std"], data["noise_torque_std"]),
            noise_source=str(data["noise_source"]),
            noise_dof=np.inf if data["noise_dof"] is None else float(data["noise_dof"]),
            chi_square=number("chi_square"),
            dof=int(data["dof"]),
            p_value=np.nan if data["p_value"] is None else float(data["p_value"]),
            channel_chi_square=floats("channel_chi_square").reshape(6),
            covariance_scale=number("covariance_scale"),
            pose_ids=np.array(data["pose_ids"], dtype=np.int64),
            pose_normalized_residuals=floats("pose_normalized_residuals"),
            pose_p_values=floats("pose_p_values"),
            outlier_pose_ids=tuple(int(i) for i in data["outlier_pose_ids"]),
            dropped_pose_ids=tuple(int(i) for i in data["dropped_pose_ids"]),
            condition_number=number("condition_number"),
            weakest_direction=floats("weakest_direction").reshape(12),
            relative_std_errors=floats("relative_std_errors").reshape(12),
            warnings=tuple(str(w) for w in data["warnings"]),
        )


def _json_float(value) -> float | None:
    return float(value) if np.isfinite(value) else None


def _json_floats(values) -> list:
    return [_json_float(value) for value in np.asarray(values, dtype=float)]


def _f_sf(ratio, dfn, dfd):
    """Survival function of F(dfn, dfd), the chi-square limit for infinite ``dfd``."""
    if not np.isfinite(dfd) or dfd > 1e7:
        return stats.chi2.sf(ratio * dfn, dfn)
    return stats.f.sf(ratio, dfn, dfd)


def _block_scales(theta: np.ndarray) -> np.ndarray:
    """``(12,)`` scale each parameter's standard error is judged against."""
    weight = float(np.linalg.norm(theta[0:3]))
    com = max(float(np.linalg.norm(theta[9:12])), MIN_COM_SCALE)
    scales = [weight, max(float(np.linalg.norm(theta[3:6])), weight),
              max(float(np.linalg.norm(theta[6:9])), weight * com), com]
    return np.repeat(np.maximum(scales, 1e-300), 3)


def _pose_statistics(whitened, jac, fit_ok, source, noise_dof):
    """Per-pose studentized statistics: normalized residual [σ] and p-value."""
    count = len(whitened)
    blocks = jac.reshape(count, 6, 12)
    gram_inv = np.linalg.pinv(jac.T @ jac, hermitian=True)
    hat = blocks @ gram_inv @ np.transpose(blocks, (0, 2, 1))
    complement = np.eye(6) - hat
    inverse = np.linalg.pinv(complement, rcond=1e-8, hermitian=True)
    z = np.einsum("pi,pij,pj->p", whitened, inverse, whitened)
    rank = np.linalg.matrix_rank(complement, tol=1e-8, hermitian=True).astype(float)
    rank = np.maximum(rank, 1.0)
    total, dof = float(np.sum(whitened**2)), 6 * count - 12
    leave_out_dof = dof - rank
    if source == "residuals" or not fit_ok:
        with np.errstate(invalid="ignore", divide="ignore"):
            scale = (total - z) / leave_out_dof
        if source != "residuals":
            scale = np.maximum(scale, 1.0)
        scale = np.where(leave_out_dof > 0, np.maximum(scale, 1e-300), np.nan)
        denominator_dof = leave_out_dof
    else:
        scale = np.ones(count)
        denominator_dof = np.full(count, noise_dof)
    normalized = np.sqrt(z / rank / scale)
    p_values = np.array([
        _f_sf(n**2, k, d) if np.isfinite(n) and d > 0 else np.nan
        for n, k, d in zip(normalized, rank, denominator_dof)
    ])
    leverage = np.diagonal(hat, axis1=1, axis2=2)
    return normalized, p_values, leverage


def diagnose(fit, pose_ids, dropped_pose_ids=()) -> tuple[FitDiagnostics, np.ndarray]:
    """Assess an :class:`~ftkin.ml.MlFit`; returns its diagnostics and the (scaled) covariance.

    Warnings are also sent to the ``ftkin.fit_quality`` logger.
    """
    theta = fit.model.to_vector()
    problem = fit.problem
    whitened = problem.whitened_residuals(theta).reshape(-1, 6)
    jac = problem.whitened_jacobian(theta)
    count = len(whitened)
    dof = 6 * count - 12
    chi_square = float(np.sum(whitened**2))
    if fit.noise_source == "residuals" or dof <= 0:
        p_value = np.nan
    else:
        p_value = float(_f_sf(chi_square / dof, dof, fit.noise_dof))
    fit_ok = not (p_value < FIT_ALPHA)
    normalized, pose_p, leverage = _pose_statistics(whitened, jac, fit_ok, fit.noise_source, fit.noise_dof)
    with np.errstate(invalid="ignore", divide="ignore"):
        channel_chi_square = np.sum(whitened**2, axis=0) / np.sum(1.0 - leverage, axis=0)
    scale = chi_square / dof if (not fit_ok and chi_square > dof) else 1.0
    covariance = fit.covariance * scale
    information = fit.information
    diagonal = np.sqrt(np.diag(information))
    eigenvalues, eigenvectors = np.linalg.eigh(information / np.outer(diagonal, diagonal))
    weakest = eigenvectors[:, 0] * np.sign(eigenvectors[np.argmax(np.abs(eigenvectors[:, 0])), 0])
    relative = np.sqrt(np.clip(np.diag(covariance), 0.0, None)) / _block_scales(theta)
    pose_ids = np.asarray(pose_ids)
    outliers = tuple(int(i) for i in pose_ids[pose_p < OUTLIER_ALPHA / max(count, 1)])

    messages = []
    if not fit_ok:
        messages.append(
            f"the readings do not fit the model within their noise (chi-square {chi_square:.1f} for {dof} "
            f"degrees of freedom, p = {p_value:.1e}): sensor crosstalk, a contact or cable at some poses, or "
            f"noise underestimated; standard errors scaled by {np.sqrt(scale):.2f}"
        )
    if outliers:
        worst = ", ".join(
            f"{i} ({normalized[pose_ids == i][0]:.1f}σ, p = {pose_p[pose_ids == i][0]:.1e})" for i in outliers
        )
        messages.append(
            f"outlier pose(s), far outside the noise: {worst} (RMS normalized residual over the six channels; "
            f"threshold p < {OUTLIER_ALPHA / count:.1e}); check them or refit without them "
            "(drop_outliers=True, --drop-outliers)"
        )
    for block, name in enumerate(PARAMETER_NAMES):
        part = slice(3 * block, 3 * block + 3)
        if np.any(relative[part] > RELATIVE_STD_ERROR_WARNING):
            sigma = np.sqrt(np.diag(covariance))[part]
            messages.append(
                f"{name} is poorly determined: standard errors [{', '.join(f'{s:.3g}' for s in sigma)}] "
                f"{_UNITS[name]} are up to {100 * relative[part].max():.0f} % of its scale "
                f"{_block_scales(theta)[3 * block]:.3g} {_UNITS[name]}; add poses that tilt the sensor further "
                f"(condition number {eigenvalues[-1] / eigenvalues[0]:.3g})"
            )
    for message in messages:
        logger.warning(message)
    diagnostics = FitDiagnostics(
        loss=fit.loss,
        noise=fit.noise,
        noise_source=fit.noise_source,
        noise_dof=fit.noise_dof,
        chi_square=chi_square,
        dof=dof,
        p_value=p_value,
        channel_chi_square=channel_chi_square,
        covariance_scale=float(scale),
        pose_ids=pose_ids,
        pose_normalized_residuals=normalized,
        pose_p_values=pose_p,
        outlier_pose_ids=outliers,
        dropped_pose_ids=tuple(int(i) for i in dropped_pose_ids),
        condition_number=float(eigenvalues[-1] / eigenvalues[0]),
        weakest_direction=weakest,
        relative_std_errors=relative,
        warnings=tuple(messages),
    )
    return diagnostics, covariance
