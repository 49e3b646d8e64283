"""Options of the fused calibration (an orientation and the IMU): :class:`FusedCalibrationOptions`.

Also what ``ftkin.calibrate(fused_samples, ...)`` takes as keywords: its own fields and those of
:class:`~ftkin.calibration.imu_options.ImuCalibrationOptions` (the IMU's rotation, scale, noise
and position). An FK :class:`~ftkin.calibration.CalibrationOptions` carries its noise, mount mode
and reading conventions over.
"""

from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..exceptions import InvalidInput
from .conventions import check_flip_axis, check_sensor_sign
from .imu_options import ImuCalibrationOptions, checked_calibration_options
from .mount import MountMode

MOUNT_TOLERANCE_DEG = 0.2
"""Default smallest mount angle [deg] the check warns about, beside being beyond the noise: a
15 N tool seen 0.2° off is 0.05 N, the noise of a typical reading."""


@dataclass(frozen=True)
class FusedCalibrationOptions:
    """How :func:`~ftkin.calibration.fused_fit.calibrate_fused` fits.

    Attributes:
        estimate_mount: ``"none"`` (default: the orientation's sensor frame is the sensor's, and
            the mount is only checked), ``"yaw"`` or ``"full"``: estimate ``R_M`` jointly
            (samples from joint angles only, as for the FK fit).
        mount_tolerance_deg: Smallest mount angle [deg] the check warns about (it must also be
            beyond the noise); 0 warns on any significant one.
        sensor_sign: ``+1`` or ``-1`` (negate every wrench reading), as for the FK fit.
        flip_axis: None or ``"x"``, ``"y"``, ``"z"``: negate that axis's force and torque.
        imu: The IMU's options (``imu_rotation`` given or estimated, ``estimate_scale``,
            ``wrench_noise``, ``accel_noise``, ``imu_position``).
    """

    estimate_mount: MountMode | str = MountMode.NONE
    mount_tolerance_deg: float = MOUNT_TOLERANCE_DEG
    sensor_sign: int = 1
    flip_axis: str | None = None
    imu: ImuCalibrationOptions = field(default_factory=ImuCalibrationOptions)

    def __post_init__(self):
        object.__setattr__(self, "estimate_mount", MountMode.of(self.estimate_mount))
        tolerance = self.mount_tolerance_deg
        if not isinstance(tolerance, int | float) or not (0.0 <= tolerance < 90.0):
            raise InvalidInput(
                f"mount_tolerance_deg must be a number of degrees in [0, 90), got {tolerance!r}"
            )
        object.__setattr__(self, "mount_tolerance_deg", float(tolerance))
        object.__setattr__(self, "sensor_sign", check_sensor_sign(self.sensor_sign))
        check_flip_axis(self.flip_axis)
        if not isinstance(self.imu, ImuCalibrationOptions):
            raise InvalidInput(
                f"imu must be an ftkin ImuCalibrationOptions, got {type(self.imu).__name__}"
            )

    @classmethod
    def from_keywords(cls, options=None, **keywords) -> "FusedCalibrationOptions":
        """``options`` (these, an ``ImuCalibrationOptions``, an FK ``CalibrationOptions`` or None)
        with ``keywords`` (fields of either class) replacing theirs.
        """
        if options is None or isinstance(options, cls):
            base = options or cls()
        elif isinstance(options, ImuCalibrationOptions):
            base = cls(imu=options)
        else:
            base = _from_calibration_options(options)
        own = {f.name for f in fields(cls)} - {"imu"}
        imu_names = {f.name for f in fields(ImuCalibrationOptions)}
        unknown = set(keywords) - own - imu_names
        if unknown:
            raise InvalidInput(
                f"unknown option(s) for a fused calibration: {', '.join(sorted(unknown))}; "
                f"expected {', '.join(sorted(own | imu_names))}"
            )
        imu = replace(base.imu, **{k: v for k, v in keywords.items() if k in imu_names})
        return replace(base, imu=imu, **{k: v for k, v in keywords.items() if k in own})

    @property
    def mount_tolerance(self) -> float:
        """:attr:`mount_tolerance_deg` in radians."""
        return float(np.deg2rad(self.mount_tolerance_deg))


def _from_calibration_options(options) -> FusedCalibrationOptions:
    """An FK ``CalibrationOptions``: its noise, mount mode, sign and flip carry over; any other
    setting is refused."""
    # convention_check: the fused fit reads no orientation under its mistakes (nothing to skip)
    options = checked_calibration_options(
        options,
        ("noise", "g", "estimate_mount", "sensor_sign", "flip_axis", "convention_check"),
        "the fused calibration (an orientation and the IMU: one maximum-likelihood fit, the "
        "base's gravity measured)",
        "FusedCalibrationOptions",
    )
    return FusedCalibrationOptions(
        estimate_mount=options.estimate_mount,
        sensor_sign=options.sensor_sign,
        flip_axis=options.flip_axis,
        imu=ImuCalibrationOptions(wrench_noise=options.noise),
    )
