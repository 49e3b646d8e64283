"""One control tick from joint angles and a raw reading to joint velocities.

:meth:`JointAdmittance.step` does, for a 1 kHz joint-velocity controller:

1. forward kinematics and the sensor-frame Jacobian (Pinocchio, one call);
2. compensation (:class:`~ftkin.control.compensation.Compensator`: bias and tool
   weight removed), or nothing when no compensator is given;
3. the wrench moved to the control frame and the admittance law
   (:class:`~ftkin.control.admittance.Admittance`), giving the control-point twist;
4. that twist moved to the sensor origin and mapped to joints by damped least
   squares ``dq = Jᵀ(J Jᵀ + λ² I)⁻¹ V`` (Cholesky), the damping growing as
   the manipulability ``w = sqrt(det(J Jᵀ))`` drops below a threshold:
   ``λ = λ_max (1 − w/w₀)`` (Nakamura–Hanafusa);
5. joint limits: each joint's velocity bound shrinks with its distance to the
   position limit (``gain · distance`` [rad/s]) and is capped by the velocity
   limit; ``dq`` is scaled uniformly (direction kept) to fit;
6. safety: a contact force [N] or torque [N·m] beyond the user limit commands
   ``dq = 0`` and latches until :meth:`JointAdmittance.reset`; so does an
   oscillating loop (:class:`~ftkin.control.oscillation.OscillationDetector`:
   repeated large reversals of the contact force), with
   ``fault = SensorFault.OSCILLATION`` and a message naming the gain to lower.

Before all that, a :class:`~ftkin.control.sensor_faults.FaultMonitor` checks the tick
(NaN/inf in ``q`` or the reading, a ``dt`` jump or a ``dt`` below
:data:`~ftkin.control.sensor_faults.MIN_DT`, a saturated channel, a stuck
sensor); a tick whose ``dq`` comes out non-finite (huge but finite inputs
overflowing on the way) is held the same way, its filter restarted; so is a ``q`` outside the
arm's joint limits by more than :data:`~ftkin.kinematics.joint_units.JOINT_LIMIT_MARGIN`
(``fault = SensorFault.JOINT_RANGE``, the event naming the joint, and degrees when ``q`` read as
degrees fits: what :meth:`~ftkin.control.compensation.Compensator.compensate` refuses). A faulty
tick commands ``dq = 0``, names the fault in
``last_status.fault`` and leaves the admittance filter untouched, so no bad
sample enters the state; faults are not latched: after
``SensorLimits.recovery_ticks`` good ticks the arm moves again, its derivative
filter restarted from the current force error (no kick from the jump in ΔF).
``step`` neither raises nor returns NaN for inputs of the right shape; wrong shapes or
non-numeric inputs raise :class:`~ftkin.exceptions.InvalidInput`. Each tick leaves a
:class:`StepStatus` in ``last_status``.
"""

import math
from dataclasses import dataclass
from operator import le
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..kinematics.arm import Arm, bundled_urdf_path
from ..kinematics.mounting import mounted_arm
from ..validation import FLOAT64, MAX_IMU_VALUE, as_positive
from .admittance import Admittance
from .compensation import JOINT_LIMIT_MARGIN, Compensator, outside_limits_text
from .control_frame import control_frame_for
from .damped_least_squares import damped_least_squares
from .dynamic_compensation import DynamicCompensator
from .oscillation import DEFAULT_OSCILLATION_LIMITS, OscillationDetector, OscillationLimits
from .sensor_faults import FaultMonitor, SensorFault, SensorLimits

if TYPE_CHECKING:  # the IMU's modules load with their first use
    from .imu_compensation import ImuCompensator


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


def _checked_imu(imu, compensator, dynamic) -> "ImuCompensator | None":
    """``imu`` once it is an :class:`ImuCompensator` that may go with the other compensators."""
    if imu is None:
        return None
    from .imu_compensation import ImuCompensator

    if not isinstance(imu, ImuCompensator):
        raise InvalidInput(f"imu must be an ftkin ImuCompensator or None, got {type(imu).__name__}")
    if dynamic is not None or (compensator is not None and compensator.tracker is not None):
        raise InvalidInput(
            "an IMU compensator goes with a static Compensator without a bias tracker (or none): "
            "the tracker re-zeroes the FK compensation only, and a DynamicCompensator is another "
            "model of the same inertial wrench"
        )
    return imu


