"""Compensation during motion: remove bias, tool gravity and the tool's inertial wrench.

A moving tool loads the sensor with its weight and with the d'Alembert
(inertial) wrench ``−(I a + v ×* I v)`` (:mod:`ftkin.calibration.regressor`)::

    raw = bias + gravity wrench − Y(v, a) θ + contact
    contact = raw − bias − (gravity wrench + inertial wrench),   inertial wrench = −Y(v, a) θ

with ``v, a`` the sensor frame's spatial velocity and acceleration in its own
axes (from ``q, dq, ddq`` by Pinocchio) and θ the tool's ten inertial
parameters in the sensor frame. All wrenches are ``[fx, fy, fz, mx, my, mz]``
[N, N·m] in the sensor frame.

This is a separate entry point from :meth:`Compensator.compensate` (the static
hot path). A calibration without an inertia (static) still removes the
translational inertial force of its mass and centre of mass (a point-mass
tool); only the rotational inertia about the COM is then missing.
"""

import math
from collections import deque

import numpy as np
import pinocchio as pin

from ..calibration.derivatives import CausalDifferentiator
from ..calibration.log_cholesky import inertia_entries
from ..calibration.model import SensorModel
from ..calibration.regressor import MotionSamples
from ..exceptions import InvalidInput
from ..kinematics.arm import Arm
from ..validation import FLOAT64, MAX_WRENCH, as_vector, as_wrench, as_wrenches, check_finite
from .compensation import Compensator


def point_mass_parameters(mass_and_moment) -> np.ndarray:
    """θ ``(10,)`` of a point mass from ``[m, m c]`` ``(4,)`` [kg, kg·m]: its inertia about the
    sensor origin is ``m (|c|² I − c cᵀ)`` (zero for ``m ≤ 0``: then only ``[m, m c]``)."""
    theta = np.zeros(10)
    theta[:4] = mass_and_moment
    mass, moment = float(theta[0]), theta[1:4]
    if mass > 0:
        theta[4:] = inertia_entries((moment @ moment * np.eye(3) - np.outer(moment, moment)) / mass)
    return theta


