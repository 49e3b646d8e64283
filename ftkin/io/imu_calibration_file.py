"""The ``imu`` entry of a calibration file: what a calibration from the sensor's IMU adds.

Written beside the keys every calibration has (``tool_mass``, ``center_of_mass``,
``force_offset``, ``torque_offset``, ...; :mod:`ftkin.io.calibration_file`), read back into an
:class:`~ftkin.calibration.imu_result.ImuCalibrationResult`. Keys (units): ``imu_rotation``
(3×3 ``R_SI``, IMU → sensor frame), ``imu_rotation_rpy_deg`` (for reading), ``accel_bias``
[m/s², IMU frame], ``accel_scale`` [-] and ``scale_estimated``, ``imu_position`` [m, sensor
frame] or null and ``imu_position_source``, ``parameter_names`` with ``parameter_covariance``
and ``std_errors``, ``accel_std`` [m/s²], ``warnings``,
``motion_residual_rms`` [N, N·m] or null, ``inseparable`` (the parameters only determined in
combination, e.g. the accelerometer's bias and the offsets of a moving recording without a
prior) and ``units``. The goodness of fit is every calibration's ``fit_test`` (beside
``imu``, the accelerometer's channels ``ax``..``az`` among its ``channel_names``). A fused
calibration (an orientation and
the IMU) adds ``fused: true`` and ``mount_check``
(:class:`~ftkin.calibration.mount_check.MountCheck`: ``R_M`` against the URDF, its covariance
[rad²], chi-square, per-pose angles [deg]; or null).
"""

import numpy as np

from ..calibration.fused_result import FusedCalibrationResult
from ..calibration.imu_result import ImuCalibrationResult
from ..calibration.mount_check import MountCheck
from ..calibration.result import CalibrationResult
from ..exceptions import FtkinError
from .json_reader import NestedReader

IMU_UNITS = {
    "imu_rotation": "IMU frame -> sensor frame (R_SI)",
    "imu_rotation_rpy_deg": "deg, roll-pitch-yaw of R_SI (R = Rz(yaw) Ry(pitch) Rx(roll))",
    "accel_bias": "m/s^2, IMU frame",
    "accel_scale": "1; the accelerometer reads (1 + s) * f + b",
    "imu_position": "m, sensor frame",
    "accel_std": "m/s^2 per reading",
    "parameter_covariance": "units of the parameters (N, N*m, kg, m, rad about the sensor axes, "
    "m/s^2, 1)",
}

IMU_TYPES = {
    "parameter_names": "strings",
    "imu_position_source": "string?",
    "warnings": "strings",
    "inseparable": "strings",
    "accel_std": "numbers?",
}


def imu_document(result: CalibrationResult) -> dict:
    """``{"imu": {...}}`` for a calibration from the IMU, else ``{}``."""
    if not isinstance(result, ImuCalibrationResult):
        return {}
    return {
        "imu": {
            "units": IMU_UNITS,
            "imu_rotation": result.imu_rotation,
            "imu_rotation_rpy_deg": result.imu_rotation_rpy_deg,
            "accel_bias": result.accel_bias,
            "accel_scale": result.accel_scale,
            "scale_estimated": [bool(v) for v in result.scale_estimated],
            "imu_position": result.imu_position,
            "imu_position_source": result.imu_position_source,
            "parameter_names": list(result.parameter_names),
            "parameter_covariance": result.parameter_covariance,
            "std_errors": result.parameter_std_errors,
            "accel_std": [None if not np.isfinite(v) else float(v) for v in result.accel_std],
            "warnings": list(result.imu_warnings),
            "motion_residual_rms": result.motion_residual_rms,
            "inseparable": list(result.inseparable),
            **_fused_document(result),
        }
    }


def _fused_document(result: ImuCalibrationResult) -> dict:
    """A fused calibration's ``mount_check`` (null when its poses could not check the mount)."""
    if not isinstance(result, FusedCalibrationResult):
        return {}
    check = result.mount_check
    return {"fused": True, "mount_check": None if check is None else check.to_dict()}


def imu_result(reader, result: CalibrationResult) -> ImuCalibrationResult:
    """The :class:`ImuCalibrationResult` of a file whose ``imu`` entry ``reader`` reads, with the
    common fields of ``result`` (its inertia too, when the file has one)."""
    data = reader.optional_object("imu") or {}
    sub = NestedReader(reader.path, data, "imu")
    sub.check_types(IMU_TYPES)
    names = tuple(data.get("parameter_names") or ())
    flags = data.get("scale_estimated", [False, False, False])
    if not (
        isinstance(flags, list) and len(flags) == 3 and all(isinstance(v, bool) for v in flags)
    ):
        sub.fail("expected three booleans", "scale_estimated")
    common = result.base_fields()
    fused = {}
    if data.get("fused") is True:  # a fused calibration: its mount check
        check = sub.optional_object("mount_check")
        fused = {"mount_check": None if check is None else _mount_check(sub, check)}
    try:
        return (FusedCalibrationResult if fused else ImuCalibrationResult)(
            **common,
            **fused,
            imu_rotation=sub.array("imu_rotation", (3, 3)),
            accel_bias=sub.array("accel_bias", (3,)),
            accel_scale=sub.array("accel_scale", (3,)),
            scale_estimated=tuple(flags),
            imu_position=sub.array("imu_position", (3,), required=False),
            imu_position_source=sub.optional("imu_position_source", str),
            parameter_names=names,
            parameter_covariance=sub.array(
                "parameter_covariance", (len(names), len(names)), required=False
            ),
            accel_std=np.array(
                [np.nan if v is None else v for v in data.get("accel_std") or [None] * 3],
                dtype=float,
            ),
            imu_warnings=tuple(data.get("warnings") or ()),
            motion_residual_rms=sub.array("motion_residual_rms", (6,), required=False),
            inseparable=tuple(data.get("inseparable") or ()),
        )
    except (FtkinError, TypeError, ValueError) as error:
        sub.fail(f"malformed: {str(error)[:200]}")


def _mount_check(reader, data: dict) -> MountCheck:
    """The ``imu.mount_check`` entry (its derived figures are recomputed, not trusted)."""
    try:
        return MountCheck.from_dict(data)
    except (FtkinError, KeyError, TypeError, ValueError) as error:
        reader.fail(f"malformed: {str(error)[:200]}", "mount_check")
