"""The result of a calibration from the sensor's IMU: :class:`ImuCalibrationResult`.

A :class:`~ftkin.calibration.CalibrationResult` (so it saves, loads and summarises like any other,
with the JSON keys ``tool_mass``, ``center_of_mass``, ``force_offset``, ``torque_offset``) plus
the IMU's own parameters: ``R_SI``, the accelerometer's bias and scale, the IMU's position, their
covariance and the fit's noise (its test, ``fit_test``, is every calibration's).

An IMU calibration has no base frame: ``gravity_in_base`` is ``[0, 0, −m g]`` of a level world,
so ``tool_mass`` and ``tool_weight`` read as usual and the base tilt is zero by construction.
"""

from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput
from .imu_model import IMU_ROTATION_NAMES
from .mount import rotation_to_rpy
from .result import CalibrationResult, scalar_text


def _frozen(value, shape, name: str) -> np.ndarray:
    array = np.array(value, dtype=float)
    if array.shape != shape or not np.all(np.isfinite(array)):
        raise InvalidInput(f"{name} must be a finite array of shape {shape}, got {value!r}")
    array.setflags(write=False)
    return array


@dataclass(frozen=True)
class ImuCalibrationResult(CalibrationResult):
    """A calibration made from the sensor's accelerometer (and gyro), no orientation.

    Inherits :class:`~ftkin.calibration.CalibrationResult` (``force_offset`` [N],
    ``torque_offset`` [N·m], ``center_of_mass`` [m, sensor frame], ``tool_mass`` [kg], the
    12×12 ``covariance`` over ``[a, F0, M0, P]`` with ``a = [0, 0, −m g]``, residuals per pose,
    and the inertia fields of a dynamic calibration).

    Attributes:
        imu_rotation: ``R_SI`` ``(3, 3)``: IMU-frame vectors → sensor frame.
        accel_bias: ``b`` ``(3,)`` [m/s², IMU frame].
        accel_scale: ``s`` ``(3,)`` [-]: the accelerometer reads ``(1 + s) ∘ f + b``.
        scale_estimated: ``(3,)`` which scale components were estimated (the others are 0).
        imu_position: ``r`` ``(3,)`` [m, sensor frame] of the IMU's origin, or None (unknown:
            compensation then ignores the lever arm).
        imu_position_source: ``"given"``, ``"estimated"`` or None.
        parameter_names: Names of :attr:`parameter_covariance`'s rows (``imu_rotation[x]`` is a
            rotation about the sensor's x axis [rad]).
        parameter_covariance: Covariance of the estimated parameters (their units: N, N·m, kg,
            m, rad, m/s², -), or None.
        accel_std: ``(3,)`` noise of one accelerometer reading [m/s²] used by the fit.
        imu_warnings: What the fit found doubtful (a misfit's warning of :attr:`fit_test`
            among them).
        motion_residual_rms: ``(6,)`` RMS residual over a moving recording [N, N·m], or None.
        inseparable: Parameters the data determine only in combination (empty when every one
            was separated). A moving recording without the accelerometer's bias gives
            ``("accel_bias", "force_offset", "torque_offset")``: ``accel_bias`` is then taken as 0
            and ``force_offset``, ``torque_offset`` hold the combined offsets ``F0 + m R_SI b``,
            ``M0 + m c × (R_SI b)``, which compensate this tool with this IMU exactly; a static IMU
            calibration of the same IMU splits them (``prior=``, ``--prior``).
    """

    imu_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    accel_bias: np.ndarray = field(default_factory=lambda: np.zeros(3))
    accel_scale: np.ndarray = field(default_factory=lambda: np.zeros(3))
    scale_estimated: tuple[bool, bool, bool] = (False, False, False)
    imu_position: np.ndarray | None = None
    imu_position_source: str | None = None
    parameter_names: tuple[str, ...] = ()
    parameter_covariance: np.ndarray | None = None
    accel_std: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    imu_warnings: tuple[str, ...] = ()
    motion_residual_rms: np.ndarray | None = None
    inseparable: tuple[str, ...] = ()

    _summary_has_fit_test = False  # in imu_summary_lines

    def __post_init__(self):
        super().__post_init__()
        rotation = _frozen(self.imu_rotation, (3, 3), "imu_rotation")
        if (
            not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6)
            or np.linalg.det(rotation) <= 0.0
        ):
            raise InvalidInput(
                "imu_rotation must be a rotation matrix (orthonormal, det = +1), got "
                f"{rotation.tolist()}"
            )
        object.__setattr__(self, "imu_rotation", rotation)
        object.__setattr__(self, "accel_bias", _frozen(self.accel_bias, (3,), "accel_bias"))
        object.__setattr__(self, "accel_scale", _frozen(self.accel_scale, (3,), "accel_scale"))
        if np.any(np.asarray(self.accel_scale) <= -1.0):
            raise InvalidInput(f"accel_scale must be above -1, got {self.accel_scale.tolist()}")
        object.__setattr__(self, "scale_estimated", tuple(bool(v) for v in self.scale_estimated))
        if self.imu_position is not None:
            position = _frozen(self.imu_position, (3,), "imu_position")
            object.__setattr__(self, "imu_position", position)
        if self.imu_position_source not in (None, "given", "estimated"):
            raise InvalidInput(
                "imu_position_source must be 'given', 'estimated' or None, got "
                f"{self.imu_position_source!r}"
            )
        names = tuple(str(name) for name in self.parameter_names)
        object.__setattr__(self, "parameter_names", names)
        if self.parameter_covariance is not None:
            size = len(names)
            covariance = _frozen(self.parameter_covariance, (size, size), "parameter_covariance")
            object.__setattr__(self, "parameter_covariance", covariance)
        array = np.array(self.accel_std, dtype=float).reshape(3)
        array.setflags(write=False)
        object.__setattr__(self, "accel_std", array)
        if self.motion_residual_rms is not None:
            residual = _frozen(self.motion_residual_rms, (6,), "motion_residual_rms")
            object.__setattr__(self, "motion_residual_rms", residual)
        object.__setattr__(self, "imu_warnings", tuple(str(w) for w in self.imu_warnings))
        if isinstance(self.inseparable, str):
            raise InvalidInput(
                f"inseparable must be a sequence of parameter names, got {self.inseparable!r}"
            )
        object.__setattr__(self, "inseparable", tuple(str(name) for name in self.inseparable))

    @property
    def imu_rotation_rpy_deg(self) -> np.ndarray:
        """``(3,)`` roll, pitch, yaw [deg] of ``R_SI`` (``R = Rz(yaw) Ry(pitch) Rx(roll)``)."""
        return np.rad2deg(rotation_to_rpy(self.imu_rotation))

    @property
    def parameter_std_errors(self) -> dict[str, float]:
        """Standard error of each estimated parameter by name (rotations in rad)."""
        if self.parameter_covariance is None:
            return {}
        sigma = np.sqrt(np.clip(np.diag(self.parameter_covariance), 0.0, None))
        return dict(zip(self.parameter_names, sigma.tolist()))

    def std_error_of(self, names) -> np.ndarray:
        """``(k,)`` standard errors of ``names`` (NaN for a parameter not estimated)."""
        errors = self.parameter_std_errors
        return np.array([errors.get(name, np.nan) for name in names])

    @property
    def imu_rotation_std_deg(self) -> np.ndarray:
        """``(3,)`` standard errors [deg] of ``R_SI`` about the sensor's axes (NaN if given)."""
        return np.rad2deg(self.std_error_of(IMU_ROTATION_NAMES))

    @property
    def warnings(self) -> tuple[str, ...]:
        """The IMU fit's warnings."""
        return self.imu_warnings

    def _vector(self, values, names, digits=4, scale=1.0) -> str:
        """``[v, ...] ± [σ, ...]`` of the named parameters (the ± part when all are estimated)."""
        errors = self.parameter_std_errors
        text = "[" + ", ".join(f"{v * scale:+.{digits}f}" for v in values) + "]"
        sigma = [errors.get(name) for name in names]
        if all(s is not None for s in sigma):
            text += " ± [" + ", ".join(f"{s * scale:.{digits}f}" for s in sigma) + "]"
        return text

    def summary(self) -> str:
        """Readable summary with units (± standard error): what the CLI prints."""
        errors, vector = self.parameter_std_errors, self._vector
        axes = ("x", "y", "z")
        mass_error = errors.get("tool_mass")
        lines = [
            f"ftkin calibration from the IMU: method {self.method}, "
            + (
                f"{self.pose_count} poses, {self.sample_count} readings"
                if self.pose_count
                else f"moving recording of {self.sample_count} readings"
            ),
            "  force_offset    F0 = "
            f"{vector(self.force_offset, [f'force_offset[{a}]' for a in axes])} N (sensor frame)",
            "  torque_offset   M0 = "
            f"{vector(self.torque_offset, [f'torque_offset[{a}]' for a in axes], 5)} N·m",
            f"  tool_mass       m  = {scalar_text(self.tool_mass, 4, mass_error)} kg (g = "
            f"{self.g:g} m/s²)",
            "  center_of_mass  c  = "
            f"{vector(self.center_of_mass, [f'center_of_mass[{a}]' for a in axes], 5)} m",
        ]
        return "\n".join(lines + self.imu_summary_lines())

    def imu_summary_lines(self) -> list[str]:
        """The summary's lines on the IMU: ``R_SI``, bias, scale, position, inertia, noise, fit
        and the warnings."""
        vector, axes = self._vector, ("x", "y", "z")
        lines = [
            "  imu_rotation    R_SI rpy = "
            f"{vector(np.deg2rad(self.imu_rotation_rpy_deg), IMU_ROTATION_NAMES, 3, 180 / np.pi)}°"
            " (± about the sensor axes)",
            "  accel_bias      b  = "
            f"{vector(self.accel_bias, [f'accel_bias[{a}]' for a in axes])} m/s² (IMU frame"
            + ("; taken as 0, not separated)" if "accel_bias" in self.inseparable else ")"),
        ]
        if self.inseparable:
            lines.append(
                f"  not separated   {', '.join(self.inseparable)}: only their combination is "
                "determined (the offsets include the accelerometer's bias; see the warning)"
            )
        if any(self.scale_estimated):
            lines.append(
                "  accel_scale     s  = "
                + "["
                + ", ".join(
                    f"{100 * v:+.3f}%" if estimated else "fixed 0"
                    for v, estimated in zip(self.accel_scale, self.scale_estimated)
                )
                + "]"
            )
        if self.imu_position is not None:
            lines.append(
                "  imu_position    r  = "
                f"{vector(self.imu_position, [f'imu_position[{a}]' for a in axes], 4)} m "
                f"({self.imu_position_source})"
            )
        if self.has_inertia:
            inertia = self.inertia_about_com_in_sensor
            moments = ", ".join(f"{m:.6f}" for m in np.linalg.eigvalsh(inertia))
            lines.append(f"  inertia about the COM: principal moments {moments} kg·m²")
        noise = (
            f"noise per reading: accelerometer {np.round(self.accel_std, 5).tolist()} m/s²; "
            if np.all(np.isfinite(self.accel_std))
            else ""
        )
        if noise:
            lines.append(f"  {noise.removesuffix('; ')}")
        lines += self.fit_test_lines(with_warning=False)  # the warning is among imu_warnings
        if self.motion_residual_rms is not None:
            lines.append(
                "  residual RMS over the motion: "
                + ", ".join(f"{v:.4g}" for v in self.motion_residual_rms)
                + " (N, N·m)"
            )
        return lines + [f"  WARNING: {message}" for message in self.imu_warnings]
