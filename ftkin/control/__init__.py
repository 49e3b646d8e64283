"""Control: raw readings in, contact wrench and joint velocities out.

:class:`Compensator` turns a raw reading [N, N·m, sensor frame] and the pose
(``q`` or ``R_BS``) into the contact wrench (raw − bias − tool gravity, what
the environment exerts on the tool, in the sensor frame). :class:`Admittance`
turns the contact-force error into a twist [m/s, rad/s] in its control frame;
:class:`JointAdmittance` maps that twist through the frame Jacobian to joint
velocities ``dq`` [rad/s] for a joint-velocity controller, with sensor-fault
handling (:class:`FaultMonitor`), an oscillation detector
(:class:`OscillationDetector`) and a safety stop. :func:`max_stable_k1` bounds
K1 on a stiff contact. :class:`LoadTracker` identifies the load in the hand
(:class:`LoadEstimator`) and tells grasps, releases, tool changes and contacts apart.

Depends on :mod:`ftkin.calibration` (the sensor model) and :mod:`ftkin.kinematics`.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "Admittance": ".admittance",
    "BiasTracker": ".bias_tracker",
    "Compensator": ".compensation",
    "ControlFrame": ".control_frame",
    "DynamicCompensator": ".dynamic_compensation",
    "FaultMonitor": ".sensor_faults",
    "ImuCompensator": ".imu_compensation",
    "JointAdmittance": ".joint_admittance",
    "LoadEstimate": ".load_estimator",
    "LoadEstimator": ".load_estimator",
    "LoadEvent": ".load_events",
    "LoadThresholds": ".load_events",
    "LoadTrack": ".load_track",
    "LoadTracker": ".load_events",
    "OscillationDetector": ".oscillation",
    "OscillationLimits": ".oscillation",
    "SensorFault": ".sensor_faults",
    "SensorLimits": ".sensor_faults",
    "StepStatus": ".joint_admittance",
    "max_stable_k1": ".stability",
    "track_load": ".load_track",
}
"""Public name → module, loaded on first access (PEP 562): importing one module of this stage does
not import them all.
"""

__all__ = [
    "Admittance",
    "BiasTracker",
    "Compensator",
    "ControlFrame",
    "DynamicCompensator",
    "FaultMonitor",
    "ImuCompensator",
    "JointAdmittance",
    "LoadEstimate",
    "LoadEstimator",
    "LoadEvent",
    "LoadThresholds",
    "LoadTrack",
    "LoadTracker",
    "OscillationDetector",
    "OscillationLimits",
    "SensorFault",
    "SensorLimits",
    "StepStatus",
    "max_stable_k1",
    "track_load",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
