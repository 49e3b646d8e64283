"""The diagnostics record of a maximum-likelihood calibration and its JSON form.

:class:`FitDiagnostics` is what :func:`ftkin.calibration.fit_quality.diagnose` finds: the
noise used, the chi-square test, per-pose normalized residuals and outliers,
observability and the warnings. The thresholds it is judged by live here (the fit test's,
``FIT_ALPHA`` and ``OUTLIER_ALPHA``, in :mod:`ftkin.calibration.goodness_of_fit`, every
calibration kind's).
"""

from dataclasses import dataclass

import numpy as np

from .goodness_of_fit import FIT_ALPHA, OUTLIER_ALPHA, FitTest
from .information import SensorNoise
from .model import COMPONENT_NAMES

RELATIVE_STD_ERROR_WARNING = 0.02
"""Warn when a parameter's standard error exceeds this fraction of its block's scale."""

MIN_COM_SCALE = 0.01
"""Smallest scale [m] the centre of mass is judged against (a COM near the sensor origin)."""


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
        fit_test: The test every calibration kind reports
            (:class:`~ftkin.calibration.goodness_of_fit.FitTest`, the source of ``chi_square``,
            ``dof``, ``p_value`` and ``channel_chi_square`` here), or None (read from a file's
            ``diagnostics`` alone; the file keeps it under ``fit_test``).
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
    fit_test: FitTest | None = None

    @property
    def fit_ok(self) -> bool:
        """False when the chi-square test rejects the model (always True with residual-based
        noise).
        """
        return not (self.p_value < FIT_ALPHA)

    @property
    def noise_too_large(self) -> bool:
        """True when the readings fit far better than a given noise says they can (the
        chi-square's lower tail below ``FIT_ALPHA``): the noise given is too large, and the
        standard errors with it."""
        return self.noise_source == "given" and self.dof > 0 and self.p_value > 1.0 - FIT_ALPHA

    @property
    def outlier_threshold(self) -> float:
        """Per-pose p-value below which a pose is an outlier."""
        return OUTLIER_ALPHA / max(len(self.pose_ids), 1)

    @property
    def weakest_components(self) -> list[tuple[str, float]]:
        """Main entries ``(name, weight)`` of the weakest direction, largest first."""
        return main_components(self.weakest_direction)

    @property
    def poorly_determined(self) -> tuple[str, ...]:
        """Parameter components whose relative standard error exceeds the warning level."""
        return tuple(
            COMPONENT_NAMES[i]
            for i in np.flatnonzero(self.relative_std_errors > RELATIVE_STD_ERROR_WARNING)
        )

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
    def from_dict(cls, data: dict) -> "FitDiagnostics":
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
            p_value=number("p_value"),
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


def main_components(direction: np.ndarray) -> list[tuple[str, float]]:
    """Entries of a unit direction in θ above 0.3 in magnitude, ``(name, weight)``, largest
    first.
    """
    return [
        (COMPONENT_NAMES[i], float(direction[i]))
        for i in np.argsort(-np.abs(direction))
        if abs(direction[i]) > 0.3
    ]


def _json_float(value) -> float | None:
    return float(value) if np.isfinite(value) else None


def _json_floats(values) -> list:
    return [_json_float(value) for value in np.asarray(values, dtype=float)]
