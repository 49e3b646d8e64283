"""File formats: samples and calibrations to and from disk, exports for ROS controllers.

* Samples CSV (:func:`load_samples`) and ROS 2 bags (optional extra ``bags``)
  in, :class:`~ftkin.calibration.Samples` out; static segments are found in
  moving recordings.
* The calibration file: versioned JSON in SI units (:func:`save_calibration`,
  :func:`load_calibration`).
* Exports to the parameter formats of ROS controllers, and the tool as the
  robot controller's payload (Franka ``SetLoad``, UR ``set_payload``).
* Every file is written atomically (temporary file in the target's folder, then rename).

Depends on :mod:`ftkin.calibration` and :mod:`ftkin.kinematics`.
"""

from .calibration_file import load_calibration, save_calibration
from .conventions import diagnose_samples
from .motion_recording import MotionRecording, load_motion_bag, load_motion_csv
from .payload_export import Payload, export_payload, payload_in_flange
from .samples_csv import load_samples

__all__ = [
    "MotionRecording",
    "Payload",
    "diagnose_samples",
    "export_payload",
    "load_calibration",
    "load_motion_bag",
    "load_motion_csv",
    "load_samples",
    "payload_in_flange",
    "save_calibration",
]