class DynamicCompensator:
    """Contact wrench of a moving arm from ``(q, dq, ddq)`` and a raw reading.

    Args:
        calibration: A :class:`~ftkin.calibration.dynamic.DynamicCalibrationResult`
            (uses its inertia) or any :class:`SensorModel` (point-mass tool).
        arm: Kinematics (Pinocchio) of the arm carrying the sensor.
        inertial_parameters: Override θ (10,) in the sensor frame (see
            :mod:`ftkin.calibration.log_cholesky`).
        allow_other_arm: Accept an arm other than the one the calibration
            records (as :class:`~ftkin.control.compensation.Compensator`).
        load: The load in the hand, as :class:`~ftkin.control.compensation.Compensator` takes
            it (a :class:`~ftkin.control.load_events.LoadTracker` or True): it is given the
            contact after the tool's weight and inertia, and its load is removed too.
    """

    def __init__(
        self,
        calibration: SensorModel,
        arm: Arm,
        inertial_parameters=None,
        *,
        allow_other_arm: bool = False,
        load=None,
    ):
        if not isinstance(arm, Arm):
            raise InvalidInput(f"arm must be an ftkin Arm, got {type(arm).__name__}")
        self.static = Compensator(calibration, arm, allow_other_arm=allow_other_arm, load=load)
        # the arm with the calibration's mount folded into the sensor frame, if any
        self.calibration, self.arm = self.static.calibration, self.static.arm
        self.inertial_parameters = (
            self.calibration.dynamic_parameters
            if inertial_parameters is None
            else as_vector(inertial_parameters, 10, "inertial_parameters")
        )
        self._model, self._frame = self.arm.model, self.arm.sensor_frame_id
        self._data, self._q_shape = self._model.createData(), (arm.nq,)
        # the static kernel: current bias (re-zeroed or tracked), reading signs; the static
        # compensator's load part, if any, ticks on the contact after the tool's inertia too
        self._contact_floats = self.static.tool_contact_floats
        self._load_tick = None if self.static.load is None else self.static.load.tick
        self._load_version, self._theta = None, self.inertial_parameters
        if self._load_tick is not None:
            self._load_noise = tuple(self.static.load.noise.channel_std.tolist())
        self._stream: CausalDifferentiator | None = None
        self._raw_buffer: deque = deque()

    # ------------------------------------------------------------ one sample
    def compensate_moving(self, q, dq, ddq, raw_wrench) -> np.ndarray:
        """Contact wrench ``(6,)`` [N, N·m] from ``q`` [rad], ``dq`` [rad/s], ``ddq`` [rad/s²]
        ``(nq,)`` and one raw reading.

        The control-loop path: one forward-kinematics call with velocities and
        accelerations, three frame queries, Pinocchio's body regressor times θ and the static kernel
        on floats.
        """
        return np.array(self.contact_moving_floats(q, dq, ddq, raw_wrench))

    def contact_moving_floats(self, q, dq, ddq, raw_wrench) -> tuple[float, ...]:
        """:meth:`compensate_moving` returning six Python floats (``JointAdmittance.step``'s path);
        validated the same way.
        """
        raw = raw_wrench
        try:  # float64 arrays (the control loop's) pass as they are
            if not (
                type(q) is type(dq) is type(ddq) is type(raw) is np.ndarray
                and q.dtype is dq.dtype is ddq.dtype is raw.dtype is FLOAT64
            ):
                q, dq, ddq, raw = (np.asarray(v, dtype=np.float64) for v in (q, dq, ddq, raw))
        except (TypeError, ValueError) as error:
            raise InvalidInput(f"q, dq, ddq and raw_wrench must be numeric: {error}") from None
        shape = self._q_shape
        if q.shape != shape or dq.shape != shape or ddq.shape != shape or raw.shape != (6,):
            raise InvalidInput(
                f"expected q, dq, ddq of shape {shape} and raw_wrench of shape (6,), got "
                f"{q.shape}, {dq.shape}, {ddq.shape}, {raw.shape}"
            )
        values = raw.tolist()
        # One test for the common case: the sum is finite only if every input is, and the reading's
        # norm bounds its entries; else the checks name the entry (an overflowing sum passes them).
        if not (
            math.isfinite(sum(q.tolist()) + sum(dq.tolist()) + sum(ddq.tolist()))
            and math.hypot(*values) <= MAX_WRENCH
        ):
            for value, name in ((q, "q"), (dq, "dq"), (ddq, "ddq")):
                check_finite(value, name)
            as_wrenches(raw, "raw_wrench")
        return self._moving_floats(q, dq, ddq, values)

    def contact_rates_floats(self, q: np.ndarray, raw: list, dq, ddq) -> tuple[float, ...]:
        """:meth:`contact_moving_floats` for a ``q`` (float64 ``(nq,)``) and ``raw`` (six finite
        floats) the caller
        validated already (``JointAdmittance.step``): only ``dq`` [rad/s] and ``ddq`` [rad/s²] are
        checked.
        """
        try:
            dq, ddq = np.asarray(dq, dtype=np.float64), np.asarray(ddq, dtype=np.float64)
        except (TypeError, ValueError) as error:
            raise InvalidInput(f"dq and ddq must be numeric: {error}") from None
        if dq.shape != self._q_shape or ddq.shape != self._q_shape:
            raise InvalidInput(
                f"expected dq, ddq of shape {self._q_shape}, got {dq.shape}, {ddq.shape}"
            )
        if not math.isfinite(sum(dq.tolist()) + sum(ddq.tolist())) and not (
            np.isfinite(dq).all() and np.isfinite(ddq).all()
        ):
            raise InvalidInput(f"dq and ddq must be finite, got dq={dq} ddq={ddq}")
        return self._moving_floats(q, dq, ddq, raw)

    def compensate_moving_unchecked(
        self, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, raw: np.ndarray
    ) -> np.ndarray:
        """:meth:`compensate_moving` without validation (float arrays of the right shapes); returns
        a new array.
        """
        return np.array(self._moving_floats(q, dq, ddq, raw.tolist()))

    def _moving_floats(
        self, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray, raw: list
    ) -> tuple[float, ...]:
        model, data, frame = self._model, self._data, self._frame
        pin.forwardKinematics(model, data, q, dq, ddq)
        rotation = pin.updateFramePlacement(model, data, frame).rotation
        # Y(v, a) θ with Pinocchio's body regressor (as the batch path), v and a LOCAL (Pinocchio's
        # default frame:
        # naming it costs a conversion per call); a test checks it against the Newton–Euler sum
        # written out.
        regressor = pin.bodyRegressor(
            pin.getFrameVelocity(model, data, frame), pin.getFrameAcceleration(model, data, frame)
        )
        theta = self.inertial_parameters
        if self._load_tick is not None:  # the held load's inertial wrench as a point mass too
            load = self.static.load
            if load.version != self._load_version:
                self._load_version = load.version
                self._theta = theta + point_mass_parameters(load.load_parameters + load.tool_offset)
            theta = self._theta
        i0, i1, i2, i3, i4, i5 = regressor.dot(theta).tolist()
        if self._load_tick is not None:  # moving: the inertial wrench beyond a reading's noise
            s0, s1, s2, s3, s4, s5 = self._load_noise
            self.static.load.moving = (
                abs(i0) > s0
                or abs(i1) > s1
                or abs(i2) > s2
                or abs(i3) > s3
                or abs(i4) > s4
                or abs(i5) > s5
            )
        rows = rotation.tolist()
        c0, c1, c2, c3, c4, c5 = self._contact_floats(rows, raw)
        if self._load_tick is not None:  # the load, identified from the contact after the tool
            return self._load_tick(rows, (c0 + i0, c1 + i1, c2 + i2, c3 + i3, c4 + i4, c5 + i5))
        return c0 + i0, c1 + i1, c2 + i2, c3 + i3, c4 + i4, c5 + i5

    # ---------------------------------------------------------------- stream
    def start_stream(
        self, sample_period: float, window: int | None = None, polyorder: int = 4
    ) -> float:
        """Estimate ``dq, ddq`` online from the stream of ``q`` (:class:`CausalDifferentiator`);
        returns its delay [s].
        """
        self._stream = CausalDifferentiator(self.arm.nq, sample_period, window, polyorder)
        self._raw_buffer = deque(maxlen=self._stream.window)
        return self._stream.delay

    def compensate_stream(self, q, raw_wrench) -> np.ndarray | None:
        """Push one ``(q, raw)``; the contact wrench of the sample ``delay`` seconds ago, or None
        while filling.

        The raw readings are delayed with the joint estimates, so each output
        is consistent (same instant); call :meth:`start_stream` first.
        """
        if self._stream is None:
            raise InvalidInput("call start_stream(sample_period) before compensate_stream")
        raw = as_wrench(raw_wrench, "raw_wrench")
        estimate = self._stream.update(
            q
        )  # validates q first: a refused sample enters neither buffer
        self._raw_buffer.append(raw)
        if estimate is None:
            return None
        return self.compensate_moving_unchecked(
            estimate[0], estimate[1], estimate[2], self._raw_buffer[(self._stream.window - 1) // 2]
        )

    # ----------------------------------------------------------------- batch
    def compensate_motion(self, motion: MotionSamples) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` of :class:`~ftkin.calibration.regressor.MotionSamples`
        (vectorized).
        """
        return (
            self.static._batch_unchecked(motion.rotations, motion.wrenches)
            + motion.regressor() @ self.inertial_parameters
        )

    def compensate_trajectory(
        self, joint_positions, joint_velocities, joint_accelerations, raw_wrenches
    ) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` from ``(N, nq)`` ``q, dq, ddq`` and ``(N, 6)`` raw
        readings.
        """
        return self.compensate_motion(
            MotionSamples.from_joint_trajectory(
                self.arm, joint_positions, joint_velocities, joint_accelerations, raw_wrenches
            )
        )
