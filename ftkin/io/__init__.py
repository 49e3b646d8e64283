"""File formats: samples and calibrations to and from disk, exports for ROS controllers.

* Samples CSV (:func:`load_samples`) and ROS 2 bags (optional extra ``bags``)
  in, :class:`~ftkin.calibration.Samples` out; static segments are found in
  moving recordings.
* The calibration file: versioned JSON in SI units (:func:`save_calibration`,
  :func:`load_calibration`).
* Exports to the parameter formats of ROS controllers.
* Every file is written atomically (temporary file in the target's folder, then rename).

Depends on :mod:`ftkin.calibration` and :mod:`ftkin.kinematics`.
"""

from .calibration_file import load_calibration, save_calibration
from .conventions import diagnose_samples
from .samples_csv import load_samples

__all__ = [
    "diagnose_samples",
    "load_calibration",
    "load_samples",
    "save_calibration",
]
