"""The result of a static calibration: :class:`CalibrationResult`.

A frozen :class:`~ftkin.calibration.model.SensorModel` (bias, tool gravity in
the base frame, centre of mass) with what the fit knows about itself: per-pose
residuals, covariance and standard errors, diagnostics, the sensor's mount and
reading signs, and the bias trajectory of a drifting sensor; and its readable summary
(what the CLI prints).
"""

from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..exceptions import InvalidInput
from ..kinematics.record import KinematicsRecord
from ..validation import as_vector
from .conventions import check_flip_axis, check_sensor_sign, reading_signs
from .diagnostics import FitDiagnostics
from .drift import BiasDrift
from .goodness_of_fit import FitTest
from .information import standard_errors
from .model import WRENCH_CHANNELS, SensorModel
from .mount import MOUNT_NAMES, MountMode, rotation_to_rpy


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
        fit_test: Whether the model fits the readings, the same test for every calibration kind
            (:class:`~ftkin.calibration.goodness_of_fit.FitTest`: chi-square, p-value or why
            none, per-channel chi-square, outliers, verdict), or None (``linear``).
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
        kinematics: The arm the samples' joint angles were read with (robot or URDF, mount,
            the chain from the base to the sensor frame:
            :class:`~ftkin.kinematics.record.KinematicsRecord`), or None when unknown (samples
            from orientations or the IMU).
        drift: The bias over time (:class:`~ftkin.calibration.drift.BiasDrift`)
            when the samples had times, else None. With a drift model the
            ``force_offset``/``torque_offset`` are the bias at the end of the
            recording and ``residuals`` are taken against the bias at each
            pose's time.
        inertia_about_com_in_sensor: ``(3, 3)`` tool inertia about the COM, sensor axes
            [kg·m²], when a dynamic calibration identified it, else None.
        inertia_std_errors: ``(3, 3)`` its standard errors [kg·m²], or None.
        inertial_parameters: ``(10,)`` inertial parameters θ in the sensor frame (see
            :mod:`ftkin.calibration.log_cholesky`), or None.
        inertial_covariance: ``(10, 10)`` covariance of θ, or None.

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
    fit_test: FitTest | None = None
    mount_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    mount_mode: MountMode | str = MountMode.NONE
    mount_covariance: np.ndarray | None = None
    sensor_sign: int = 1
    flip_axis: str | None = None
    drift: BiasDrift | None = None
    kinematics: KinematicsRecord | None = None
    inertia_about_com_in_sensor: np.ndarray | None = None
    inertia_std_errors: np.ndarray | None = None
    inertial_parameters: np.ndarray | None = None
    inertial_covariance: np.ndarray | None = None

    _OPTIONAL_ARRAYS = (
        "inertia_about_com_in_sensor",
        "inertia_std_errors",
        "inertial_parameters",
        "inertial_covariance",
    )

    def __post_init__(self):
        super().__post_init__()
        for name in self._OPTIONAL_ARRAYS:
            value = self.__dict__[name]
            if value is not None:
                value = np.array(value, dtype=float)
                value.setflags(write=False)
                object.__setattr__(self, name, value)
        rotation = np.array(self.mount_rotation, dtype=float)
        if (
            rotation.shape != (3, 3)
            or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6)
            or np.linalg.det(rotation) <= 0
        ):
            raise InvalidInput(
                "mount_rotation must be a (3, 3) rotation matrix (orthonormal, det = +1), got "
                f"{rotation.tolist()}"
            )
        rotation.setflags(write=False)
        object.__setattr__(self, "mount_rotation", rotation)
        object.__setattr__(self, "mount_mode", MountMode.of(self.mount_mode))
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
        """Standard errors [deg] of the estimated mount angles by name (empty without a mount
        estimate).
        """
        if self.mount_covariance is None:
            return {}
        sigma = np.rad2deg(np.sqrt(np.clip(np.diag(self.mount_covariance), 0.0, None)))
        return dict(zip(MOUNT_NAMES[self.mount_mode], sigma.tolist()))

    @property
    def reading_signs(self) -> np.ndarray:
        """``(6,)`` factors ``±1`` applied to every raw reading (``sensor_sign`` and
        ``flip_axis``).
        """
        return reading_signs(self.sensor_sign, self.flip_axis)

    def base_fields(self) -> dict:
        """The fields :class:`CalibrationResult` declares, by name (a subclass's own left out):
        the keywords that build another kind of result from this one (a file's inertia or IMU
        entry read onto its common part)."""
        return {name: self.__dict__[name] for name in _BASE_FIELDS}

    @classmethod
    def from_model(cls, model: SensorModel) -> "CalibrationResult":
        """``model`` itself if it is a calibration, else a calibration of its bare parameters."""
        if isinstance(model, CalibrationResult):
            return model
        return cls(
            model.force_offset,
            model.torque_offset,
            model.gravity_in_base,
            model.center_of_mass,
            model.g,
        )

    @property
    def has_inertia(self) -> bool:
        """True when the inertia was identified (compensation may then remove inertial forces)."""
        return self.inertia_about_com_in_sensor is not None

    @property
    def dynamic_parameters(self) -> np.ndarray:
        """θ (10,) for compensation: the identified one, or ``[m, m·c, 0…]`` (a point mass)."""
        if self.inertial_parameters is not None:
            return np.array(self.inertial_parameters)
        return np.concatenate([[self.tool_mass], self.tool_mass * self.center_of_mass, np.zeros(6)])

    @property
    def pose_count(self) -> int:
        """Number of distinct static poses."""
        return len(self.pose_ids)

    @property
    def model(self) -> SensorModel:
        """The bare parameters, without provenance."""
        return SensorModel(
            self.force_offset, self.torque_offset, self.gravity_in_base, self.center_of_mass, self.g
        )

    @property
    def residual_rms(self) -> np.ndarray:
        """``(6,)`` RMS of the per-pose residuals per channel [N, N·m]."""
        if len(self.residuals) == 0:
            return np.full(6, np.nan)
        return np.sqrt(np.mean(self.residuals**2, axis=0))

    @property
    def mean_relative_error(self) -> np.ndarray:
        """``(6,)`` mean over poses of ``|residual| / |measured|`` per channel (the paper's Table 3)
        [-].
        """
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.mean(np.abs(self.residuals) / np.abs(self.pose_wrenches), axis=0)

    @property
    def std_errors(self) -> dict | None:
        """Standard errors per parameter (see
        :func:`ftkin.calibration.information.standard_errors`), or None.
        """
        return None if self.covariance is None else standard_errors(self, self.covariance)

    @property
    def warnings(self) -> tuple[str, ...]:
        """Warnings about fit quality, outlier poses and poorly determined parameters."""
        if self.diagnostics is not None:
            return self.diagnostics.warnings
        warning = None if self.fit_test is None else self.fit_test.warning
        return () if warning is None else (warning,)

    def bias_at(self, times) -> np.ndarray:
        """Bias ``[F0, M0]`` [N, N·m] at ``times`` [s]: ``(N, 6)``, or ``(6,)`` for a scalar time.

        From the drift trajectory inside the recorded span (held at its first
        or last value outside); the constant bias without a drift model.
        """
        if self.drift is not None:
            return self.drift.bias_at(times)
        times = np.asarray(times, dtype=float)
        return self.bias.copy() if times.ndim == 0 else np.tile(self.bias, (times.size, 1))

    def with_bias(self, bias) -> "CalibrationResult":
        """A copy with the sensor bias ``[F0, M0]`` [N, N·m] replaced (after a re-zero); the rest is
        kept.
        """
        bias = as_vector(bias, 6, "bias [F0, M0]")
        return replace(self, force_offset=bias[:3], torque_offset=bias[3:])

    _summary_has_fit_test = True  # the IMU's results print it with their own lines

    def fit_test_lines(self, with_warning: bool = True) -> list[str]:
        """The summary's lines of :attr:`fit_test` (none without it): the test and, with
        ``with_warning``, its misfit warning."""
        if self.fit_test is None:
            return []
        warning = self.fit_test.warning if with_warning else None
        return [self.fit_test.summary_line()] + ([f"  WARNING: {warning}"] if warning else [])

    def summary(self) -> str:
        """Human-readable summary with units (± standard error), fit and provenance: what the
        CLI prints.
        """
        errors = self.std_errors or {}
        tilt_u, tilt_v = self.base_tilt_deg
        tilt_errors = np.rad2deg(errors["base_tilt"]) if "base_tilt" in errors else (None, None)
        lines = [
            f"ftkin calibration: method {self.method}, {self.pose_count} poses, "
            f"{self.sample_count} readings",
            f"  force_offset    F0 = {_vector(self.force_offset, 4, errors.get('force_offset'))} N "
            "(sensor frame)",
            f"  torque_offset   M0 = {_vector(self.torque_offset, 4, errors.get('torque_offset'))} "
            "N·m (sensor frame)",
            "  center_of_mass  P  = "
            f"{_vector(self.center_of_mass, 4, errors.get('center_of_mass'))} m (sensor frame)",
            "  gravity_in_base a  = "
            f"{_vector(self.gravity_in_base, 4, errors.get('gravity_in_base'))} N (base frame)",
            "  tool_weight     G  = "
            f"{scalar_text(self.tool_weight, 3, errors.get('tool_weight'))} N",
            "  tool_mass       m  = "
            f"{scalar_text(self.tool_mass, 4, errors.get('tool_mass'))} kg (g = {self.g:g} m/s²)",
            f"  base_tilt       U  = {scalar_text(tilt_u, 3, tilt_errors[0])}°, V = "
            f"{scalar_text(tilt_v, 3, tilt_errors[1])}°",
        ]
        lines += _mount_lines(self) + _inertia_lines(self)
        if self.drift is not None:
            lines.append(f"  bias drift: {self.drift.describe()}")
            if self.drift.model != "none":
                lines.append(
                    "    F0, M0 above are the bias at the end of the recording (t = "
                    f"{self.drift.end_time:.6g} s)"
                )
            if self.drift.criteria:
                lines.append(
                    "    BIC: "
                    + ", ".join(
                        f"{name} {value:.1f}" for name, value in self.drift.criteria.items()
                    )
                )
        if self.pose_count:
            lines += [
                "  residual RMS per pose: "
                + ", ".join(
                    f"{name} {v:.4f}" for name, v in zip(WRENCH_CHANNELS, self.residual_rms)
                )
                + " (N, N·m)",
                "  mean relative compensation error: "
                + ", ".join(
                    f"{name} {value:.2f}%"
                    for name, value in zip(WRENCH_CHANNELS, 100.0 * self.mean_relative_error)
                ),
            ]
        if self.diagnostics is not None:
            lines += _diagnostics_lines(self.diagnostics)
        elif self._summary_has_fit_test:
            lines += self.fit_test_lines()
        if self.urdf:
            lines.append(f"  kinematics: {self.urdf} (sensor frame {self.sensor_frame})")
        return "\n".join(lines)


