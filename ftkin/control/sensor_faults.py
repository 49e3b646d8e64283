"""Sensor faults seen from the control loop: detect, hold, recover.

A control loop must not crash on bad data, and must not move on it either.
:class:`FaultMonitor` looks at each tick's joint positions ``q`` [rad], raw
reading [N, N·m] and time step ``dt`` [s] and names the first fault it finds:

* :attr:`SensorFault.NOT_FINITE`: a NaN or inf in ``q`` or in the reading;
* :attr:`SensorFault.DT_JUMP`: ``dt`` not finite, below :data:`MIN_DT` (a
  subnormal or zero step would blow the derivative up), or more than
  ``dt_ratio`` times the nominal step (dropped ticks; the nominal step is
  ``nominal_dt`` or a running average of the accepted steps);
* :attr:`SensorFault.SATURATED`: ``|raw_i| >= range_i`` on any channel
  (the paper's sensor reads ±250 N / ±6 N·m);
* :attr:`SensorFault.STUCK`: the reading bit-identical on all six channels
  for more than ``stuck_ticks`` ticks or ``stuck_time`` [s] (a live sensor
  always has noise; a frozen driver or a dead cable repeats the last value).

Faults are not latched: after ``recovery_ticks`` consecutive good ticks the
monitor reports :attr:`SensorFault.NONE` again. The caller (``JointAdmittance``)
holds the arm (``dq = 0``) while :meth:`FaultMonitor.check` reports a fault and
keeps the bad sample out of its filter. Wrong shapes are programming errors,
not sensor faults, and stay :class:`~ftkin.exceptions.InvalidInput`.
"""

import math
from dataclasses import dataclass
from enum import StrEnum
from numbers import Real
from operator import lt

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array


class SensorFault(StrEnum):
    """Why a tick was held (``NONE``: it was not)."""

    NONE = "none"
    NOT_FINITE = "not_finite"
    DT_JUMP = "dt_jump"
    SATURATED = "saturated"
    STUCK = "stuck"
    OSCILLATION = "oscillation"
    """Not a sensor fault: the loop itself oscillates (:mod:`ftkin.control.oscillation`); latched
    until reset.
    """
    JOINT_RANGE = "joint_range"
    """Not a sensor fault: ``q`` is outside the arm's joint limits by more than
    :data:`~ftkin.kinematics.joint_units.JOINT_LIMIT_MARGIN` (degrees given for radians, a wrong
    joint order), which :meth:`~ftkin.control.compensation.Compensator.compensate` refuses; held
    while it lasts.
    """


_OK = (SensorFault.NONE, "")
"""``check``'s answer for a good tick (one shared tuple: the common case allocates nothing)."""


@dataclass(frozen=True)
class SensorLimits:
    """Fault thresholds; None disables a check (NaN/inf and ``dt <= 0`` are always faults).

    Attributes:
        force_range: Saturation per force channel [N] (scalar or 3-vector): ``|F_i| >= range`` is a
        fault.
        torque_range: Saturation per torque channel [N·m] (scalar or 3-vector).
        stuck_ticks: A reading repeated bit for bit on more than this many
            consecutive ticks is a stuck sensor. Must exceed the number of
            control ticks per sensor update if the sensor is slower than the loop.
        stuck_time: The same, as a duration [s].
        dt_ratio: ``dt > dt_ratio · nominal`` is a dropped tick.
        nominal_dt: Fixed nominal step [s]; None: a running average of the
            accepted steps (starting from the first one, so a bogus first
            ``dt`` after a reset is believed for a while: pass this if that matters).
        recovery_ticks: Consecutive good ticks after a fault before the arm may move (the last one
        moves it).
    """

    force_range: object = 250.0
    torque_range: object = 6.0
    stuck_ticks: int | None = 10
    stuck_time: float | None = 0.05
    dt_ratio: float | None = 5.0
    nominal_dt: float | None = None
    recovery_ticks: int = 5

    def __post_init__(self):
        for name, expected in _EXPECTED.items():
            value = getattr(self, name)
            valid = (
                isinstance(value, Real)
                and not isinstance(value, bool)
                and math.isfinite(value)
                and (value >= 1 and value == int(value) if "integer" in expected else value > 0)
            )
            if not (valid or value is None and expected.endswith("or None")):
                raise InvalidInput(f"{name} must be {expected}, got {value!r}")
        if self.dt_ratio is not None and self.dt_ratio <= 1.0:
            raise InvalidInput(
                f"dt_ratio must be > 1 (a multiple of the nominal step), got {self.dt_ratio!r}"
            )
        self.ranges()

    def ranges(self) -> np.ndarray:
        """Saturation limits ``(6,)`` [N, N·m] per channel (``inf`` where disabled).

        Each part is None (``inf``), a number or a 3-vector, all > 0.
        """
        parts = []
        for name, unit in (("force_range", "N"), ("torque_range", "N·m")):
            value = getattr(self, name)
            try:
                array = np.broadcast_to(np.asarray(np.inf if value is None else value, float), 3)
            except (TypeError, ValueError):
                array = np.full(3, np.nan)
            if np.isnan(array).any() or np.any(array <= 0):
                raise InvalidInput(
                    f"{name} must be None, or a number or 3-vector > 0 [{unit}], got {value!r}"
                )
            parts.append(array)
        return np.concatenate(parts)


