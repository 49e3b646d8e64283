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

from .._lazy import lazy_exports

_EXPORTS = {
    "MotionRecording": ".motion_recording",
    "Payload": ".payload_inertia",
    "Stream": ".stream_join",
    "diagnose_samples": ".table_readings",
    "export_payload": ".export",
    "join_streams": ".stream_join",
    "load_calibration": ".calibration_file",
    "load_imu_samples": ".imu_columns",
    "load_motion_bag": ".motion_recording",
    "load_motion_csv": ".motion_recording",
    "load_samples": ".samples_csv",
    "payload_in_flange": ".payload_export",
    "save_calibration": ".calibration_file",
}
"""Public name → module: each loads on first access (PEP 562), so ``import ftkin.io.samples_csv``
does
not import the calibration file, motion recordings and payload exports (start-up of the CLI)."""

__all__ = [
    "MotionRecording",
    "Payload",
    "Stream",
    "diagnose_samples",
    "export_payload",
    "join_streams",
    "load_calibration",
    "load_imu_samples",
    "load_motion_bag",
    "load_motion_csv",
    "load_samples",
    "payload_in_flange",
    "save_calibration",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
