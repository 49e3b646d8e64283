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

from .conventions import ConventionCheck, detect_sign_and_handedness
from .derivatives import CausalDifferentiator, joint_derivatives
from .diagnostics import FitDiagnostics
from .doctor import ConventionReport, diagnose_readings
from .drift import DRIFT_CHOICES, BiasDrift
from .dynamic import DynamicCalibrationResult, calibrate_dynamic
from .estimate import METHODS, CalibrationResult, calibrate
from .information import SensorNoise, fisher_information
from .model import STANDARD_GRAVITY, SensorModel
from .mount import MOUNT_MODES
from .regressor import MotionSamples
from .samples import Samples

__all__ = [
    "BiasDrift",
    "CalibrationResult",
    "CausalDifferentiator",
    "ConventionCheck",
    "ConventionReport",
    "DRIFT_CHOICES",
    "DynamicCalibrationResult",
    "FitDiagnostics",
    "METHODS",
    "MOUNT_MODES",
    "MotionSamples",
    "STANDARD_GRAVITY",
    "Samples",
    "SensorModel",
    "SensorNoise",
    "calibrate",
    "calibrate_dynamic",
    "detect_sign_and_handedness",
    "diagnose_readings",
    "fisher_information",
    "joint_derivatives",
]
