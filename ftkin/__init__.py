"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics.
"""

from .arm import Arm, SensorMount, bundled_urdf_path
from .calibration import METHODS, CalibrationResult, calibrate
from .calibration_file import load_calibration, save_calibration
from .compensation import Compensator
from .csv_io import load_samples
from .exceptions import (
    CalibrationFileError,
    FrameNotFound,
    FtkinError,
    InvalidInput,
    InvalidSamples,
    MissingDependency,
    UnobservableParameters,
    UrdfError,
)
from .information import SensorNoise, fisher_information
from .model import STANDARD_GRAVITY, SensorModel
from .rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .samples import Samples
from .simulation import SimulatedSensor

__version__ = "0.1.0"

__all__ = [
    "Arm",
    "CalibrationFileError",
    "CalibrationResult",
    "Compensator",
    "FrameNotFound",
    "FtkinError",
    "InvalidInput",
    "InvalidSamples",
    "METHODS",
    "MissingDependency",
    "STANDARD_GRAVITY",
    "Samples",
    "SensorModel",
    "SensorMount",
    "SensorNoise",
    "SimulatedSensor",
    "UnobservableParameters",
    "UrdfError",
    "bundled_urdf_path",
    "calibrate",
    "euler_zyx_deg_to_matrix",
    "fisher_information",
    "load_calibration",
    "load_samples",
    "quaternion_to_matrix",
    "save_calibration",
]
