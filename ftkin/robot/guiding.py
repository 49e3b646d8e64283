"""Hand-guiding: the arm yields to a hand on the tool, and stays where it is let go.

:func:`hand_guiding` builds the :class:`~ftkin.control.joint_admittance.JointAdmittance` for it:
zero desired wrench, a pure velocity admittance ``V = K2 · F'`` of the control point (the
arm's tool frame) in base axes, translation free and rotation optional. Without a position
gain (``K1 = 0``) nothing is remembered: when the hand lets go, ``F'`` is the compensation's
residual, inside the deadband, and the command is exactly zero. The payload must be right for
that: see docs/robot.md (the robot's controller counts every body once).

With ``imu=True`` (a calibration from the sensor's IMU, or the fused one) the contact is
compensated with the accelerometer each tick (:class:`~ftkin.control.ImuCompensator`): the
tool's weight and its linear acceleration as the IMU sees them, so the arm's own motion is not
felt as a push (:func:`~ftkin.robot.loop.run_admittance` reads the sensor's ``read_sample()``).
"""

from __future__ import annotations

from ..calibration.model import SensorModel
from ..control.admittance import Admittance
from ..control.compensation import Compensator
from ..control.joint_admittance import JointAdmittance
from ..control.load_events import LoadTracker
from ..control.oscillation import OscillationLimits
from ..control.sensor_faults import SensorLimits
from ..exceptions import InvalidInput

GUIDING_FORCE_GAIN = 0.0035
"""Default translation gain K2 [m/(s·N)]: 10 N moves the tool at 3.5 cm/s."""
GUIDING_TORQUE_GAIN = 0.1
"""Default rotation gain [rad/(s·N·m)] when rotation is free."""
GUIDING_OSCILLATION = OscillationLimits(force_step=4.0)
"""The oscillation stop of the preset: reversals of the contact force by more than 4 N."""


def hand_guiding(
    arm,
    calibration: SensorModel,
    *,
    rotation: bool = False,
    force_gain: float = GUIDING_FORCE_GAIN,
    torque_gain: float = GUIDING_TORQUE_GAIN,
    force_deadband: float = 1.0,
    torque_deadband: float = 0.1,
    max_linear_velocity: float = 0.1,
    max_angular_velocity: float = 0.5,
    force_limit: float = 60.0,
    torque_limit: float = 10.0,
    sensor_limits: SensorLimits | None = None,
    oscillation: OscillationLimits | None = GUIDING_OSCILLATION,
    imu: bool = False,
    load: LoadTracker | None = None,
) -> JointAdmittance:
    """The hand-guiding controller for ``arm`` with the compensation of ``calibration``.

    Args:
        arm: The arm (its tool frame is the control point, else the sensor frame).
        calibration: The sensor's calibration (bias and tool weight are removed).
        rotation: Also let the hand turn the tool (about the control point).
        force_gain: K2 of the translation [m/(s·N)].
        torque_gain: K2 of the rotation [rad/(s·N·m)] (with ``rotation``).
        force_deadband: Force ignored per axis [N]: the compensation's residual and noise.
        torque_deadband: Torque ignored per axis [N·m].
        max_linear_velocity: Speed limit of the control point [m/s].
        max_angular_velocity: Rotation speed limit [rad/s].
        force_limit: A contact force beyond this stops the arm (latched) [N].
        torque_limit: The same for the torque [N·m].
        sensor_limits: The sensor's measuring range and fault thresholds (default ±200 N,
            ±10 N·m: set your sensor's).
        oscillation: Thresholds of the oscillation stop (None: off). The default counts only
            reversals of more than 4 N: a tool accelerated by a velocity-streaming arm jitters by
            1-2 N tick to tick (franky-sim: ±1.5 N on a 1.2 kg tool).
        imu: Compensate with the sensor's accelerometer (``calibration`` must be an
            :class:`~ftkin.calibration.imu_result.ImuCalibrationResult`: from the IMU, or fused).
            A calibration from the IMU alone has no FK compensation to fall back on.
        load: A :class:`~ftkin.control.load_events.LoadTracker` for the load in the hand: the
            compensation removes what it identifies (a grasped object) and it follows the hand
            (docs/load.md); its ``period`` should be the loop's. Not with ``imu``.
    """
    if not isinstance(calibration, SensorModel):
        raise InvalidInput(
            f"calibration must be an ftkin calibration, got {type(calibration).__name__}"
        )
    if load is not None and not isinstance(load, LoadTracker):
        raise InvalidInput(f"load must be an ftkin LoadTracker or None, got {type(load).__name__}")
    if load is not None and imu:
        raise InvalidInput(
            "the load tracker runs on the FK compensation, not with the IMU's (imu=True): "
            "track the load without imu"
        )
    angular = 1.0 if rotation else 0.0
    law = Admittance(
        k1=0.0,
        k2=[force_gain] * 3 + [torque_gain * angular] * 3,
        selection=[1.0, 1.0, 1.0, angular, angular, angular],
        desired_wrench=0.0,
        frame="base",
        force_deadband=force_deadband,
        torque_deadband=torque_deadband,
        max_linear_velocity=max_linear_velocity,
        max_angular_velocity=max_angular_velocity,
    )
    limits = (
        sensor_limits
        if sensor_limits is not None
        else SensorLimits(force_range=200.0, torque_range=10.0)
    )
    imu_compensator, from_imu_alone = None, False
    if imu:
        from ..calibration.fused_result import FusedCalibrationResult
        from ..control.imu_compensation import ImuCompensator

        imu_compensator = ImuCompensator(calibration)  # refuses an FK calibration, by name
        # from the IMU alone there is no base tilt or mount to compensate FK ticks with
        from_imu_alone = not isinstance(calibration, FusedCalibrationResult)
    compensator = None if from_imu_alone else Compensator(calibration, arm, load=load)
    return JointAdmittance(
        arm,
        law,
        compensator,
        force_limit=force_limit,
        torque_limit=torque_limit,
        sensor_limits=limits,
        velocity_scale=0.5,
        oscillation=oscillation,
        imu=imu_compensator,
    )
