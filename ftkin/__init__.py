"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

The top level holds the names of the main path, in the order a user meets them
(:data:`_GROUPS`, the groups of docs/api.md): the arm, samples, calibrate and its
result, load and save, compensate, control, plan, the simulated sensor, the errors.
Everything else is imported from its stage (``ftkin.calibration``, ``ftkin.control``,
``ftkin.io``, ...); a name that used to be at the top level still works there for
one release, with a ``FutureWarning`` naming its stage (:data:`_MOVED`).

Importing ftkin is cheap: each public name loads its module on first use
(PEP 562), so ``ftkin --version`` and a script using only the compensation
do not import the planner or the I/O layer. Optional extras (and scipy) are
imported where they are used.
"""

from ._lazy import lazy_exports
from ._version import __version__  # noqa: F401  (re-exported: ftkin.__version__)

_GROUPS = {
    "The arm": {
        "Arm": ".kinematics.arm",
        "load_robot": ".kinematics.robots",
        "SensorMount": ".kinematics.arm",
    },
    "Samples": {
        "Samples": ".calibration.samples",
        "load_samples": ".io.samples_csv",
    },
    "Calibrate": {
        "calibrate": ".calibration.estimate",
        "CalibrationOptions": ".calibration.estimate",
        "CalibrationResult": ".calibration.estimate",
        "SensorModel": ".calibration.model",
        "SensorNoise": ".calibration.information",
        "calibrate_dynamic": ".calibration.dynamic",
        "DynamicCalibrationResult": ".calibration.dynamic",
    },
    "Load and save": {
        "load_calibration": ".io.calibration_file",
        "save_calibration": ".io.calibration_file",
    },
    "Compensate": {
        "Compensator": ".control.compensation",
        "DynamicCompensator": ".control.dynamic_compensation",
    },
    "Control": {
        "Admittance": ".control.admittance",
        "JointAdmittance": ".control.joint_admittance",
    },
    "Plan": {
        "plan_poses": ".planning.plan",
        "PlanSpec": ".planning.plan",
        "PoseConstraints": ".planning.constraints",
        "evaluate_poses": ".planning.evaluation",
        "plan_excitation": ".planning.excitation",
    },
    "Simulate": {
        "SimulatedSensor": ".sim.sensor",
    },
    "Errors": {
        "FtkinError": ".exceptions",
        "InvalidInput": ".exceptions",
        "InvalidSamples": ".exceptions",
        "FrameNotFound": ".exceptions",
        "UrdfError": ".exceptions",
        "UnobservableParameters": ".exceptions",
        "CalibrationFileError": ".exceptions",
        "MissingDependency": ".exceptions",
        "ConventionMistake": ".exceptions",
        "UnexplainedReadings": ".exceptions",
        "InconsistentPoses": ".exceptions",
    },
}
"""The top-level names by group, in the user's order: ``{group: {name: defining module}}``."""

_EXPORTS = {name: module for names in _GROUPS.values() for name, module in names.items()}
"""Public name → the module defining it (imported on first access)."""

_MOVED = {
    "ArmSimulation": ".sim.mujoco",
    "BiasDrift": ".calibration",
    "BiasTracker": ".control",
    "CausalDifferentiator": ".calibration",
    "ClosedLoopRun": ".sim.mujoco",
    "ControlFrame": ".control",
    "ConventionCheck": ".calibration",
    "ConventionReport": ".calibration",
    "CrossValidation": ".calibration",
    "DRIFT_CHOICES": ".calibration",
    "DriftModel": ".calibration",
    "ExcitationPlan": ".planning",
    "ExcitationSpec": ".planning",
    "ExpectedCalibration": ".planning",
    "FaultMonitor": ".control",
    "FitDiagnostics": ".calibration",
    "FourierTrajectory": ".planning",
    "GraspedObject": ".sim.mujoco",
    "METHODS": ".calibration",
    "MOUNT_MODES": ".calibration",
    "MotionRecording": ".io",
    "MotionSamples": ".calibration",
    "MujocoRecorder": ".sim",
    "MujocoSensor": ".sim.mujoco",
    "OscillationDetector": ".control",
    "OscillationLimits": ".control",
    "Payload": ".io",
    "PlacementRun": ".sim",
    "PlacementScenario": ".sim",
    "PoseEvaluation": ".planning",
    "PosePlan": ".planning",
    "ROBOTS": ".kinematics",
    "STANDARD_GRAVITY": ".calibration",
    "SensorDrift": ".sim",
    "SensorFault": ".control",
    "SensorLimits": ".control",
    "StepStatus": ".control",
    "Surface": ".sim",
    "SuspectConvention": ".exceptions",
    "ToolInertia": ".sim",
    "build_arm_model": ".sim",
    "bundled_urdf_path": ".kinematics",
    "cross_validate": ".calibration",
    "detect_sign_and_handedness": ".calibration",
    "diagnose_samples": ".io",
    "euler_zyx_deg_to_matrix": ".kinematics",
    "export_payload": ".io",
    "fisher_information": ".calibration",
    "joint_derivatives": ".calibration",
    "load_motion_bag": ".io",
    "load_motion_csv": ".io",
    "max_stable_k1": ".control",
    "mounted_arm": ".kinematics",
    "payload_in_flange": ".io",
    "quaternion_to_matrix": ".kinematics",
    "recording_times": ".sim",
    "register_drift_model": ".calibration",
    "run_closed_loop": ".sim",
    "simulate_placement": ".sim",
    "simulate_placement_mujoco": ".sim",
}
"""Names that left the top level → the stage that exports them (deprecated here)."""

__all__ = sorted(_EXPORTS)

STAGES = ("kinematics", "calibration", "control", "planning", "io", "sim", "viz", "robot")
"""The subpackages, in data-path order (each imports on first access: ``ftkin.control``)."""

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals(), moved=_MOVED, subpackages=STAGES)
