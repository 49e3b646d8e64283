"""Control: raw readings in, contact wrench and joint velocities out.

:class:`Compensator` turns a raw reading [N, N·m, sensor frame] and the pose
(``q`` or ``R_BS``) into the contact wrench (raw − bias − tool gravity, what
the environment exerts on the tool, in the sensor frame). :class:`Admittance`
turns the contact-force error into a twist [m/s, rad/s] in its control frame;
:class:`JointAdmittance` maps that twist through the frame Jacobian to joint
velocities ``dq`` [rad/s] for a joint-velocity controller, with sensor-fault
handling (:class:`FaultMonitor`), an oscillation detector
(:class:`OscillationDetector`) and a safety stop. :func:`max_stable_k1` bounds
K1 on a stiff contact.

Depends on :mod:`ftkin.calibration` (the sensor model) and :mod:`ftkin.kinematics`.
"""

from .admittance import Admittance
from .bias_tracker import BiasTracker
from .compensation import Compensator
from .control_frame import ControlFrame
from .dynamic_compensation import DynamicCompensator
from .joint_admittance import JointAdmittance, StepStatus
from .oscillation import OscillationDetector, OscillationLimits
from .sensor_faults import FaultMonitor, SensorFault, SensorLimits
from .stability import max_stable_k1

__all__ = [
    "Admittance",
    "BiasTracker",
    "Compensator",
    "ControlFrame",
    "DynamicCompensator",
    "FaultMonitor",
    "JointAdmittance",
    "OscillationDetector",
    "OscillationLimits",
    "SensorFault",
    "SensorLimits",
    "StepStatus",
    "max_stable_k1",
]
