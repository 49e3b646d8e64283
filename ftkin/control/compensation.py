"""Gravity and bias compensation at control rate (METHOD.md §4).

contact wrench = raw − bias − tool gravity::

    Gs = R_BS(q)ᵀ a,   F' = F − F0 − Gs,   M' = M − M0 − P × Gs

All wrenches are ``[fx, fy, fz, mx, my, mz]`` [N, N·m] in the sensor frame.
Positive contact force is what the environment exerts on the tool.

A calibration that estimated the sensor's mount ``R_M`` is applied by folding
it into the arm's sensor frame (:func:`~ftkin.kinematics.mounting.mounted_arm`):
the joint-angle entry points see the real sensor at no extra cost, and
``R_BS`` given directly is taken as the real sensor's orientation. A stored
sensor sign or reversed axis (:mod:`ftkin.calibration.conventions`) multiplies
every raw reading by ``±1`` first; without one the hot path is unchanged.

The bias is an attribute the caller can move without slowing the control path
(re-zero, driver-zeroed readings, a bias tracker, the bias trajectory of a
drifting calibration).
"""

import logging
import math
from operator import le

import numpy as np

from ..calibration.model import FloatModel, SensorModel, contact_batch, gravity_in_sensor
from ..calibration.result import CalibrationResult
from ..calibration.samples import Samples
from ..calibration.samples_arm import warn_if_samples_arm_differs
from ..exceptions import FrameNotFound, InvalidInput, MissingDependency, UrdfError
from ..kinematics.arm import Arm
from ..kinematics.joint_units import JOINT_LIMIT_MARGIN  # the one margin (re-exported here)
from ..kinematics.mounting import mounted_arm
from ..validation import (
    FLOAT64,
    MAX_WRENCH,
    as_batch,
    as_float_array,
    as_rotation_batch,
    as_vector,
    as_wrench,
    as_wrenches,
    check_finite,
    is_rotation_rows,
    rotation_rows,
)
from .bias_checks import bias_at_times, rezero_warnings
from .bias_tracker import BiasTracker
from .load_events import LoadTracker

logger = logging.getLogger(__name__)


def refuse_outside_limits(arm: Arm, q: np.ndarray) -> None:
    """Raise :class:`InvalidInput` naming the first joint of ``q`` outside the arm's limits."""
    message = outside_limits_text(arm, q)
    if message is not None:
        raise InvalidInput(message)


def outside_limits_text(arm: Arm, q: np.ndarray) -> str | None:
    """What is wrong with ``q`` ``(nq,)`` [rad] when a joint is outside the arm's limits (by more
    than :data:`JOINT_LIMIT_MARGIN`), else None: the first such joint, and degrees named when
    ``q`` read as degrees is within them (a wrong joint order otherwise). One text for the
    refusal of :meth:`Compensator.compensate` and the held tick of
    :class:`~ftkin.control.joint_admittance.JointAdmittance`.
    """
    lows, highs = arm.lower_limits - JOINT_LIMIT_MARGIN, arm.upper_limits + JOINT_LIMIT_MARGIN
    outside = np.flatnonzero(~((q >= lows) & (q <= highs)))  # NaN is outside
    if not outside.size:
        return None
    i = int(outside[0])
    degrees = np.all(np.abs(np.deg2rad(q)) <= np.maximum(np.abs(lows), np.abs(highs)))
    hint = (
        "; these look like degrees: joint angles are in radians (np.radians(q))"
        if degrees
        else "; is q in the arm's joint order (" + ", ".join(arm.joint_names) + ")?"
    )
    return (
        f"q: {arm.joint_names[i]} = {q[i]:.6g} is outside its limits "
        f"[{arm.lower_limits[i]:.4g}, {arm.upper_limits[i]:.4g}] rad{hint}"
    )


