"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

Importing ftkin is cheap: each public name loads its module on first use
(PEP 562), so ``ftkin --version`` and a script using only the compensation
do not import the planner or the I/O layer. Optional extras (and scipy) are
imported where they are used.
"""

import importlib

from ._version import __version__  # noqa: F401  (re-exported: ftkin.__version__)

_EXPORTS = {
    "Admittance": ".control.admittance",
    "Arm": ".kinematics.arm",
    "CalibrationFileError": ".exceptions",
    "CalibrationResult": ".calibration.estimate",
    "Compensator": ".control.compensation",
    "ControlFrame": ".control.admittance",
    "FaultMonitor": ".control.sensor_faults",
    "FitDiagnostics": ".calibration.diagnostics",
    "FrameNotFound": ".exceptions",
    "FtkinError": ".exceptions",
    "InvalidInput": ".exceptions",
    "InvalidSamples": ".exceptions",
    "JointAdmittance": ".control.joint_admittance",
    "METHODS": ".calibration.estimate",
    "MissingDependency": ".exceptions",
    "PlacementRun": ".sim.placement",
    "PlacementScenario": ".sim.placement",
    "PoseConstraints": ".planning.constraints",
    "PoseEvaluation": ".planning.evaluation",
    "PosePlan": ".planning.plan",
    "ROBOTS": ".kinematics.robots",
    "STANDARD_GRAVITY": ".calibration.model",
    "Samples": ".calibration.samples",
    "SensorFault": ".control.sensor_faults",
    "SensorLimits": ".control.sensor_faults",
    "SensorModel": ".calibration.model",
    "SensorMount": ".kinematics.arm",
    "SensorNoise": ".calibration.information",
    "SimulatedSensor": ".sim.sensor",
    "StepStatus": ".control.joint_admittance",
    "Surface": ".sim.surfaces",
    "UnobservableParameters": ".exceptions",
    "UrdfError": ".exceptions",
    "bundled_urdf_path": ".kinematics.arm",
    "calibrate": ".calibration.estimate",
    "euler_zyx_deg_to_matrix": ".kinematics.rotations",
    "evaluate_poses": ".planning.evaluation",
    "fisher_information": ".calibration.information",
    "load_calibration": ".io.calibration_file",
    "load_robot": ".kinematics.robots",
    "load_samples": ".io.samples_csv",
    "plan_poses": ".planning.plan",
    "quaternion_to_matrix": ".kinematics.rotations",
    "save_calibration": ".io.calibration_file",
    "simulate_placement": ".sim.placement",
}
"""Public name → the module defining it (imported on first access)."""

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


def __getattr__(name: str):
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'ftkin' has no attribute {name!r}")
    value = getattr(importlib.import_module(module, __name__), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