# what each scalar field of SensorLimits must be (the refusal says it)
_EXPECTED = {
    "stuck_time": "a finite number > 0 or None",
    "dt_ratio": "a finite number > 0 or None",
    "nominal_dt": "a finite number > 0 or None",
    "stuck_ticks": "an integer >= 1 or None",
    "recovery_ticks": "an integer >= 1",
}


MIN_DT = 1e-6
"""Shortest accepted control step [s] (1 MHz): below it ``ΔF / dt`` is no derivative but an
overflow."""


class FaultMonitor:
    """Per-tick fault detection with the state it needs (previous reading, counters).

    Attributes:
        limits: The thresholds.
        counts: Ticks held so far per fault (not cleared by :meth:`reset`).
    """

    def __init__(self, limits: SensorLimits | None = None):
        self.limits = SensorLimits() if limits is None else limits
        if not isinstance(self.limits, SensorLimits):
            raise InvalidInput(
                f"limits must be an ftkin SensorLimits or None, got {type(limits).__name__}"
            )
        self._ranges = self.limits.ranges().tolist()
        self._check_range = any(math.isfinite(r) for r in self._ranges)
        self._stuck_ticks, self._stuck_time, self._ratio = (
            math.inf if value is None else float(value)
            for value in (self.limits.stuck_ticks, self.limits.stuck_time, self.limits.dt_ratio)
        )
        self._running_dt = self.limits.nominal_dt is None
        self.counts = {fault: 0 for fault in SensorFault if fault is not SensorFault.NONE}
        self.reset()

    def reset(self) -> None:
        """Forget the previous reading, the dt estimate and any fault in progress."""
        self._previous: list | None = None
        self._repeats, self._stale_time = 0, 0.0
        self._reference_dt = self.limits.nominal_dt
        self.fault, self.good_ticks = SensorFault.NONE, 0

    def check(self, q: np.ndarray | list, raw: list, dt: float) -> tuple[SensorFault, str]:
        """The fault holding this tick and a description (``(NONE, "")`` when the arm may move).

        Args:
            q: Joint positions ``(nq,)`` float array [rad] (shape already checked), or its
                ``tolist()`` (the control-loop path).
            raw: The six raw channels [N, N·m], best as a list of Python floats
                (the control-loop path); an array is converted.
            dt: Time step [s].
        """
        if type(raw) is not list:
            raw = as_float_array(raw, "raw reading").tolist()
            if len(raw) != 6 or not all(isinstance(value, float) for value in raw):
                raise InvalidInput(f"raw reading must have shape (6,), got {np.shape(raw)}")
        fault, event = self._detect(q, raw, dt)
        if fault is not SensorFault.NONE:
            self.fault, self.good_ticks = fault, 0
            self.counts[fault] += 1
            return fault, event
        if self.fault is SensorFault.NONE:
            return _OK
        self.good_ticks += 1
        if self.good_ticks >= self.limits.recovery_ticks:
            self.fault = SensorFault.NONE
            return _OK
        self.counts[self.fault] += 1
        return (
            self.fault,
            f"recovering from {self.fault.value}: {self.good_ticks}/{self.limits.recovery_ticks} "
            "good ticks",
        )

    def _detect(self, q: np.ndarray | list, raw: list, dt: float) -> tuple[SensorFault, str]:
        positions = q if type(q) is list else q.tolist()
        # One test for the common case: the sum is finite only if every input is (or they overflow:
        # the tests below pass).
        if not (math.isfinite(sum(raw) + sum(positions)) and 1e-6 <= dt < math.inf):  # MIN_DT
            if not all(map(math.isfinite, raw)):
                return SensorFault.NOT_FINITE, f"raw_wrench not finite: {raw}: holding"
            if not all(map(math.isfinite, positions)):
                return SensorFault.NOT_FINITE, f"q not finite: {positions}: holding"
            if not (math.isfinite(dt) and dt >= MIN_DT):
                return SensorFault.DT_JUMP, (
                    f"dt = {dt!r} s is not a time step of at least {MIN_DT:g} s: holding"
                )
        reference = self._reference_dt
        if reference is None:
            reference = self._reference_dt = dt
        elif self._running_dt:  # weight 0.01 per accepted step: about 100 ticks of memory
            self._reference_dt = reference + 0.01 * (min(dt, self._ratio * reference) - reference)
        if dt > self._ratio * reference:
            return SensorFault.DT_JUMP, (
                f"dt = {dt:.4g} s is more than {self._ratio:g} x the nominal "
                f"{reference:.4g} s (dropped ticks): holding"
            )
        if self._check_range and not all(map(lt, map(abs, raw), self._ranges)):
            for channel, (value, limit) in enumerate(zip(raw, self._ranges)):
                if not -limit < value < limit:
                    return (
                        SensorFault.SATURATED,
                        f"channel {channel} reads {value:.4g}, at or beyond the range ±{limit:g}: "
                        "holding",
                    )
        if raw == self._previous:
            self._repeats += 1
            self._stale_time += dt
            if self._repeats >= self._stuck_ticks or self._stale_time > self._stuck_time:
                return (
                    SensorFault.STUCK,
                    f"reading unchanged for {self._repeats + 1} ticks ({self._stale_time:.4g} s): "
                    "holding",
                )
        else:
            self._previous, self._repeats, self._stale_time = raw, 0, 0.0
        return _OK
