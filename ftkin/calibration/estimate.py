"""Static calibration of a wrist F/T sensor: :func:`calibrate` and its result.

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput
from ..kinematics.record import KinematicsRecord
from ..validation import as_positive
from .diagnostics import FitDiagnostics
from .fit_quality import diagnose
from .information import SensorNoise, standard_errors
from .linear import fit_linear
from .ml import LOSSES, fit_ml
from .model import STANDARD_GRAVITY, SensorModel
from .samples import PoseAverages, Samples
from .summary import format_summary

METHODS = ("ml", "linear")
"""Estimators :func:`calibrate` accepts; the first is the default."""


@dataclass(frozen=True)
class CalibrationResult(SensorModel):
    """A calibrated sensor model plus how it was obtained and how well it fits.

    Inherits the parameters of :class:`~ftkin.calibration.model.SensorModel`
    (``force_offset`` [N], ``torque_offset`` [N·m], ``gravity_in_base`` [N],
    ``center_of_mass`` [m, sensor frame], ``g`` [m/s²]) and the derived
    ``tool_weight`` [N], ``tool_mass`` [kg], ``base_tilt`` (U, V) [rad].

    Attributes:
        method: Estimator used (``"linear"``, ...).
        pose_ids: ``(P,)`` pose identifiers.
        pose_wrenches: ``(P, 6)`` mean measured raw wrench per pose [N, N·m].
        residuals: ``(P, 6)`` measured minus predicted per pose [N, N·m].
        sample_count: Raw readings used (≥ number of poses).
        urdf: URDF used for forward kinematics, if joint angles were given.
        sensor_frame: Its sensor frame name.
        covariance: ``(12, 12)`` covariance of ``θ = [a, F0, M0, P]`` when
            the estimator provides one (``ml``), else None.
        diagnostics: Fit quality, outlier poses, observability and warnings
            (:class:`~ftkin.calibration.diagnostics.FitDiagnostics`) for ``ml``, else None.
        kinematics: How the sensor frame was obtained (robot or URDF, mount, URDF hash:
            :class:`~ftkin.kinematics.record.KinematicsRecord`), or None when unknown.
    """

    method: str = "linear"
    pose_ids: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=int))
    pose_wrenches: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    residuals: np.ndarray = field(default_factory=lambda: np.zeros((0, 6)))
    sample_count: int = 0
    urdf: str | None = None
    sensor_frame: str | None = None
    covariance: np.ndarray | None = None
    diagnostics: FitDiagnostics | None = None
    kinematics: KinematicsRecord | None = None

    @property
    def pose_count(self) -> int:
        """Number of distinct static poses."""
        return len(self.pose_ids)

    @property
    def model(self) -> SensorModel:
        """The bare parameters, without provenance."""
        return SensorModel(self.force_offset, self.torque_offset, self.gravity_in_base, self.center_of_mass, self.g)

    @property
    def residual_rms(self) -> np.ndarray:
        """``(6,)`` RMS of the per-pose residuals per channel [N, N·m]."""
        if len(self.residuals) == 0:
            return np.full(6, np.nan)
        return np.sqrt(np.mean(self.residuals**2, axis=0))

    @property
    def mean_relative_error(self) -> np.ndarray:
        """``(6,)`` mean over poses of ``|residual| / |measured|`` per channel (the paper's Table 3) [-]."""
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.mean(np.abs(self.residuals) / np.abs(self.pose_wrenches), axis=0)

    @property
    def std_errors(self) -> dict | None:
        """Standard errors per parameter (see :func:`ftkin.calibration.information.standard_errors`), or None."""
        if self.covariance is None:
            return None
        return standard_errors(self, self.covariance)

    @property
    def warnings(self) -> tuple[str, ...]:
        """Warnings about fit quality, outlier poses and poorly determined parameters."""
        return self.diagnostics.warnings if self.diagnostics is not None else ()

    def summary(self) -> str:
        """Human-readable summary with units."""
        return format_summary(self)


def _subset(poses: PoseAverages, keep: np.ndarray) -> PoseAverages:
    return PoseAverages(poses.pose_ids[keep], poses.rotations[keep], poses.wrenches[keep], poses.counts[keep], poses.spread[keep])


def calibrate(
    samples: Samples,
    *,
    method: str = "ml",
    g: float = STANDARD_GRAVITY,
    noise: SensorNoise | None = None,
    loss: str = "linear",
    drop_outliers: bool = False,
) -> CalibrationResult:
    """Estimate bias, tool gravity and base tilt from static-pose readings.

    Args:
        samples: Raw readings with sensor orientations (see :class:`Samples`);
            readings sharing a pose id are averaged first.
        method: ``"ml"`` (default): joint maximum-likelihood fit of all six
            channels with standard errors and diagnostics (:mod:`ftkin.calibration.ml`);
            ``"linear"``: the paper's two-step least squares.
        g: Gravity used to report the tool mass [m/s²] (the paper used 9.8).
        noise: ``ml`` only: noise of one raw reading [N, N·m]. None estimates
            it from the spread of repeated readings per pose, else from the
            residuals.
        loss: ``ml`` only: ``"linear"`` (Gaussian likelihood), ``"soft_l1"``
            or ``"huber"`` (robust to outlying poses).
        drop_outliers: ``ml`` only: refit once without the poses flagged as
            outliers (see :mod:`ftkin.calibration.fit_quality`).

    Returns:
        A frozen :class:`CalibrationResult`.

    Raises:
        UnobservableParameters: the poses cannot determine the parameters
            (fewer than three, orientations alike, gravity along one sensor
            direction); the error names them.
        InvalidInput: unknown method or loss, bad ``g`` or ``noise``, or ml
            options with ``method="linear"``.
    """
    if not isinstance(samples, Samples):
        raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
    if method not in METHODS:
        raise InvalidInput(f"unknown calibration method {method!r}; expected one of {', '.join(METHODS)}")
    if loss not in LOSSES:
        raise InvalidInput(f"unknown loss {loss!r}; expected one of {', '.join(LOSSES)}")
    if noise is not None and not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin.SensorNoise, got {type(noise).__name__}")
    if method == "linear" and (noise is not None or loss != "linear" or drop_outliers):
        raise InvalidInput("noise, loss and drop_outliers apply to method='ml' only")
    g = as_positive(g, "g")
    poses = samples.pose_averages()
    covariance = diagnostics = None
    if method == "linear":
        model = fit_linear(poses, g)
    else:
        fit = fit_ml(poses, g, noise, loss)
        diagnostics, covariance = diagnose(fit, poses.pose_ids)
        if drop_outliers and diagnostics.outlier_pose_ids:
            dropped = diagnostics.outlier_pose_ids
            poses = _subset(poses, ~np.isin(poses.pose_ids, dropped))
            fit = fit_ml(poses, g, noise, loss)
            diagnostics, covariance = diagnose(fit, poses.pose_ids, dropped)
        model = fit.model
    residuals = poses.wrenches - model.predict(poses.rotations)
    return CalibrationResult(
        force_offset=model.force_offset,
        torque_offset=model.torque_offset,
        gravity_in_base=model.gravity_in_base,
        center_of_mass=model.center_of_mass,
        g=g,
        method=method,
        pose_ids=poses.pose_ids,
        pose_wrenches=poses.wrenches,
        residuals=residuals,
        sample_count=int(np.sum(poses.counts)),
        urdf=samples.urdf,
        sensor_frame=samples.sensor_frame,
        covariance=covariance,
        diagnostics=diagnostics,
    )
