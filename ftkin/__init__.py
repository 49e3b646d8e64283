"""ftkin: make a robot's wrist force/torque sensor tell the truth.

Calibrate a six-axis sensor's bias, tool weight, centre of mass and base tilt
from static poses; compensate raw readings at control rate with the sensor
orientation from Pinocchio forward kinematics; control the arm compliantly
(admittance to joint velocities); plan calibration poses; see the result.

The top level holds the names of the main path, in the order a user meets them
(:data:`_GROUPS`, the groups of docs/api.md): the arm, samples, calibrate and its
result, load and save, compensate, control, plan, the simulated sensor, the errors.
Everything else is imported from its stage (``ftkin.calibration``, ``ftkin.control``,
``ftkin.io``, ...).

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
        "calibrate": ".calibration.fit_registry",
        "CalibrationOptions": ".calibration.fit_options",
        "CalibrationResult": ".calibration.result",
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

__all__ = sorted(_EXPORTS)

STAGES = ("kinematics", "calibration", "control", "planning", "io", "sim", "viz", "robot")
"""The subpackages, in data-path order (each imports on first access: ``ftkin.control``)."""

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals(), subpackages=STAGES)