class Compensator:
    """Remove the sensor bias and the tool's weight from raw readings.

    Args:
        calibration: Parameters (a :class:`~ftkin.calibration.CalibrationResult`
            or any :class:`~ftkin.calibration.model.SensorModel`).
        arm: Kinematics for the joint-angle entry points; not needed when the
            caller supplies ``R_BS`` itself; default: the arm the calibration records
            (``calibration.kinematics``), when it can be rebuilt. With a calibration that
            carries a mount, :attr:`arm` is a copy with the real sensor frame. When the
            calibration records the arm it was made with, ``arm`` must have its kinematics
            (the chain from the base to the sensor frame, within
            :data:`~ftkin.kinematics.record.KINEMATICS_TOLERANCE`), whatever its URDF file.
        tracker: Optional :class:`~ftkin.control.bias_tracker.BiasTracker`
            (off by default); it is restarted from the calibration's bias.
        allow_other_arm: Accept an arm that differs from the recorded one (deliberate reuse).
        load: The load in the hand (:mod:`ftkin.control.load_events`): a
            :class:`~ftkin.control.load_events.LoadTracker`, or True for one from the calibration
            (:meth:`~ftkin.control.load_events.LoadTracker.for_calibration`). Each
            :meth:`compensate` / :meth:`compensate_rotation` tick (and every user of
            :attr:`contact_floats`, e.g. :class:`~ftkin.control.JointAdmittance`) then feeds it
            and returns the contact after the tool and the load it holds (after a grasp the tool
            and load, after a release the tool alone); its clock advances by its ``period`` per
            tick and the gripper's state is its ``gripper`` attribute. The batch paths stay
            stateless (tool only): a recording goes through
            :func:`~ftkin.control.load_track.track_load`.

    Raises:
        InvalidInput: ``arm`` differs from the calibration's record (the message says how).
    """

    def __init__(
        self,
        calibration: SensorModel,
        arm: Arm | None = None,
        tracker: BiasTracker | None = None,
        *,
        allow_other_arm: bool = False,
        load: "LoadTracker | bool | None" = None,
    ):
        if not isinstance(calibration, SensorModel):
            raise InvalidInput(
                "calibration must be an ftkin SensorModel or CalibrationResult, got "
                f"{type(calibration).__name__}"
            )
        if arm is not None and not isinstance(arm, Arm):
            hint = f" (ftkin.load_robot({arm!r}))" if isinstance(arm, str) else ""
            raise InvalidInput(f"arm must be an ftkin.Arm or None, got {type(arm).__name__}{hint}")
        if tracker is not None and not isinstance(tracker, BiasTracker):
            raise InvalidInput(
                f"tracker must be an ftkin BiasTracker or None, got {type(tracker).__name__}"
            )
        calibration = CalibrationResult.from_model(calibration)
        record = calibration.kinematics
        self._no_arm = (  # both doors' spellings: ftkin rezero prints it as it is
            "pass arm= to use joint angles (ftkin: --robot NAME or --urdf PATH, with "
            "--sensor-frame, --sensor-parent, --sensor-offset as the sensor is mounted), or give "
            "R_BS"
            + (
                ""
                if record is not None
                else "; this calibration records no arm (it was made from orientations or the "
                "sensor's IMU, not joint angles)"
            )
        )
        if arm is None and record is not None:  # the calibration's own arm, if it can be rebuilt
            try:
                arm = record.build_arm()
            except (InvalidInput, FrameNotFound, UrdfError, MissingDependency) as error:
                self._no_arm = f"the calibration's arm cannot be rebuilt ({error}); {self._no_arm}"
        elif arm is not None and record is not None and not allow_other_arm:
            problems = record.mismatches(arm)
            if problems:
                raise InvalidInput(
                    f"this arm is not the one the calibration was made with ({record.describe()}): "
                    f"{'; '.join(problems)}. Pass allow_other_arm=True (ftkin "
                    "compensate: --allow-other-arm) if that is deliberate."
                )
        self.calibration = calibration
        self.arm = mounted_arm(arm, calibration.mount_rotation) if arm is not None else arm
        signs = calibration.reading_signs  # the tick's copy is _sign_floats (no conversion)
        self._reading_signs, self._sign_floats = (
            None if np.all(signs == 1.0) else signs,
            tuple(signs.tolist()),
        )
        self._gravity_in_base, self._bias, self._com = (
            np.array(calibration.gravity_in_base),
            np.array(calibration.bias),
            np.array(calibration.center_of_mass),
        )
        self._floats = FloatModel(self._gravity_in_base, self._com, self._bias)
        # Every one-sample path (and JointAdmittance.step) runs the float kernel of the model.
        self.contact_floats = (
            self._floats.contact if self._reading_signs is None else self._signed_contact_floats
        )
        self._q_shape = (self.arm.nq,) if self.arm is not None else None
        if self.arm is not None:  # the joint limits widened by a margin, as floats (one pass)
            self._lowest = (self.arm.lower_limits - JOINT_LIMIT_MARGIN).tolist()
            self._highest = (self.arm.upper_limits + JOINT_LIMIT_MARGIN).tolist()
        self.load = _load_part(load, calibration)
        self.tool_contact_floats = self.contact_floats  # the tool alone (a moving arm's inertia
        # goes between it and the load: DynamicCompensator)
        if self.load is not None:  # the tool's kernel, then the load's tick (same floats)
            tool_floats, load_tick = self.contact_floats, self.load.tick
            self.contact_floats = lambda rows, raw: load_tick(rows, tool_floats(rows, raw))
        self.tracker = tracker
        if tracker is not None:
            tracker.reset(self._bias, tracker.std)

    def _signed_contact_floats(self, rotation_rows, raw) -> tuple[float, ...]:
        """:meth:`FloatModel.contact` of the readings times the stored signs (unpacked: faster than
        a map over the six, and a reading of another length raises instead of being cut).
        """
        (s0, s1, s2, s3, s4, s5), (w0, w1, w2, w3, w4, w5) = self._sign_floats, raw
        return self._floats.contact(
            rotation_rows, (w0 * s0, w1 * s1, w2 * s2, w3 * s3, w4 * s4, w5 * s5)
        )

    def __repr__(self) -> str:
        path = None if self.arm is None else self.arm.urdf_path
        arm = (
            "none"
            if self.arm is None
            else f"{self.arm.sensor_frame} of {path.name if path else '?'}"
        )
        return (
            f"Compensator(tool {self.calibration.tool_weight:.4g} N, COM "
            f"{np.round(self.calibration.center_of_mass, 4).tolist()} m, "
            f"bias {np.round(self.calibration.bias, 4).tolist()} [N, N·m], arm {arm})"
        )

    def refresh_floats(self) -> None:
        """Copy the parameter arrays (``_bias``, ``_gravity_in_base``, ``_com``) into the float
        path.

        The one-sample path reads Python floats: call this after replacing a
        parameter array at run time (e.g. a re-zeroed bias).
        """
        self._floats.set(self._gravity_in_base, self._com, self._bias)

    def _require_arm(self) -> Arm:
        if self.arm is None:
            raise InvalidInput(f"this Compensator has no Arm: {self._no_arm}")
        return self.arm

    # ------------------------------------------------------------ one sample
    def compensate(self, q, raw_wrench) -> np.ndarray:
        """Contact wrench ``(6,)`` from joint angles ``q`` [rad] and one raw reading.

        This is the control-loop path: one forward-kinematics call and a few
        float operations, no allocation of large arrays.

        Raises:
            InvalidInput: ``q`` or the reading of the wrong shape or not finite, or ``q`` outside
                the arm's joint limits by more than :data:`JOINT_LIMIT_MARGIN` (degrees given
                for radians: the message says so).
        """
        arm = self.arm if self.arm is not None else self._require_arm()
        # float64 arrays, the control loop's case, pass without a conversion; anything else is
        # checked (booleans, text, complex and masked entries refused, not cast)
        if type(q) is not np.ndarray or q.dtype is not FLOAT64:
            q = as_float_array(q, "q [rad]")
        raw = (
            raw_wrench.tolist()
            if type(raw_wrench) is np.ndarray and raw_wrench.dtype is FLOAT64
            else as_float_array(raw_wrench, "raw_wrench [N, N·m]").tolist()
        )
        if (
            q.shape != self._q_shape
            or type(raw) is not list
            or len(raw) != 6
            or type(raw[0]) is not float
        ):
            raise InvalidInput(
                f"expected q of shape {self._q_shape} and raw_wrench of shape (6,), "
                f"got {q.shape} and {np.shape(raw_wrench)}"
            )
        if not math.hypot(*raw) <= MAX_WRENCH:  # NaN, inf or a huge entry: named below
            as_wrenches(raw, "raw_wrench")
        positions = q.tolist()
        # within the limits, which a NaN or an infinite angle is not (one pass does both checks)
        if not (all(map(le, self._lowest, positions)) and all(map(le, positions, self._highest))):
            check_finite(q, "q")
            refuse_outside_limits(arm, q)
        return np.array(self.contact_floats(arm.sensor_rotation_unchecked(q).tolist(), raw))

    def compensate_rotation(self, rotation_sensor_to_base, raw_wrench) -> np.ndarray:
        """Contact wrench ``(6,)`` from ``R_BS`` ``(3, 3)`` and one raw reading.

        Raises:
            InvalidInput: ``R_BS`` not a ``(3, 3)`` rotation (orthonormal within 1e-6, det +1),
                or ``raw_wrench`` not six finite numbers.
        """
        rotation, raw = rotation_sensor_to_base, raw_wrench
        try:
            if type(rotation) is type(raw) is np.ndarray and rotation.dtype is raw.dtype is FLOAT64:
                # The common case, two float64 arrays: no conversion, the closed-form check on
                # their floats. A wrong shape fails there (unpacking R's rows, or a nested reading
                # in the sum).
                rows, values = rotation.tolist(), raw.tolist()
                valid = is_rotation_rows(rows)
            else:  # the same check after a conversion (real numbers only: no booleans or text)
                rows = rotation_rows(rotation)  # None if not one rotation
                values, valid = as_float_array(raw, "raw_wrench").tolist(), rows is not None
            if valid and len(values) == 6 and math.hypot(*values) <= MAX_WRENCH:  # NaN fails
                return np.array(self.contact_floats(rows, values))
        except (InvalidInput, TypeError, ValueError):
            pass
        # Something is wrong, a batch of one, or six entries within ±MAX_WRENCH whose norm is not:
        # the array checks accept it or name what is wrong.
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        batch, _ = as_wrenches(raw_wrench, "raw_wrench")
        if len(rotations) != 1 or len(batch) != 1:
            raise InvalidInput(
                "compensate_rotation takes one (3, 3) rotation and one (6,) wrench; use "
                "compensate_batch"
            )
        return np.array(self.contact_floats(rotations[0].tolist(), batch[0].tolist()))

    def compensate_unchecked(self, rotation: np.ndarray, raw: np.ndarray) -> np.ndarray:
        """The fast path: :meth:`compensate_rotation` without validation, for a control loop
        whose inputs are checked already: ``R_BS`` ``(3, 3)`` and ``raw`` ``(6,)`` float64
        arrays (a wrong shape or a NaN is not caught). Returns a new ``(6,)`` array.

        The joint-angle loop's fast path is :class:`~ftkin.control.JointAdmittance`'s tick,
        which runs the same float kernel (:attr:`contact_floats`) on its own FK.
        """
        return np.array(self.contact_floats(rotation.tolist(), raw.tolist()))

    # ------------------------------------------------------------------ bias
    @property
    def bias(self) -> np.ndarray:
        """The bias ``[F0, M0]`` [N, N·m] subtracted now (a copy)."""
        return self._bias.copy()

    def _apply_bias(self, bias: np.ndarray) -> None:
        self._bias = np.array(bias, dtype=float)
        self.refresh_floats()

    def set_bias(self, bias) -> None:
        """Use ``bias`` ``(6,)`` [N, N·m] from now on (the tracker, if any, restarts from it)."""
        bias = as_wrench(bias, "bias [F0, M0]")
        self._apply_bias(bias)
        if self.tracker is not None:
            self.tracker.reset(bias)

    def _zero_at(self, rotation_sensor_to_base, raw: np.ndarray, what: str) -> np.ndarray:
        """Set and return the bias that makes ``raw`` ``(6,)`` a reading without contact at
        ``R_BS``.
        """
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        if len(rotations) != 1:
            raise InvalidInput(f"{what} takes one (3, 3) rotation")
        if self._reading_signs is not None:  # a stored sign or reversed axis applies here too
            raw = raw * self._reading_signs
        bias = raw - self.calibration.tool_gravity_wrench(rotations[0])
        self.set_bias(bias)
        return bias

    def _rotation_of(self, orientation, what: str) -> np.ndarray:
        """``R_BS`` ``(3, 3)`` of joint angles ``(nq,)`` [rad] (checked against the limits) or of
        a rotation ``(3, 3)`` (checked to be one)."""
        shape = np.shape(orientation)
        if shape == (3, 3):
            rotations, _ = as_rotation_batch(orientation)
            return rotations[0]
        arm = self._require_arm()
        if len(shape) == 1 and shape != (arm.nq,):
            raise InvalidInput(
                f"{what} takes the arm's {arm.nq} joint angles q [rad] "
                f"({', '.join(arm.joint_names)}) or R_BS (3, 3), got {shape[0]} numbers"
            )
        q = as_vector(orientation, arm.nq, f"{what}: joint angles q")
        refuse_outside_limits(arm, q)
        return arm.sensor_rotation_unchecked(q).copy()

    def rezero(self, orientation, raw_wrench) -> np.ndarray:
        """Re-zero: the contact wrench of ``raw_wrench`` at this pose becomes zero.

        Args:
            orientation: The pose, as compensation takes it: joint angles ``(nq,)`` [rad], or
                ``R_BS`` ``(3, 3)``.
            raw_wrench: The reading there ``(6,)`` [N, N·m] (average a few hundred).

        The new bias is the reading minus the predicted tool gravity at the pose (not the whole
        reading, which would subtract the tool's weight at this pose and make it appear at every
        other). The tool must be free of contact and the arm still. Returns the new bias ``(6,)``
        [N, N·m].

        Warns (logging) when the force bias moved by more than the tool's weight, and when the
        calibration has a drift trajectory the re-zero leaves in place
        (:func:`~ftkin.control.bias_checks.rezero_warnings`, the texts of ``ftkin rezero``).
        """
        rotation = self._rotation_of(orientation, "rezero")
        previous = self._bias
        bias = self._zero_at(rotation, as_wrench(raw_wrench, "raw_wrench"), "rezero")
        for text in rezero_warnings(self.calibration, previous, bias):
            logger.warning("%s", text)
        return bias

    def driver_zeroed_at(self, orientation) -> np.ndarray:
        """The sensor driver was zeroed (tool on, no contact) at this pose: joint angles
        ``(nq,)`` [rad] or ``R_BS`` ``(3, 3)``.

        Its readings are then ``raw − raw(pose)``: the true bias and the tool gravity at the
        pose are gone. The bias to subtract from them is minus the tool gravity wrench there
        (``−[Gs, P × Gs]``), after which the contact wrenches are right at every pose. Returns
        that bias ``(6,)``.
        """
        rotation = self._rotation_of(orientation, "driver_zeroed_at")
        return self._zero_at(rotation, np.zeros(6), "driver_zeroed_at")

    def bias_at(self, times) -> np.ndarray:
        """Bias ``(N, 6)`` [N, N·m] for readings at ``times`` ``(N,)`` [s].

        Inside the recording of a drifting calibration: its trajectory
        (:meth:`~ftkin.calibration.drift.BiasDrift.bias_at`; a reading then had the bias the
        recording saw, whatever a later re-zero found). Outside it (after its end, or before its
        start, e.g. a log on another clock), or without a drift model: the current bias
        (calibration's last, or as re-zeroed or tracked since).

        With a drift trajectory, warns (logging) of times that look like another clock: rows
        inside the recording while the current bias differs from the trajectory's end (a re-zero
        since), or times long before the recording
        (:func:`~ftkin.control.bias_checks.check_log_times`, the texts of ``ftkin compensate``).

        Raises:
            InvalidInput: a time that is not a finite number of seconds.
        """
        times = as_float_array(times, "times [s]").reshape(-1)
        if not np.all(np.isfinite(times)):
            check_finite(times, "times [s]")
        return bias_at_times(self.calibration.drift, self._bias, times)

    def observe_bias(
        self, contact_wrench, dt: float, *, q=None, free: bool | None = None, fault: bool = False
    ) -> bool:
        """Give the tracker this tick's contact wrench; True when it moved the bias (used from the
        next call).
        """
        moved = self.tracker is not None and self.tracker.observe(
            contact_wrench, dt, q=q, free=free, fault=fault
        )
        if moved:
            self._apply_bias(self.tracker.bias)
        return moved

    # ----------------------------------------------------------------- batch
    def compensate_batch(self, orientations, raw_wrenches, times=None) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` of ``N`` raw readings ``(N, 6)`` (vectorized).

        Args:
            orientations: ``R_BS`` ``(N, 3, 3)`` (the real sensor's; one ``(3, 3)`` is a batch
                of one), or joint angles ``(N, nq)`` [rad] (through the arm, its mount applied;
                checked against the joint limits).
            raw_wrenches: ``(N, 6)`` [N, N·m], sensor frame.
            times: ``(N,)`` reading times [s]; the bias is then :meth:`bias_at` those times.
        """
        raw, _ = as_wrenches(raw_wrenches, "raw_wrenches")
        shape = np.shape(orientations)
        one_rotation = shape == (3, 3) and (self.arm is None or self.arm.nq != 3)
        if len(shape) == 3 or one_rotation:  # (3, 3) of a 3-joint arm: three joint-angle rows
            rotations, _ = as_rotation_batch(orientations)
            gravity = None
        else:
            arm = self._require_arm()
            configurations, _ = as_batch(orientations, arm.nq, "joint angles q")
            outside = (configurations < self._lowest) | (configurations > self._highest)
            if outside.any():
                refuse_outside_limits(arm, configurations[np.flatnonzero(outside.any(axis=1))[0]])
            rotations = None
            gravity = arm.vectors_in_sensor_unchecked(configurations, self._gravity_in_base)
        count = len(rotations) if rotations is not None else len(gravity)
        if count != len(raw):
            raise InvalidInput(f"{count} orientations but {len(raw)} wrenches; expected one each")
        bias = None if times is None else self.bias_at(times)
        if bias is not None and len(bias) != len(raw):
            raise InvalidInput(f"{len(bias)} times but {len(raw)} wrenches; expected one each")
        if gravity is None:
            gravity = gravity_in_sensor(rotations, self._gravity_in_base)
        return self._contact_batch(raw, gravity, bias)

    def _batch_unchecked(
        self, rotations: np.ndarray, raw: np.ndarray, bias: np.ndarray | None = None
    ) -> np.ndarray:
        """:meth:`compensate_batch` of validated ``R_BS`` ``(N, 3, 3)``; ``bias``: ``(N, 6)``
        per-reading bias [N, N·m] (default: the current one)."""
        return self._contact_batch(raw, gravity_in_sensor(rotations, self._gravity_in_base), bias)

    def _contact_batch(
        self, raw: np.ndarray, gravity_in_sensor: np.ndarray, bias: np.ndarray | None = None
    ) -> np.ndarray:
        """:func:`~ftkin.calibration.model.contact_batch` with the signs and the current bias."""
        raw = raw if self._reading_signs is None else raw * self._reading_signs
        return contact_batch(
            raw, gravity_in_sensor, self._com, self._bias if bias is None else bias
        )

    def compensate_samples(self, samples: Samples) -> np.ndarray:
        """Contact wrenches ``(N, 6)`` of a :class:`~ftkin.calibration.samples.Samples` (at their
        times, if any).

        Samples read from joint angles hold the URDF's ``R_BS``: the calibration's mount is applied
        to them (:meth:`sensor_rotations`).
        """
        warn_if_samples_arm_differs(samples, self.calibration)  # read with another arm?
        return self._batch_unchecked(
            self.sensor_rotations(samples),
            samples.wrenches,
            None if samples.times is None else self.bias_at(samples.times),
        )

    def sensor_rotations(self, samples: Samples) -> np.ndarray:
        """The real sensor's ``R_BS`` ``(N, 3, 3)`` of samples: read from joint angles, the URDF's
        with the calibration's mount applied; else as given."""
        rotations = samples.rotations
        if samples.joint_positions is not None and self.calibration.has_mount:
            rotations = rotations @ self.calibration.mount_rotation.T
        return rotations

    @staticmethod
    def payload_weight(contact_wrench) -> np.ndarray | float:
        """Weight of a held load ``|F'|`` [N] from contact wrench ``(6,)`` → float or ``(N, 6)`` →
        ``(N,)`` (arm still).
        """
        wrench, single = as_batch(contact_wrench, 6, "contact_wrench")
        norms = np.linalg.norm(wrench[:, :3], axis=1)
        return float(norms[0]) if single else norms


def _load_part(load, calibration) -> LoadTracker | None:
    """The :class:`LoadTracker` of :class:`Compensator`'s ``load`` argument."""
    if load is None or load is False:
        return None
    if load is True:
        return LoadTracker.for_calibration(calibration)
    if not isinstance(load, LoadTracker):
        raise InvalidInput(
            f"load must be an ftkin LoadTracker, True or None, got {type(load).__name__}"
        )
    return load
