"""Static calibration of a wrist F/T sensor: :func:`calibrate` and its result.

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_positive, as_vector
from .diagnostics import FitDiagnostics
from .drift import BiasDrift, parse_drift
from .drift_select import fit_drift
from .fit_quality import diagnose, log_warnings
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
        drift: The bias over time (:class:`~ftkin.calibration.drift.BiasDrift`)
            when the samples had times, else None. With a drift model the
            ``force_offset``/``torque_offset`` are the bias at the end of the
            recording and ``residuals`` are taken against the bias at each
            pose's time.
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
    drift: BiasDrift | None = None

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

    def bias_at(self, times) -> np.ndarray:
        """Bias ``[F0, M0]`` [N, N·m] at ``times`` [s]: ``(N, 6)``, or ``(6,)`` for a scalar time.

        From the drift trajectory inside the recorded span (held at its first
        or last value outside); the constant bias without a drift model.
        """
        if self.drift is not None:
            return self.drift.bias_at(times)
        times = np.asarray(times, dtype=float)
        return self.bias.copy() if times.ndim == 0 else np.tile(self.bias, (times.size, 1))

    def with_bias(self, bias) -> CalibrationResult:
        """A copy with the sensor bias ``[F0, M0]`` [N, N·m] replaced (after a re-zero); the rest is kept."""
        bias = as_vector(bias, 6, "bias [F0, M0]")
        return replace(self, force_offset=bias[:3], torque_offset=bias[3:])

    def summary(self) -> str:
        """Human-readable summary with units."""
        return format_summary(self)


def _subset(poses: PoseAverages, keep: np.ndarray) -> PoseAverages:
    times = poses.times[keep] if poses.times is not None else None
    return PoseAverages(poses.pose_ids[keep], poses.rotations[keep], poses.wrenches[keep], poses.counts[keep], poses.spread[keep],
                        times)


def calibrate(
    samples: Samples,
    *,
    method: str = "ml",
    g: float = STANDARD_GRAVITY,
    noise: SensorNoise | None = None,
    loss: str = "linear",
    drop_outliers: bool = False,
    drift: str = "auto",
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
        drift: How the bias may change with time when the samples carry
            times (:mod:`ftkin.calibration.drift`): ``"auto"`` (default: the
            model the information criterion prefers; the constant bias without
            times, with ``method="linear"``, a robust loss or ``drop_outliers``),
            ``"none"`` (constant), ``"poly:N"`` or ``"random-walk"`` (these two
            need times and the plain ``ml`` fit).

    Returns:
        A frozen :class:`CalibrationResult`.

    Raises:
        UnobservableParameters: the poses cannot determine the parameters
            (fewer than three, orientations alike, gravity along one sensor
            direction); the error names them.
        InvalidInput: unknown method, loss or drift model, bad ``g`` or
            ``noise``, ml options with ``method="linear"``, or a drift model
            without times or with options it does not support.
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
    drift_kind, degree = _drift_kind(drift, samples, method, loss, drop_outliers)
    poses = samples.pose_averages()
    covariance = diagnostics = None
    if method == "linear":
        model = fit_linear(poses, g)
    else:
        fit = fit_ml(poses, g, noise, loss)
        diagnostics, covariance = diagnose(fit, poses.pose_ids, log=drift_kind == "none")
        if drop_outliers and diagnostics.outlier_pose_ids:
            dropped = diagnostics.outlier_pose_ids
            poses = _subset(poses, ~np.isin(poses.pose_ids, dropped))
            fit = fit_ml(poses, g, noise, loss)
            diagnostics, covariance = diagnose(fit, poses.pose_ids, dropped)
        model = fit.model
    trajectory = None
    if samples.times is not None and method == "ml" and drift_kind != "none":
        drift_fit, criteria = fit_drift(poses, fit, drift_kind, degree)
        if drift_fit is not None:
            diagnostics, covariance = diagnose(drift_fit, poses.pose_ids, parameter_count=drift_fit.parameter_count)
            model, trajectory = SensorModel.from_vector(drift_fit.model.to_vector(), g), drift_fit.drift
        else:
            log_warnings(diagnostics)
            trajectory = _constant_trajectory(model, poses, covariance, criteria)
    elif samples.times is not None:
        trajectory = _constant_trajectory(model, poses, covariance, {})
    if trajectory is not None:
        trajectory = replace(trajectory, recorded_span=np.array([np.min(samples.times), np.max(samples.times)]))
    if trajectory is None or trajectory.model == "none":
        residuals = poses.wrenches - model.predict(poses.rotations)
    else:
        residuals = poses.wrenches - model.tool_gravity_wrench(poses.rotations) - trajectory.bias_at(poses.times)
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
        drift=trajectory,
    )


def _drift_kind(drift, samples: Samples, method: str, loss: str, drop_outliers: bool) -> tuple[str, int]:
    """The drift model to fit: ``("none"|"auto"|"poly"|"random-walk", degree)`` after checking the options."""
    kind, degree = parse_drift(drift)
    if kind in ("none", "auto"):
        unsupported = method != "ml" or loss != "linear" or drop_outliers
        if kind == "auto" and (samples.times is None or unsupported or np.ptp(samples.times) <= 0.0):
            return "none", 0
        return kind, degree
    if samples.times is None:
        raise InvalidInput(f"drift={drift!r} needs the time of each reading (Samples.times, a 't' column in the CSV)")
    if method != "ml" or loss != "linear" or drop_outliers:
        raise InvalidInput(f"drift={drift!r} needs method='ml' with loss='linear' and no drop_outliers")
    if np.ptp(samples.times) <= 0.0:
        raise InvalidInput(f"drift={drift!r}: all readings have the same time; a drift needs readings spread over time")
    return kind, degree


def _constant_trajectory(model: SensorModel, poses: PoseAverages, covariance, criteria: dict) -> BiasDrift:
    """The constant bias as a :class:`BiasDrift` (``"none"``), for samples that had times."""
    times = np.sort(poses.times)
    std = np.sqrt(np.diag(covariance)[3:9]) if covariance is not None else np.zeros(6)
    return BiasDrift("none", "auto" if criteria else "given", times, np.tile(model.bias, (len(times), 1)),
                     np.tile(std, (len(times), 1)), criteria=criteria)
