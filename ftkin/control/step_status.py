"""What one control tick did: :class:`StepStatus` (see
:class:`~ftkin.control.joint_admittance.JointAdmittance`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .sensor_faults import SensorFault


@dataclass(frozen=True)
class StepStatus:
    """What one :meth:`JointAdmittance.step` did.

    Attributes:
        dq: Commanded joint velocities ``(nq,)`` [rad/s].
        contact_wrench: Compensated wrench in the sensor frame [N, N·m] (NaN on a sensor-fault
        tick).
        twist: Admittance output at the control point, control-frame axes [m/s, rad/s].
        manipulability: ``w = sqrt(det(J Jᵀ))`` of the sensor Jacobian.
        damping: ``λ`` used in the least-squares inverse.
        limit_scale: Uniform factor applied for joint velocity/position limits (1 = none).
        safety_stop: True when the contact exceeded the limit (this tick or latched).
        event: ``""`` or a short description of why the arm was stopped.
        fault: The sensor fault holding the arm this tick (or being recovered
            from), :attr:`SensorFault.NONE` when there is none.
    """

    dq: np.ndarray
    contact_wrench: np.ndarray
    twist: np.ndarray
    manipulability: float
    damping: float
    limit_scale: float
    safety_stop: bool
    event: str
    fault: SensorFault = SensorFault.NONE

    @property
    def held(self) -> bool:
        """True when ``dq`` is zero because of a safety stop or a sensor fault."""
        return self.safety_stop or self.fault is not SensorFault.NONE
