"""Were these samples read with the arm a calibration was made with?

Samples read from joint angles carry the URDF and sensor frame they were read with
(``Samples.urdf``, ``Samples.sensor_frame``); a calibration records its own. When both are known
and the URDF's file name or the sensor frame differ, the orientations of the samples are not the
ones the calibration's parameters belong to, and using them together (compensating them, a
report, the 3D view) is warned of through :mod:`logging`: by
:meth:`~ftkin.control.compensation.Compensator.compensate_samples`,
:func:`~ftkin.viz.report.report_figure` and :mod:`ftkin.viz.view_frames`, so by ``ftkin
compensate``, ``ftkin report`` and ``ftkin view`` alike.
"""

import logging
from pathlib import Path

from .result import CalibrationResult

logger = logging.getLogger(__name__)


def samples_arm_mismatch(samples, calibration) -> str | None:
    """What differs between the arm ``samples`` were read with and ``calibration``'s (URDF file
    name or sensor frame), as a warning text; None when they agree or one is not known."""
    if not isinstance(calibration, CalibrationResult):  # a model alone records no arm
        return None
    urdf, frame = calibration.urdf, calibration.sensor_frame
    if samples.urdf is None or urdf is None:
        return None
    if Path(samples.urdf).name == Path(urdf).name and samples.sensor_frame == frame:
        return None
    return (
        f"the calibration was made with {urdf} (sensor frame {frame}) but these samples were "
        f"read with {samples.urdf} (sensor frame {samples.sensor_frame})"
    )


def warn_if_samples_arm_differs(samples, calibration) -> None:
    """Log :func:`samples_arm_mismatch` as a warning, if there is one."""
    text = samples_arm_mismatch(samples, calibration)
    if text is not None:
        logger.warning("%s", text)
