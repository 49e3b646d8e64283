"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

Optional extras are imported lazily: importing ftkin needs only pin, numpy
and scipy.
"""

from ._version import __version__  # noqa: F401  (re-exported: ftkin.__version__)
from .calibration.conventions import ConventionReport
from .calibration.diagnostics import FitDiagnostics
from .calibration.estimate import METHODS, CalibrationResult, calibrate
from .calibration.information import SensorNoise, fisher_information
from .calibration.model import STANDARD_GRAVITY, SensorModel
from .calibration.samples import Samples
from .control.admittance import Admittance, ControlFrame
from .control.compensation import Compensator
from .control.joint_admittance import JointAdmittance, StepStatus
from .control.sensor_faults import FaultMonitor, SensorFault, SensorLimits
from .exceptions import (
    CalibrationFileError,
    ConventionMistake,
    FrameNotFound,
    FtkinError,
    InvalidInput,
    InvalidSamples,
    MissingDependency,
    UnobservableParameters,
    UrdfError,
)
from .io.calibration_file import load_calibration, save_calibration
from .io.conventions import diagnose_samples
from .io.samples_csv import load_samples
from .kinematics.arm import Arm, SensorMount, bundled_urdf_path
from .kinematics.robots import ROBOTS, load_robot
from .kinematics.rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .planning.constraints import PoseConstraints
from .planning.evaluation import PoseEvaluation, evaluate_poses
from .planning.plan import PosePlan, plan_poses
from .sim.placement import PlacementRun, PlacementScenario, simulate_placement
from .sim.sensor import SimulatedSensor
from .sim.surfaces import Surface

__all__ = [
    "Admittance",
    "Arm",
    "CalibrationFileError",
    "CalibrationResult",
    "Compensator",
    "ControlFrame",
    "ConventionMistake",
    "ConventionReport",
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
    "diagnose_samples",
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