def _real_or_nan(value) -> np.ndarray:
    """``value`` as a float64 array; complex numbers (a state estimator gone wrong) become NaN,
    a fault the tick holds on, instead of numpy's cast to the real part with a warning."""
    array = np.asarray(value)
    if array.dtype.kind == "c":
        return np.full(array.shape, math.nan)
    return np.asarray(array, dtype=np.float64)


class JointAdmittance:
    """Admittance control output as joint velocities.

    Args:
        arm: Kinematics (sensor frame, and tool frame for a tool control point).
        admittance: The Cartesian law; its ``frame`` picks the control frame.
        compensator: Removes bias and tool weight; None passes raw readings
            through (the "uncompensated" experiment). A
            :class:`~ftkin.control.dynamic_compensation.DynamicCompensator` also
            removes the tool's inertial wrench on ticks given joint velocities
            and accelerations (:meth:`step`); its static part serves the others.
            Its bias tracker, if any, is read here once: attach a tracker when
            creating the ``Compensator``, not afterwards. Likewise the fault
            monitor, the law and the control frame's methods are bound at
            construction (the tick's speed): build a new controller rather
            than replacing ``monitor``, ``admittance`` or ``frame`` later.
        control_point: ``"tool"`` (the arm's tool frame, rigidly attached to the
            sensor) or ``"sensor"``. Default: tool if the arm has one.
        force_limit: Contact force norm [N] that stops the arm.
        torque_limit: Contact torque norm [N·m] that stops the arm.
        manipulability_threshold: ``w₀`` below which damping starts (the
            bundled arm has w ≈ 0.06 tool-down, → 0 at the wrist singularity).
        max_damping: ``λ_max``.
        velocity_scale: Fraction of the arm's joint velocity limits to use.
        limit_gain: Joint velocity bound per radian to the position limit [1/s].
        sensor_limits: Fault thresholds (:class:`~ftkin.control.sensor_faults.SensorLimits`;
            default: the paper's sensor range ±250 N / ±6 N·m, stuck after 10
            identical ticks or 50 ms, dropped tick at 5x the nominal dt,
            5 good ticks to recover). Required for any arm but the bundled
            one: its sensor's measuring range is not the paper sensor's.
        oscillation: Thresholds of the oscillation detector
            (:class:`~ftkin.control.oscillation.OscillationLimits`); None disables it.
        imu: An :class:`~ftkin.control.imu_compensation.ImuCompensator` (a calibration from the
            sensor's IMU, or the fused one): ticks given the accelerometer's specific force
            (:meth:`step`'s ``specific_force``) are compensated with it, the tool's weight and
            its linear acceleration removed as the accelerometer sees them (the arm's motion
            included, which the static compensation misses). Without a ``compensator`` every
            tick must give it. Not with a bias tracker (it re-zeroes the FK compensation only)
            nor with a dynamic compensator (one inertial model per controller).
    """

    def __init__(
        self,
        arm: Arm,
        admittance: Admittance,
        compensator: Compensator | None = None,
        *,
        control_point: str | None = None,
        force_limit: float = 50.0,
        torque_limit: float = 5.0,
        manipulability_threshold: float = 0.005,
        max_damping: float = 0.05,
        velocity_scale: float = 1.0,
        limit_gain: float = 5.0,
        sensor_limits: SensorLimits | None = None,
        oscillation: OscillationLimits | None = DEFAULT_OSCILLATION_LIMITS,
        imu: "ImuCompensator | None" = None,
    ):
        if not isinstance(arm, Arm) or not isinstance(admittance, Admittance):
            raise InvalidInput("JointAdmittance needs an ftkin Arm and an ftkin Admittance")
        self.dynamic = compensator if isinstance(compensator, DynamicCompensator) else None
        compensator = compensator if self.dynamic is None else self.dynamic.static
        if compensator is not None and not isinstance(compensator, Compensator):
            raise InvalidInput(
                "compensator must be an ftkin Compensator or None, got "
                f"{type(compensator).__name__}"
            )
        self.force_limit, self.torque_limit, self.manipulability_threshold, self.max_damping = (
            as_positive(value, name)
            for name, value in (
                ("force_limit", force_limit),
                ("torque_limit", torque_limit),
                ("manipulability_threshold", manipulability_threshold),
                ("max_damping", max_damping),
            )
        )
        if compensator is not None and compensator.calibration.has_mount:
            # the real sensor frame, folded into the model: no work per tick
            arm = mounted_arm(arm, compensator.calibration.mount_rotation)
        self.imu = _checked_imu(imu, compensator, self.dynamic)
        self.arm, self.admittance, self.compensator = arm, admittance, compensator
        self.frame = control_frame_for(arm, admittance.frame, control_point)
        # The kinematics and joint limits the tick reads, as Python floats (limit scaling's
        # shortcut).
        self._speeds = (
            arm.velocity_limits * as_positive(velocity_scale, "velocity_scale")
        ).tolist()
        self.limit_gain = as_positive(limit_gain, "limit_gain")
        self._model, self._data, self._sensor_id = arm.model, arm.data, arm.sensor_frame_id
        self._rotation = arm.data.oMf[arm.sensor_frame_id].rotation  # a view: follows every FK call
        self._lower, self._upper = arm.lower_limits.tolist(), arm.upper_limits.tolist()
        # the range a measured q may be in (encoder overshoot allowed), as the Compensator's
        self._lowest = (arm.lower_limits - JOINT_LIMIT_MARGIN).tolist()
        self._highest = (arm.upper_limits + JOINT_LIMIT_MARGIN).tolist()
        self._nq = arm.nq
        if sensor_limits is None and (
            arm.urdf_path is None or arm.urdf_path != bundled_urdf_path().resolve()
        ):
            raise InvalidInput(
                "give sensor_limits=SensorLimits(force_range=..., torque_range=...) with your "
                "sensor's measuring range [N, N·m]: the default ±250 N / ±6 N·m is the bundled "
                "arm's (the paper's) sensor"
            )
        self.monitor, self.detector = (
            FaultMonitor(sensor_limits),
            OscillationDetector(oscillation) if oscillation is not None else None,
        )
        # Bound once: the tick calls these without attribute lookups (the compensator's kernel is
        # fixed at its creation).
        self._detect = self.detector.update if self.detector is not None else None
        self._check, self._update = self.monitor.check, admittance.update_floats
        self._wrench_floats, self._twist_floats = self.frame.wrench_floats, self.frame.twist_floats
        self._contact_floats = compensator.contact_floats if compensator is not None else None
        self._imu_floats = imu.contact_floats if imu is not None else None
        self._tracked = compensator is not None and compensator.tracker is not None
        self.reset()

    def reset(self) -> None:
        """Clear the admittance filter, the safety latch and the fault monitor's state."""
        self.admittance.reset()
        self.monitor.reset()
        if self.detector is not None:
            self.detector.reset()
        self.safety_latched, self.oscillation_event, self._holding = False, "", False
        self._status = self._status_parts = None  # the last StepStatus, or the parts to build it

    @property
    def last_status(self) -> StepStatus | None:
        """The :class:`StepStatus` of the last tick (None before the first tick after a reset).

        Built on first access: the tick itself only keeps its parts (a moving
        tick's status costs more than a microsecond to build).
        """
        if self._status_parts is not None:
            dq, contact, twist, manipulability, damping, scale = self._status_parts
            self._status = StepStatus(
                dq, np.array(contact), np.array(twist), manipulability, damping, scale, False, ""
            )
            self._status_parts = None
        return self._status

    @property
    def last_wrench_and_twist(self) -> tuple | None:
        """``(contact_wrench, twist)`` of the last tick without building its :class:`StepStatus`.

        The contact wrench in the sensor frame [N, N·m] and the twist at the control point in
        control-frame axes [m/s, rad/s], each a sequence of 6 floats (the values
        :attr:`last_status` turns into arrays); None before the first tick after a reset. What a
        live view publishes every tick (:class:`~ftkin.viz.live.PublishingController`): about a
        microsecond cheaper than :attr:`last_status`.
        """
        if self._status_parts is not None:
            return self._status_parts[1], self._status_parts[2]
        status = self._status
        return None if status is None else (status.contact_wrench, status.twist)

    def step(
        self,
        q,
        raw_wrench,
        dt: float,
        free: bool | None = None,
        joint_velocities=None,
        joint_accelerations=None,
        specific_force=None,
    ) -> np.ndarray:
        """Joint velocities ``(nq,)`` [rad/s] for this tick.

        Args:
            q: Joint positions ``(nq,)`` [rad]; outside the joint limits (degrees, a wrong
                joint order): a held tick (``SensorFault.JOINT_RANGE``), not an error.
            raw_wrench: Raw sensor reading ``(6,)`` [N, N·m], sensor frame.
            dt: Time since the previous tick [s].
            free: For the compensator's bias tracker, if it has one
                (:class:`~ftkin.control.bias_tracker.BiasTracker`): True when the
                tool is known free of contact, False in contact, None to let
                it detect. A faulty tick never reaches the tracker.
            joint_velocities: ``dq`` ``(nq,)`` [rad/s] measured (or estimated) at ``q``, with
            joint_accelerations: ``ddq`` ``(nq,)`` [rad/s²]: with a dynamic compensator, the
                contact is raw − bias − (gravity + inertial wrench) this tick.
            specific_force: The accelerometer's ``[ax, ay, az]`` [m/s², IMU frame] read with
                ``raw_wrench``: with an ``imu`` compensator, the contact is raw − bias − m ·
                (specific force in the sensor frame), with its torque. Not finite: a held tick
                (``SensorFault.NOT_FINITE``).

        Raises:
            InvalidInput: ``q``, ``raw_wrench`` or ``dt`` of the wrong shape or not numbers
                (NaN, inf, a bad ``dt`` are sensor faults: held and reported, not raised);
                joint velocities or accelerations of the wrong shape or not finite, one
                without the other, or given without a dynamic compensator; a specific force
                without an ``imu`` compensator, not of shape (3,), or missing where there is no
                other compensation.
        """
        # The tick runs on Python floats (numpy's per-call overhead dominates on 3- and 6-vectors);
        # numpy only for the Jacobian products. The status is built when asked (last_status).
        q, raw, positions, dt = self._tick_inputs(
            q, raw_wrench, dt, joint_velocities, joint_accelerations
        )
        fault, event = self._check(positions, raw, dt)
        if fault is SensorFault.NONE and not (
            all(map(le, self._lowest, positions)) and all(map(le, positions, self._highest))
        ):  # degrees for radians, a wrong joint order: what Compensator.compensate refuses
            fault = SensorFault.JOINT_RANGE
            event = f"{outside_limits_text(self.arm, q)}: holding"
        if fault is not SensorFault.NONE:
            if self._tracked:
                self.compensator.tracker.interrupt()
            return self._hold(fault, event)
        accel = None if specific_force is None else self._specific_force(specific_force)
        if accel is None and specific_force is not None:
            return self._hold(
                SensorFault.NOT_FINITE,
                f"specific force not finite or beyond {MAX_IMU_VALUE:g} m/s²: {specific_force}: "
                "holding",
            )
        # 1. kinematics: forward kinematics and the sensor Jacobian (base axes), one Pinocchio call
        jacobian = pin.computeFrameJacobian(
            self._model, self._data, q, self._sensor_id, pin.LOCAL_WORLD_ALIGNED
        )
        rotation = self._rotation.tolist()  # R_BS, updated by the call above
        # 2. compensation (six floats, sensor frame), bias tracker, oscillation check, safety stop
        if joint_velocities is not None:
            contact = self.dynamic.contact_rates_floats(
                q, raw, joint_velocities, joint_accelerations
            )
        elif accel is not None:
            contact = self._imu_floats(raw, accel)
        elif self._imu_floats is not None and self._contact_floats is None:
            raise InvalidInput(
                "this controller compensates with the IMU only: give specific_force [m/s²]"
            )
        else:
            contact = raw if self._contact_floats is None else self._contact_floats(rotation, raw)
        if self._tracked:
            self.compensator.observe_bias(contact, dt, q=q, free=free)
        fx, fy, fz, mx, my, mz = contact
        force = math.sqrt(fx * fx + fy * fy + fz * fz)
        torque = math.sqrt(mx * mx + my * my + mz * mz)
        if (self._detect is not None and self._detect(force, torque, dt)) or self.oscillation_event:
            return self._hold_oscillation(np.array(contact))
        if self.safety_latched or force > self.force_limit or torque > self.torque_limit:
            return self._stop(np.array(contact), force, torque)
        # 3. the admittance law in the control frame, its twist moved to the sensor origin
        wrench = self._wrench_floats(contact, rotation)
        if self._holding:
            self._restart_derivative(np.array(wrench))
        twist = self._update(wrench, dt)
        sensor_twist = self._twist_floats(twist, rotation)
        # 4. joint velocities: damped least squares, then the joint limits
        dq, manipulability, damping = damped_least_squares(
            jacobian, sensor_twist, self.manipulability_threshold, self.max_damping
        )
        scale = self._limit_scale(positions, dq.tolist())
        if scale < 1.0:
            dq *= scale
        elif scale != 1.0:  # NaN: dq overflowed on the way (huge but finite inputs)
            self.admittance.reset()  # the filter holds the overflowed values: restart it
            return self._hold(SensorFault.NOT_FINITE, f"dq not finite: {dq}: holding")
        self._status_parts = (dq, contact, twist, manipulability, damping, scale)
        return dq

    def _tick_inputs(self, q, raw_wrench, dt, joint_velocities, joint_accelerations) -> tuple:
        """``q`` (float64 array), the reading and ``q`` as lists of floats, ``dt`` as a float.

        Float64 arrays (the control loop's case) pass without a conversion.

        Raises:
            InvalidInput: not numbers, wrong shapes, or joint rates without a dynamic compensator
                (or one without the other).
        """
        try:  # float64 arrays (the control loop's case) pass without a conversion
            if not (
                type(q) is type(raw_wrench) is np.ndarray and q.dtype is raw_wrench.dtype is FLOAT64
            ):
                q, raw_wrench = _real_or_nan(q), _real_or_nan(raw_wrench)
            dt = float(dt)
        except (TypeError, ValueError) as error:
            raise InvalidInput(f"q, raw_wrench and dt must be numeric: {error}") from None
        if q.shape != (self._nq,) or raw_wrench.shape != (6,):
            raise InvalidInput(
                f"expected q of shape ({self._nq},) and raw_wrench of shape (6,), got {q.shape} "
                f"and {raw_wrench.shape}"
            )
        rates = joint_velocities is not None
        if rates != (joint_accelerations is not None) or rates and self.dynamic is None:
            raise InvalidInput(
                "joint_velocities and joint_accelerations go together, and with a "
                "DynamicCompensator only (a static compensator has no inertial term to use them)"
            )
        return q, raw_wrench.tolist(), q.tolist(), dt

    def _specific_force(self, specific_force) -> list | None:
        """The specific force as 3 floats [m/s²], or None when one is not finite.

        Raises:
            InvalidInput: no ``imu`` compensator, not numbers or not of shape (3,).
        """
        if self._imu_floats is None:
            raise InvalidInput(
                "specific_force needs an IMU compensator (JointAdmittance(..., imu=ImuCompensator"
                "(calibration)))"
            )
        try:
            values = _real_or_nan(specific_force)
        except (TypeError, ValueError) as error:
            raise InvalidInput(f"specific_force must be numeric: {error}") from None
        if values.shape != (3,):
            raise InvalidInput(f"expected specific_force of shape (3,), got {values.shape}")
        accel = values.tolist()
        return accel if all(math.isfinite(v) and abs(v) <= MAX_IMU_VALUE for v in accel) else None

    def _hold(self, fault: SensorFault, event: str, contact: np.ndarray | None = None):
        """``dq = 0``: a sensor fault, an oscillation or a safety stop (the caller latches those).

        A sensor fault leaves the filter and the latch alone; its status's contact wrench is NaN
        (not measured: a supervisor's ``|F'| < threshold`` test must not pass on a faulty tick).
        The status's twist is zero.
        """
        self._holding = True
        dq = np.zeros(self._nq)
        self._status_parts = None
        self._status = StepStatus(
            dq,
            np.full(6, math.nan) if contact is None else contact,
            np.zeros(6),
            math.nan,
            math.nan,
            0.0,
            self.safety_latched,
            event,
            fault,
        )
        return dq

    def _hold_oscillation(self, contact: np.ndarray) -> np.ndarray:
        """``dq = 0`` for an oscillating loop, latched until :meth:`reset`; the event names the gain
        to lower.
        """
        if not self.oscillation_event:
            law, state = self.admittance, self.admittance.state
            gain = (  # the term that contributes more to the commanded twist
                "k1 (K1, the dΔF/dt term: see ftkin.control.stability.max_stable_k1) or "
                "derivative_cutoff"
                if np.linalg.norm(law._k1s * state.filtered_derivative)
                >= np.linalg.norm(law._k2s * state.previous_error)
                else "k2 (K2, the ΔF term)"
            )
            limits = self.detector.limits
            self.oscillation_event = (
                f"oscillation: {self.detector.count:.0f} reversals of the contact force by more "
                "than "
                f"{limits.force_step:g} N within ~{limits.window:g} s: holding (reset() to "
                f"resume); lower {gain}"
            )
        return self._hold(SensorFault.OSCILLATION, self.oscillation_event, contact)

    def _restart_derivative(self, wrench: np.ndarray) -> None:
        """After a hold: take this tick's force error as the previous one and zero the filtered
        derivative.
        """
        self._holding = False
        state = self.admittance.state
        if state.started:
            state.previous_error = self.admittance.force_error(wrench)
            state.filtered_derivative = np.zeros(6)

    def _stop(self, contact: np.ndarray, force: float, torque: float) -> np.ndarray:
        previous = self.last_status
        if self.safety_latched and previous is not None and previous.safety_stop:
            event = previous.event
        else:
            event = (
                f"contact {force:.3g} N / {torque:.3g} N·m exceeded the limit "
                f"{self.force_limit:.3g} N / {self.torque_limit:.3g} N·m: stopped (reset() to "
                "resume)"
            )
        self.safety_latched = True
        return self._hold(SensorFault.NONE, event, contact)

    def _limit_scale(self, q: list, dq: list) -> float:
        """Largest ``s ≤ 1`` keeping every joint's ``s·dq`` within its bound (0 if one is at or past
        its limit); NaN when a ``dq`` is not finite.

        A joint moving towards its position limit may go at most ``limit_gain · distance``
        [rad/s], and never beyond its (scaled) velocity limit.
        """
        gain, scale = self.limit_gain, 1.0
        for position, velocity, lower, upper, speed in zip(
            q, dq, self._lower, self._upper, self._speeds
        ):
            if -speed <= velocity <= speed and (
                gain * (lower - position) <= velocity <= gain * (upper - position)
            ):
                continue  # within both of its bounds (so finite): the scale stays
            if not math.isfinite(velocity):
                return math.nan
            if velocity > 0.0:
                scale = min(scale, max(0.0, min(speed, gain * (upper - position))) / velocity)
            elif velocity < 0.0:
                scale = min(scale, min(0.0, max(-speed, gain * (lower - position))) / velocity)
        return scale
