"""Calibration: readings at static poses in, sensor and tool parameters out.

Takes :class:`Samples`: raw wrenches ``[fx, fy, fz, mx, my, mz]`` [N, N·m] in
the sensor frame, each with its ``R_BS`` (sensor → base). Gives a
:class:`CalibrationResult` (a :class:`SensorModel` with standard errors and
diagnostics): force and torque bias ``F0`` [N], ``M0`` [N·m], the tool's
weight vector in the base frame ``gravity_in_base`` [N] (hence weight, mass
and base tilt) and its centre of mass in the sensor frame ``P`` [m]. The
Fisher information here also serves pose planning.

Depends on the bottom layer and :mod:`ftkin.kinematics` (rotations).
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "BiasDrift": ".drift",
    "CalibrationOptions": ".fit_options",
    "CalibrationResult": ".result",
    "CausalDifferentiator": ".derivatives",
    "ConventionCheck": ".conventions",
    "ConventionReport": ".doctor",
    "CrossValidation": ".cross_validation",
    "DRIFT_CHOICES": ".drift",
    "DriftModel": ".drift",
    "DynamicCalibrationResult": ".dynamic",
    "FitDiagnostics": ".diagnostics",
    "FitTest": ".goodness_of_fit",
    "FusedCalibrationOptions": ".fused_options",
    "FusedCalibrationResult": ".fused_result",
    "FusedSamples": ".fused_samples",
    "ImuCalibrationOptions": ".imu_options",
    "ImuCalibrationResult": ".imu_result",
    "ImuSamples": ".imu_samples",
    "METHODS": ".fit_options",
    "MOUNT_MODES": ".mount",
    "MountCheck": ".mount_check",
    "MotionSamples": ".regressor",
    "STANDARD_GRAVITY": ".model",
    "Samples": ".samples",
    "SensorModel": ".model",
    "SensorNoise": ".information",
    "calibrate": ".fit_registry",
    "calibrate_dynamic": ".dynamic",
    "calibrate_fused": ".fused_fit",
    "calibrate_imu": ".imu_fit",
    "calibrate_imu_dynamic": ".imu_dynamic",
    "calibrate_static": ".estimate",
    "check_wrench_frame": ".wrench_frame",
    "cross_validate": ".cross_validation",
    "detect_sign_and_handedness": ".conventions",
    "diagnose_readings": ".doctor",
    "fisher_information": ".information",
    "joint_derivatives": ".derivatives",
    "register_drift_model": ".drift",
}
"""Public name → module: each loads on first access (PEP 562), so importing one calibration module
(the CLI's
start) does not import them all."""

__all__ = [
    "BiasDrift",
    "CalibrationOptions",
    "CalibrationResult",
    "CausalDifferentiator",
    "ConventionCheck",
    "ConventionReport",
    "CrossValidation",
    "DRIFT_CHOICES",
    "DriftModel",
    "DynamicCalibrationResult",
    "FitDiagnostics",
    "FitTest",
    "FusedCalibrationOptions",
    "FusedCalibrationResult",
    "FusedSamples",
    "ImuCalibrationOptions",
    "ImuCalibrationResult",
    "ImuSamples",
    "METHODS",
    "MOUNT_MODES",
    "MountCheck",
    "MotionSamples",
    "STANDARD_GRAVITY",
    "Samples",
    "SensorModel",
    "SensorNoise",
    "calibrate",
    "calibrate_dynamic",
    "calibrate_fused",
    "calibrate_imu",
    "calibrate_imu_dynamic",
    "calibrate_static",
    "check_wrench_frame",
    "cross_validate",
    "detect_sign_and_handedness",
    "diagnose_readings",
    "fisher_information",
    "joint_derivatives",
    "register_drift_model",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
