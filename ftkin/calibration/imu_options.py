"""Options of the calibration from the sensor's IMU: :class:`ImuCalibrationOptions`.

Also what ``ftkin.calibrate(imu_samples, ...)`` takes as keywords; an FK
:class:`~ftkin.calibration.CalibrationOptions` carries only its noise over.
"""

from dataclasses import dataclass, fields, replace

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_rotation_batch, as_vector
from .fit_options import CalibrationOptions
from .information import SensorNoise

SCALE_MODES = ("auto", "yes", "no")


@dataclass(frozen=True)
class ImuCalibrationOptions:
    """How :func:`calibrate_imu` fits (also ``ftkin.calibrate(imu_samples, ...)``'s keywords).

    Attributes:
        imu_rotation: ``R_SI`` ``(3, 3)`` when known (a datasheet's); None estimates it.
        estimate_scale: ``"auto"`` (default: the scale where the poses determine it, else 0),
            ``"yes"`` (refused when they do not) or ``"no"``.
        wrench_noise: Noise of one raw wrench reading; None estimates it (spread of repeated
            readings, else the residuals).
        accel_noise: Noise of one accelerometer reading [m/s²] (scalar or ``(3,)``); None
            estimates it likewise.
        imu_position: ``r`` ``(3,)`` [m, sensor frame] of the IMU (a datasheet value), recorded
            for the compensation's lever arm; static poses cannot estimate it.
    """

    imu_rotation: object = None
    estimate_scale: str = "auto"
    wrench_noise: SensorNoise | None = None
    accel_noise: object = None
    imu_position: object = None

    def __post_init__(self):
        if self.imu_rotation is not None:
            rotation, single = as_rotation_batch(self.imu_rotation, "imu_rotation")
            if not single:
                raise InvalidInput("imu_rotation must be one (3, 3) rotation matrix")
            object.__setattr__(self, "imu_rotation", rotation[0])
        mode = {True: "yes", False: "no"}.get(self.estimate_scale, self.estimate_scale)
        if mode not in SCALE_MODES:
            raise InvalidInput(
                f"estimate_scale must be one of {', '.join(SCALE_MODES)} (or a bool), got "
                f"{self.estimate_scale!r}"
            )
        object.__setattr__(self, "estimate_scale", mode)
        if self.wrench_noise is not None and not isinstance(self.wrench_noise, SensorNoise):
            raise InvalidInput(
                f"wrench_noise must be an ftkin.SensorNoise, got {type(self.wrench_noise).__name__}"
            )
        if self.accel_noise is not None:
            noise = np.broadcast_to(as_float_array(self.accel_noise, "accel_noise"), (3,)).copy()
            if not np.all(np.isfinite(noise) & (noise > 0.0) & (noise < 100.0)):
                raise InvalidInput(
                    f"accel_noise must be finite, positive and below 100 m/s², got {noise}"
                )
            object.__setattr__(self, "accel_noise", noise)
        if self.imu_position is not None:
            position = as_vector(self.imu_position, 3, "imu_position [m]")
            if np.linalg.norm(position) > 1.0:
                raise InvalidInput(
                    f"imu_position is {np.linalg.norm(position):.3g} m from the sensor origin; "
                    "expected metres within 1 m (millimetres given?)"
                )
            object.__setattr__(self, "imu_position", position)

    @classmethod
    def from_keywords(cls, options=None, **keywords) -> "ImuCalibrationOptions":
        """``options`` (an :class:`ImuCalibrationOptions`, a default ``CalibrationOptions`` or
        None) with ``keywords`` replacing its fields.
        """
        known = {f.name for f in fields(cls)}
        if options is not None and not isinstance(options, cls):
            options = _from_calibration_options(options)
        unknown = set(keywords) - known
        if unknown:
            raise InvalidInput(
                f"unknown option(s) for a calibration from the IMU: {', '.join(sorted(unknown))}; "
                f"expected {', '.join(sorted(known))}"
            )
        return replace(options or cls(), **keywords)


def _from_calibration_options(options) -> ImuCalibrationOptions:
    """An FK ``CalibrationOptions`` carries only its noise over; any other setting is refused."""
    options = checked_calibration_options(
        options,
        ("noise", "g"),
        "a calibration from the IMU (ImuSamples.from_arrays)",
        "ImuCalibrationOptions",
    )
    return ImuCalibrationOptions(wrench_noise=options.noise)


def checked_calibration_options(options, carried: tuple[str, ...], kind: str, use: str):
    """``options``, an FK ``CalibrationOptions`` whose settings other than ``carried`` are the
    defaults (the IMU and fused fits take those over), or :class:`InvalidInput` naming the
    others: they are not options of ``kind``; ``use`` names the options class to use instead."""
    if not isinstance(options, CalibrationOptions):
        raise InvalidInput(f"options must be an ftkin {use}, got {type(options).__name__}")
    default = CalibrationOptions()
    changed = [
        f.name
        for f in fields(CalibrationOptions)
        if f.name not in carried and not _same(getattr(options, f.name), getattr(default, f.name))
    ]
    if changed:
        raise InvalidInput(f"{', '.join(changed)}: not options of {kind}; use {use}")
    return options


def _same(value, default) -> bool:
    if value is None or default is None:
        return value is default
    return bool(np.array_equal(np.asarray(value), np.asarray(default)))
