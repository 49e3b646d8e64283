"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

Optional extras are imported lazily: importing ftkin needs only pin, numpy
and scipy.
"""

from ._version import __version__  # noqa: F401  (re-exported: ftkin.__version__)
from .calibration.diagnostics import FitDiagnostics
from .calibration.estimate import METHODS, CalibrationResult, calibrate
from .calibration.information import SensorNoise, fisher_information
from .calibration.model import STANDARD_GRAVITY, SensorModel
from .calibration.samples import Samples
from .control.admittance import Admittance, ControlFrame
from .control.compensation import Compensator
from .control.joint_admittance import JointAdmittance, StepStatus
from .control.oscillation import OscillationDetector, OscillationLimits
from .control.sensor_faults import FaultMonitor, SensorFault, SensorLimits
from .control.stability import max_stable_k1
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
from .io.calibration_file import load_calibration, save_calibration
from .io.samples_csv import load_samples
from .kinematics.arm import Arm, SensorMount, bundled_urdf_path
from .kinematics.robots import ROBOTS, load_robot
from .kinematics.rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .planning.constraints import PoseConstraints
from .planning.evaluation import PoseEvaluation, evaluate_poses
from .planning.plan import PosePlan, plan_poses
from .sim.mujoco import (
    ArmSimulation,
    ClosedLoopRun,
    GraspedObject,
    MujocoSensor,
    build_arm_model,
    run_closed_loop,
    simulate_placement_mujoco,
)
from .sim.placement import PlacementRun, PlacementScenario, simulate_placement
from .sim.sensor import SimulatedSensor
from .sim.surfaces import Surface

__all__ = [
    "Admittance",
    "Arm",
    "ArmSimulation",
    "CalibrationFileError",
    "CalibrationResult",
    "ClosedLoopRun",
    "Compensator",
    "ControlFrame",
    "FaultMonitor",
    "FitDiagnostics",
    "FrameNotFound",
    "FtkinError",
    "GraspedObject",
    "InvalidInput",
    "InvalidSamples",
    "JointAdmittance",
    "METHODS",
    "MissingDependency",
    "MujocoSensor",
    "OscillationDetector",
    "OscillationLimits",
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
    "build_arm_model",
    "bundled_urdf_path",
    "calibrate",
    "euler_zyx_deg_to_matrix",
    "evaluate_poses",
    "fisher_information",
    "load_calibration",
    "load_robot",
    "load_samples",
    "max_stable_k1",
    "plan_poses",
    "quaternion_to_matrix",
    "run_closed_loop",
    "save_calibration",
    "simulate_placement",
    "simulate_placement_mujoco",
]
