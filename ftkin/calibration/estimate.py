"""Static calibration of a wrist F/T sensor: :func:`calibrate` and its result.

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field, replace

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_positive
from .conventions import check_conventions, check_flip_axis, check_sensor_sign, detect_sign_and_handedness, reading_signs
from .diagnostics import FitDiagnostics
from .fit_quality import diagnose
from .information import SensorNoise, standard_errors
from .linear import fit_linear
from .ml import LOSSES, fit_ml
from .model import STANDARD_GRAVITY, SensorModel
from .mount import MOUNT_NAMES, POSES_NEEDED, check_mount_mode, rotation_to_rpy
from .samples import PoseAverages, Samples
from .summary import format_summary

logger = logging.getLogger(__name__)

MOUNT_STD_WARNING_DEG = 1.0
"""Standard error [deg] of a mount angle above which the calibration warns."""

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
        mount_rotation: ``R_M`` ``(3, 3)``: coordinates in the URDF's sensor
            frame → the real sensor frame; the real orientation is
            ``R_BS = R_BS_urdf · R_Mᵀ`` (identity unless estimated).
        mount_mode: ``"none"``, ``"yaw"`` or ``"full"`` (how ``R_M`` was estimated).
        mount_covariance: ``(k, k)`` covariance [rad²] of the mount angles
            (:data:`~ftkin.calibration.mount.MOUNT_NAMES`), else None.
        sensor_sign: ``+1`` (the sensor reports the load on it) or ``-1`` (the
            reaction): applied to every raw reading.
        flip_axis: None, or the sensor axis (``"x"``, ``"y"``, ``"z"``) whose
            force and torque channels are negated in every raw reading.

    The parameters are those of the real sensor frame: :meth:`predict` and
    :meth:`tool_gravity_wrench` take the real ``R_BS`` (with the mount) and
    give corrected readings (:attr:`reading_signs` applied).
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
    mount_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    mount_mode: str = "none"
    mount_covariance: np.ndarray | None = None
    sensor_sign: int = 1
    flip_axis: str | None = None

    def __post_init__(self):
        super().__post_init__()
        rotation = np.array(self.mount_rotation, dtype=float)
        if rotation.shape != (3, 3) or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6) or np.linalg.det(rotation) <= 0:
            raise InvalidInput(f"mount_rotation must be a (3, 3) rotation matrix (orthonormal, det = +1), got {rotation.tolist()}")
        rotation.setflags(write=False)
        object.__setattr__(self, "mount_rotation", rotation)
        object.__setattr__(self, "mount_mode", check_mount_mode(self.mount_mode))
        object.__setattr__(self, "sensor_sign", check_sensor_sign(self.sensor_sign))
        check_flip_axis(self.flip_axis)

    @property
    def has_mount(self) -> bool:
        """True when ``R_M`` is not the identity."""
        return not np.array_equal(self.mount_rotation, np.eye(3))

    @property
    def mount_rpy_deg(self) -> np.ndarray:
        """``(3,)`` roll, pitch, yaw [deg] of ``R_M`` (``R_M = Rz(yaw) Ry(pitch) Rx(roll)``)."""
        return np.rad2deg(rotation_to_rpy(self.mount_rotation))

    @property
    def mount_std_deg(self) -> dict[str, float]:
        """Standard errors [deg] of the estimated mount angles by name (empty without a mount estimate)."""
        if self.mount_covariance is None:
            return {}
        sigma = np.rad2deg(np.sqrt(np.clip(np.diag(self.mount_covariance), 0.0, None)))
        return dict(zip(MOUNT_NAMES[self.mount_mode], (float(value) for value in sigma)))

    @property
    def reading_signs(self) -> np.ndarray:
        """``(6,)`` factors ``±1`` applied to every raw reading (``sensor_sign`` and ``flip_axis``)."""
        return reading_signs(self.sensor_sign, self.flip_axis)

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


def _with_mount_warning(diagnostics: FitDiagnostics, mode: str, covariance: np.ndarray) -> FitDiagnostics:
    """Add a warning for mount angles with a standard error above :data:`MOUNT_STD_WARNING_DEG`."""
    sigma = np.rad2deg(np.sqrt(np.clip(np.diag(covariance), 0.0, None)))
    weak = [f"{name} ± {value:.2g}°" for name, value in zip(MOUNT_NAMES[mode], sigma) if value > MOUNT_STD_WARNING_DEG]
    if not weak:
        return diagnostics
    message = f"the mount is poorly determined ({', '.join(weak)}): {POSES_NEEDED[mode]}"
    logger.warning(message)
    return replace(diagnostics, warnings=diagnostics.warnings + (message,))


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
    estimate_mount: str = "none",
    sensor_sign: int = 1,
    flip_axis: str | None = None,
    base_mount: str = "floor",
    expected_gravity=None,
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
        estimate_mount: ``ml`` only: ``"none"`` (default), ``"yaw"`` (the
            sensor turned about its z axis on the flange) or ``"full"`` (any
            rotation): estimate the mount ``R_M`` jointly (samples from joint
            angles only; :mod:`ftkin.calibration.mount`).
        sensor_sign: ``+1`` (default) or ``-1``: negate every reading (a sensor
            reporting the reaction); see :mod:`ftkin.calibration.conventions`.
        flip_axis: None or ``"x"``, ``"y"``, ``"z"``: negate that axis's force
            and torque channels (a mirrored axis).
        base_mount: ``"floor"`` (default: gravity along base −z),
            ``"ceiling"`` (+z) or ``"wall"`` (no direction check).
        expected_gravity: Expected gravity direction [base frame]; overrides ``base_mount``.

    Returns:
        A frozen :class:`CalibrationResult`.

    Raises:
        UnobservableParameters: the poses cannot determine the parameters
            (fewer than three, orientations alike, gravity along one sensor
            direction); the error names them.
        InvalidInput: unknown method or loss, bad ``g`` or ``noise``, ml
            options with ``method="linear"``, or a mount for samples whose
            rotations were given directly.
        SuspectConvention: the data fit with an axis reversed, or the tool
            weight points more than 90° from the expected gravity direction.
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
    if check_mount_mode(estimate_mount) != "none" and method != "ml":
        raise InvalidInput("estimate_mount applies to method='ml' only")
    if estimate_mount != "none" and samples.joint_positions is None:
        raise InvalidInput(
            "estimate_mount needs samples from joint angles (Samples.from_joint_positions): rotations given "
            "directly are taken as the real sensor orientation, so any mount is already in them (absorbed)"
        )
    g = as_positive(g, "g")
    signs = reading_signs(sensor_sign, flip_axis)
    raw_poses = samples.pose_averages()
    poses = replace(raw_poses, wrenches=raw_poses.wrenches * signs)
    check = detect_sign_and_handedness(
        raw_poses, sensor_sign=sensor_sign, flip_axis=flip_axis, estimate_mount=estimate_mount,
        base_mount=base_mount, expected_gravity=expected_gravity, g=g,
    )
    check_conventions(check, sensor_sign, base_mount)
    covariance = diagnostics = mount_covariance = None
    mount = np.eye(3)
    if method == "linear":
        model = fit_linear(poses, g)
    else:
        fit = fit_ml(poses, g, noise, loss, estimate_mount)
        diagnostics, covariance = diagnose(fit, poses.pose_ids)
        if drop_outliers and diagnostics.outlier_pose_ids:
            dropped = diagnostics.outlier_pose_ids
            poses = _subset(poses, ~np.isin(poses.pose_ids, dropped))
            fit = fit_ml(poses, g, noise, loss, estimate_mount)
            diagnostics, covariance = diagnose(fit, poses.pose_ids, dropped)
        model, mount, mount_covariance = fit.model, fit.mount_rotation, fit.mount_covariance
        if mount_covariance is not None:
            mount_covariance = mount_covariance * diagnostics.covariance_scale  # the same goodness-of-fit scaling as θ
            diagnostics = _with_mount_warning(diagnostics, estimate_mount, mount_covariance)
    residuals = poses.wrenches - model.predict(poses.rotations @ mount.T)
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
        mount_rotation=mount,
        mount_mode=estimate_mount,
        mount_covariance=mount_covariance,
        sensor_sign=sensor_sign,
        flip_axis=flip_axis,
    )