def _decimals(errors, decimals: int) -> int:
    """Enough decimals to show two significant digits of the smallest standard error."""
    errors = np.atleast_1d(np.asarray([] if errors is None else errors, dtype=float))
    positive = errors[np.isfinite(errors) & (errors > 0)]
    if positive.size == 0:
        return decimals
    return int(min(max(decimals, np.ceil(-np.log10(positive.min())) + 1), 9))


def _vector(values, decimals: int, errors=None) -> str:
    decimals = _decimals(errors, decimals)
    text = "[" + ", ".join(f"{value:+.{decimals}f}" for value in values) + "]"
    if errors is not None:
        text += " ± [" + ", ".join(f"{value:.{decimals}f}" for value in errors) + "]"
    return text


def scalar_text(value, decimals: int, error=None) -> str:
    decimals = _decimals(error, decimals)
    return f"{value:.{decimals}f}" + (f" ± {error:.{decimals}f}" if error is not None else "")


def _inertia_lines(result) -> list[str]:
    """The identified inertia (± standard errors) and its principal moments, if any."""
    if not result.has_inertia:
        return []
    inertia, errors = result.inertia_about_com_in_sensor, result.inertia_std_errors
    errors = np.full((3, 3), np.nan) if errors is None else errors
    moments = ", ".join(f"{m:.6f}" for m in np.linalg.eigvalsh(inertia))
    return [
        "  inertia_about_com_in_sensor [kg·m²] (± standard error):",
        *(
            "    [" + ", ".join(f"{v:+.6f} ± {e:.6f}" for v, e in zip(*pair)) + "]"
            for pair in zip(inertia, errors)
        ),
        f"  principal moments: {moments} kg·m²",
    ]


