"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

Optional extras are imported lazily: importing ftkin needs only pin, numpy
and scipy.
"""

from .admittance import Admittance, ControlFrame
from .arm import Arm, SensorMount, bundled_urdf_path
from .calibration import METHODS, CalibrationResult, calibrate
from .calibration_file import load_calibration, save_calibration
from .compensation import Compensator
from .csv_io import load_samples
from .diagnostics import FitDiagnostics
from .evaluation import PoseEvaluation, evaluate_poses
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
from .joint_admittance import JointAdmittance, StepStatus
from .model import STANDARD_GRAVITY, SensorModel
from .placement import PlacementRun, PlacementScenario, simulate_placement
from .planning import PosePlan, plan_poses
from .pose_constraints import PoseConstraints
from .robots import ROBOTS, load_robot
from .rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .samples import Samples
from .sensor_faults import FaultMonitor, SensorFault, SensorLimits
from .simulation import SimulatedSensor
from .surfaces import Surface

__version__ = "0.1.0"

__all__ = [
    "Admittance",
    "Arm",
    "CalibrationFileError",
    "CalibrationResult",
    "Compensator",
    "ControlFrame",
    "FaultMonitor",
    "FitDiagnostics",
    "FrameNotFound",
    "FtkinError",
    "InvalidInput",
    "InvalidSamples",
    "JointAdmittance",
    "METHODS",
    "MissingDependency",
    "PlacementRun",
    "PlacementScenario",
    "PoseConstraints",
    "PoseEvaluation",
    "PosePlan",
    "ROBOTS",
    "STANDARD_GRAVITY",
    "Samples",
    "SensorFault",
    "SensorLimits",
    "SensorModel",
    "SensorMount",
    "SensorNoise",
    "SimulatedSensor",
    "StepStatus",
    "Surface",
    "UnobservableParameters",
    "UrdfError",
    "bundled_urdf_path",
    "calibrate",
    "euler_zyx_deg_to_matrix",
    "evaluate_poses",
    "fisher_information",
    "load_calibration",
    "load_robot",
    "load_samples",
    "plan_poses",
    "quaternion_to_matrix",
    "save_calibration",
    "simulate_placement",
]
