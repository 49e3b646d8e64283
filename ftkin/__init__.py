"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

Optional extras are imported lazily: importing ftkin needs only pin, numpy
and scipy.
"""

from ._version import __version__  # noqa: F401  (re-exported: ftkin.__version__)
from .calibration.conventions import ConventionCheck, detect_sign_and_handedness
from .calibration.derivatives import CausalDifferentiator, joint_derivatives
from .calibration.diagnostics import FitDiagnostics
from .calibration.doctor import ConventionReport
from .calibration.drift import DRIFT_CHOICES, BiasDrift
from .calibration.dynamic import DynamicCalibrationResult, calibrate_dynamic
from .calibration.estimate import METHODS, CalibrationResult, calibrate
from .calibration.information import SensorNoise, fisher_information
from .calibration.model import STANDARD_GRAVITY, SensorModel
from .calibration.mount import MOUNT_MODES
from .calibration.regressor import MotionSamples
from .calibration.samples import Samples
from .control.admittance import Admittance, ControlFrame
from .control.bias_tracker import BiasTracker
from .control.compensation import Compensator
from .control.dynamic_compensation import DynamicCompensator
from .control.joint_admittance import JointAdmittance, StepStatus
from .control.oscillation import OscillationDetector, OscillationLimits
from .control.sensor_faults import FaultMonitor, SensorFault, SensorLimits
from .control.stability import max_stable_k1
from .exceptions import (
    CalibrationFileError,
    ConventionMistake,
    FrameNotFound,
    FtkinError,
    InvalidInput,
    InvalidSamples,
    MissingDependency,
    SuspectConvention,
    UnobservableParameters,
    UrdfError,
)
from .io.calibration_file import load_calibration, save_calibration
from .io.conventions import diagnose_samples
from .io.motion_recording import MotionRecording, load_motion_bag, load_motion_csv
from .io.payload_export import Payload, export_payload, payload_in_flange
from .io.samples_csv import load_samples
from .kinematics.arm import Arm, SensorMount, bundled_urdf_path
from .kinematics.mounting import mounted_arm
from .kinematics.robots import ROBOTS, load_robot
from .kinematics.rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .planning.constraints import PoseConstraints
from .planning.evaluation import PoseEvaluation, evaluate_poses
from .planning.excitation import ExcitationPlan, FourierTrajectory, plan_excitation
from .planning.plan import PosePlan, plan_poses
from .sim.drift import SensorDrift
from .sim.mujoco import (
    ArmSimulation,
    ClosedLoopRun,
    GraspedObject,
    MujocoRecorder,
    MujocoSensor,
    ToolInertia,
    build_arm_model,
    run_closed_loop,
    simulate_placement_mujoco,
)
from .sim.placement import PlacementRun, PlacementScenario, simulate_placement
from .sim.sensor import SimulatedSensor, recording_times
from .sim.surfaces import Surface

__all__ = [
    "Admittance",
    "Arm",
    "ArmSimulation",
    "BiasDrift",
    "BiasTracker",
    "CalibrationFileError",
    "CalibrationResult",
    "CausalDifferentiator",
    "ClosedLoopRun",
    "Compensator",
    "ControlFrame",
    "ConventionCheck",
    "ConventionMistake",
    "ConventionReport",
    "DRIFT_CHOICES",
    "DynamicCalibrationResult",
    "DynamicCompensator",
    "ExcitationPlan",
    "FaultMonitor",
    "FitDiagnostics",
    "FourierTrajectory",
    "FrameNotFound",
    "FtkinError",
    "GraspedObject",
    "InvalidInput",
    "InvalidSamples",
    "JointAdmittance",
    "METHODS",
    "MOUNT_MODES",
    "MissingDependency",
    "MotionRecording",
    "MotionSamples",
    "MujocoRecorder",
    "MujocoSensor",
    "OscillationDetector",
    "OscillationLimits",
    "Payload",
    "PlacementRun",
    "PlacementScenario",
    "PoseConstraints",
    "PoseEvaluation",
    "PosePlan",
    "ROBOTS",
    "STANDARD_GRAVITY",
    "Samples",
    "SensorDrift",
    "SensorFault",
    "SensorLimits",
    "SensorModel",
    "SensorMount",
    "SensorNoise",
    "SimulatedSensor",
    "StepStatus",
    "Surface",
    "SuspectConvention",
    "ToolInertia",
    "UnobservableParameters",
    "UrdfError",
    "build_arm_model",
    "bundled_urdf_path",
    "calibrate",
    "calibrate_dynamic",
    "detect_sign_and_handedness",
    "diagnose_samples",
    "euler_zyx_deg_to_matrix",
    "evaluate_poses",
    "export_payload",
    "fisher_information",
    "joint_derivatives",
    "load_calibration",
    "load_motion_bag",
    "load_motion_csv",
    "load_robot",
    "load_samples",
    "max_stable_k1",
    "mounted_arm",
    "payload_in_flange",
    "plan_excitation",
    "plan_poses",
    "quaternion_to_matrix",
    "recording_times",
    "run_closed_loop",
    "save_calibration",
    "simulate_placement",
    "simulate_placement_mujoco",
]