def _mount_lines(result) -> list[str]:
    """The estimated mount and a non-default reading convention, if any."""
    lines = []
    if result.mount_mode != "none":
        errors = ", ".join(f"{name} ± {value:.3f}°" for name, value in result.mount_std_deg.items())
        lines.append(
            f"  mount_rpy_deg   R_M = {_vector(result.mount_rpy_deg, 3)}° (roll, pitch, yaw; URDF "
            "sensor frame → "
            f"real sensor frame, estimated: {result.mount_mode}; {errors})"
        )
    if result.sensor_sign != 1 or result.flip_axis is not None:
        flip = f", {result.flip_axis} axis reversed" if result.flip_axis else ""
        lines.append(
            f"  readings: sensor_sign {result.sensor_sign:+d}{flip} (applied to every reading)"
        )
    return lines


_NOISE_SOURCE_TEXT = {
    "given": "given",
    "spread": "from the spread of repeated readings",
    "residuals": "from the residuals",
}


def _diagnostics_lines(diagnostics) -> list[str]:
    """Noise, goodness of fit, outliers, observability and warnings of an ml fit."""
    noise = diagnostics.noise
    lines = [
        "  noise per reading "
        f"({_NOISE_SOURCE_TEXT.get(diagnostics.noise_source, diagnostics.noise_source)}): "
        f"force {_vector(noise.force_std, 4).replace('+', '')} N, torque "
        f"{_vector(noise.torque_std, 5).replace('+', '')} N·m"
        + (f"; loss {diagnostics.loss}" if diagnostics.loss != "linear" else "")
    ]
    if diagnostics.noise_source == "residuals":
        fit = "not testable (noise estimated from the same residuals)"
    elif diagnostics.noise_too_large:
        fit = "FITS FAR BETTER than the noise given (is it too large?)"
    elif diagnostics.fit_ok:
        fit = "consistent with the noise"
    else:
        fit = (
            "DOES NOT FIT the noise; standard errors scaled by "
            f"{diagnostics.covariance_scale**0.5:.2f}"
        )
    p_text = f", p = {diagnostics.p_value:.2g}" if np.isfinite(diagnostics.p_value) else ""
    lines += [
        f"  goodness of fit: chi-square {diagnostics.chi_square:.1f} for {diagnostics.dof} "
        f"dof{p_text}: {fit}",
        "  reduced chi-square per channel: "
        + ", ".join(
            f"{name} {value:.2f}"
            for name, value in zip(WRENCH_CHANNELS, diagnostics.channel_chi_square)
        ),
    ]
    finite = np.isfinite(diagnostics.pose_normalized_residuals)
    worst = (
        int(np.nanargmax(np.where(finite, diagnostics.pose_normalized_residuals, np.nan)))
        if finite.any()
        else None
    )
    if worst is not None:
        lines.append(
            f"  largest pose residual: pose {diagnostics.pose_ids[worst]} "
            f"{diagnostics.pose_normalized_residuals[worst]:.2f}σ (p = "
            f"{diagnostics.pose_p_values[worst]:.2g})"
        )
    if diagnostics.outlier_pose_ids:
        lines.append("  OUTLIER poses: " + ", ".join(str(i) for i in diagnostics.outlier_pose_ids))
    if diagnostics.dropped_pose_ids:
        lines.append(
            "  dropped as outliers before the final fit: poses "
            + ", ".join(str(i) for i in diagnostics.dropped_pose_ids)
        )
    weakest = ", ".join(f"{weight:+.2f} {name}" for name, weight in diagnostics.weakest_components)
    return [
        *lines,
        f"  observability: condition number {diagnostics.condition_number:.3g}, weakest direction "
        f"{weakest}",
        *(f"  WARNING: {message}" for message in diagnostics.warnings),
    ]


_BASE_FIELDS = tuple(item.name for item in fields(CalibrationResult))
"""The names of :class:`CalibrationResult`'s fields (:meth:`CalibrationResult.base_fields`)."""
