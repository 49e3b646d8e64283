"""``ftkin.calibrate``: the fit a calibration's samples ask for, chosen by their type.

Each samples type has its fit, in :data:`FITS`:

* :class:`~ftkin.calibration.samples.Samples` (an orientation per reading): the static fit
  :func:`~ftkin.calibration.estimate.calibrate_static`
  (:class:`~ftkin.calibration.fit_options.CalibrationOptions`);
* :class:`~ftkin.calibration.imu_samples.ImuSamples` (the sensor's accelerometer instead):
  :func:`~ftkin.calibration.imu_fit.calibrate_imu`
  (:class:`~ftkin.calibration.imu_options.ImuCalibrationOptions`);
* :class:`~ftkin.calibration.fused_samples.FusedSamples` (both):
  :func:`~ftkin.calibration.fused_fit.calibrate_fused`
  (:class:`~ftkin.calibration.fused_options.FusedCalibrationOptions`).

This module sits above every fit and imports a fit's module when samples of its type first
come (the IMU's modules stay out of the FK paths); no fit imports it. A subclass of a samples
type is fitted as its nearest registered base.
"""

from collections.abc import Callable

from ..exceptions import InvalidInput
from .result import CalibrationResult


def _static() -> Callable:
    from .estimate import calibrate_static

    return calibrate_static


def _imu() -> Callable:
    from .imu_fit import calibrate_imu  # loaded with the first calibration from the IMU

    return calibrate_imu


def _fused() -> Callable:
    from .fused_fit import calibrate_fused  # loaded with the first fused calibration

    return calibrate_fused


FITS: dict[str, Callable[[], Callable]] = {
    "ftkin.calibration.samples.Samples": _static,
    "ftkin.calibration.imu_samples.ImuSamples": _imu,
    "ftkin.calibration.fused_samples.FusedSamples": _fused,
}
"""Samples type (``module.QualifiedName``) → a function that imports and returns its fit
``fit(samples, options=None, **keywords)``. Named, not imported: a type's module loads with its
samples, never with this table."""


def fit_for(samples) -> Callable:
    """The fit for ``samples``: the one of its type, or of its nearest registered base.

    Raises:
        InvalidInput: ``samples`` is of no registered type.
    """
    for kind in type(samples).__mro__:
        load = FITS.get(f"{kind.__module__}.{kind.__qualname__}")
        if load is not None:
            return load()
    raise InvalidInput(
        f"samples must be an ftkin.Samples, got {type(samples).__name__}: readings with their "
        "orientations (Samples.from_rotations, from_joint_positions, ...), or ImuSamples "
        "(ImuSamples.from_arrays: with the sensor's accelerometer) or FusedSamples "
        "(FusedSamples.from_arrays: both)"
    )


def calibrate(samples, options=None, **keywords) -> CalibrationResult:
    """Calibrate the sensor from ``samples`` with the fit of their type (:data:`FITS`).

    Args:
        samples: :class:`~ftkin.calibration.samples.Samples` (raw readings with sensor
            orientations; readings sharing a pose id are averaged first) are fitted by
            :func:`~ftkin.calibration.estimate.calibrate_static`;
            :class:`~ftkin.calibration.imu_samples.ImuSamples` (the sensor's accelerometer:
            ``ImuSamples.from_arrays``) by :func:`~ftkin.calibration.imu_fit.calibrate_imu`;
            :class:`~ftkin.calibration.fused_samples.FusedSamples` (both:
            ``FusedSamples.from_arrays(samples, specific_force)``) by
            :func:`~ftkin.calibration.fused_fit.calibrate_fused`.
        options: That fit's options: a :class:`~ftkin.calibration.fit_options.CalibrationOptions`
            (default: all defaults), or
            :class:`~ftkin.calibration.imu_options.ImuCalibrationOptions`,
            :class:`~ftkin.calibration.fused_options.FusedCalibrationOptions` (which take over
            the settings of a ``CalibrationOptions`` that apply to them and refuse the others).
        **keywords: The options' fields, given directly (``method="linear"``,
            ``drift="poly:2"``, ...); they replace those of ``options``.

    Returns:
        A frozen :class:`~ftkin.calibration.result.CalibrationResult`
        (:class:`~ftkin.calibration.imu_result.ImuCalibrationResult`,
        :class:`~ftkin.calibration.fused_result.FusedCalibrationResult` for the IMU's fits).

    Raises:
        InvalidInput: samples of no registered type.
        FtkinError: what the chosen fit raises, listed in its own docstring
            (:func:`~ftkin.calibration.estimate.calibrate_static`,
            :func:`~ftkin.calibration.imu_fit.calibrate_imu`,
            :func:`~ftkin.calibration.fused_fit.calibrate_fused`): one list for each fit, kept
            where the fit is.
    """
    return fit_for(samples)(samples, options, **keywords)
