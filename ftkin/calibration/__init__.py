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

from .conventions import ConventionReport, diagnose_readings
from .diagnostics import FitDiagnostics
from .estimate import METHODS, CalibrationResult, calibrate
from .information import SensorNoise, fisher_information
from .model import STANDARD_GRAVITY, SensorModel
from .samples import Samples

__all__ = [
    "METHODS",
    "STANDARD_GRAVITY",
    "CalibrationResult",
    "ConventionReport",
    "FitDiagnostics",
    "Samples",
    "SensorModel",
    "SensorNoise",
    "calibrate",
    "diagnose_readings",
    "fisher_information",
]
