"""Track a drifting sensor bias while the robot works: a Kalman random walk on ``[F0, M0]``.

The bias ``b = [F0, M0]`` [N, N·m, sensor frame] is modelled as a random walk
of rate ``q`` [N/√s, N·m/√s] per channel (from a ``random-walk`` calibration,
:mod:`ftkin.calibration.drift`, or given). Each control tick the compensator
hands over the contact wrench computed with the current bias, which is the
innovation ``raw − (b + tool gravity)``. The tracker only learns from ticks
where that innovation is the bias error and nothing else:

* **free of contact**: declared by the controller (``free=True``), or detected:
  the arm still (every joint slower than ``still_speed``) and every channel
  of the innovation within ``k σ`` (``σ² =`` reading noise ``+`` bias
  variance) for ``window`` seconds in a row;
* **never** while the controller says ``free=False``, during a sensor fault,
  or while the arm moves faster than ``max_speed`` (inertial forces are not
  in the model), even if declared free.

Ticks are gathered in blocks of ``window`` seconds; a block is used only when
all its ticks passed, and (when detected, not declared) when its mean stays
within ``k`` standard deviations of the prediction and the ``guard`` seconds
after it passed too; after any failed tick the first ``guard`` seconds are
skipped. So the small first and last ticks of a contact (its ramps, below
``k σ``) are never absorbed into the bias. A block is one Kalman measurement
update with the block mean (noise ``σ² / n``). Between updates the bias
variance grows by ``q² dt``. Any failed tick throws the partial and the
pending block away.
"""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_vector


def _positive_six(value, name: str) -> np.ndarray:
    """Six per-channel values from a scalar, ``[force, torque]`` or ``(6,)``, all finite and ≥ 0."""
    array = as_float_array(value, name)
    if array.shape == (2,):
        array = np.repeat(array, 3)
    if array.shape not in ((), (1,), (6,)):
        raise InvalidInput(f"{name} must be a scalar, [force, torque] or six channels, got shape {array.shape}")
    array = np.broadcast_to(array, (6,)).astype(float)
    if not np.all(np.isfinite(array)) or np.any(array < 0):
        raise InvalidInput(f"{name} must be finite and ≥ 0 (a scalar, [force, torque] or six channels), got {array}")
    return array


class BiasTracker:
    """Online random-walk estimate of the sensor bias from contact-free readings.

    Args:
        rate: Drift rate ``q`` [N/√s, N·m/√s]: ``[force, torque]`` or ``(6,)``.
        noise: Noise of one reading ``σ`` [N, N·m]: ``[force, torque]`` or ``(6,)`` (positive).
        window: Length of a block of consistent ticks before an update [s].
        guard: Consistent time needed after a detected block before it is used [s].
        k: Consistency threshold in standard deviations (per channel).
        still_speed: Fastest joint speed [rad/s] at which the arm counts as still (detection).
        max_speed: Fastest joint speed [rad/s] at which even a declared-free tick is used.
        initial_std: Standard deviation of the initial bias [N, N·m] (``[force, torque]`` or ``(6,)``).

    Attributes:
        update_count: Measurement updates made so far.
        last_update_span: Ticks from the last update's tick back to the first
            reading it used (to audit which readings moved the bias).
    """

    def __init__(self, rate, noise, *, window: float = 0.5, guard: float = 0.25, k: float = 4.0, still_speed: float = 0.01,
                 max_speed: float = 0.2, initial_std=0.0):
        self.rate = _positive_six(rate, "rate")
        self.noise = _positive_six(noise, "noise")
        if np.any(self.noise <= 0):
            raise InvalidInput(f"noise must be positive, got {self.noise}")
        numbers = np.array([window, guard, k, still_speed, max_speed], dtype=float)
        if not np.all(np.isfinite(numbers)) or np.any(numbers[[0, 2, 3, 4]] <= 0) or numbers[1] < 0:
            raise InvalidInput(f"window, k, still_speed and max_speed must be finite and > 0, guard ≥ 0, got {numbers}")
        self.window, self.guard, self.k, self.still_speed, self.max_speed = (float(v) for v in numbers)
        self._initial_std = _positive_six(initial_std, "initial_std")
        self.update_count = 0
        self.last_update_span = 0
        self.reset(np.zeros(6))

    @classmethod
    def from_calibration(cls, calibration, rate=None, noise=None, **options) -> BiasTracker:
        """A tracker whose rate and noise come from a calibration unless given.

        The rate is the calibration's random-walk rate (``drift.rate``), the
        noise its per-reading noise (``diagnostics.noise``), the initial
        uncertainty the standard error of its bias.

        Raises:
            InvalidInput: neither given nor in the calibration (e.g. a
                calibration without times: give ``rate=``).
        """
        drift = getattr(calibration, "drift", None)
        if rate is None:
            if drift is None or drift.rate is None:
                raise InvalidInput("the calibration has no random-walk drift rate: give rate=[N/√s, N·m/√s]")
            rate = drift.rate
        if noise is None:
            diagnostics = getattr(calibration, "diagnostics", None)
            if diagnostics is None:
                raise InvalidInput("the calibration has no noise estimate (method 'linear'?): give noise=[N, N·m]")
            noise = diagnostics.noise.channel_std
        errors = getattr(calibration, "std_errors", None)
        if errors is not None and "initial_std" not in options:
            options["initial_std"] = np.concatenate([errors["force_offset"], errors["torque_offset"]])
        tracker = cls(rate, noise, **options)
        tracker.reset(calibration.bias)
        return tracker

    # ------------------------------------------------------------- state
    def reset(self, bias, std=None) -> None:
        """Restart from ``bias`` ``(6,)`` [N, N·m] with standard deviation ``std`` (default: ``initial_std``)."""
        self._bias = as_vector(bias, 6, "bias [F0, M0]").copy()
        self._variance = (self._initial_std if std is None else _positive_six(std, "std")) ** 2
        self._previous_q = None
        self.interrupt()

    def interrupt(self) -> None:
        """Throw the current and the pending block away (a fault, a contact, a jump)."""
        self._start_block()
        self._pending = None
        self._settle = 0.0
        self._settle_ticks = 0

    def _start_block(self) -> None:
        self._sum = np.zeros(6)
        self._count = 0
        self._elapsed = 0.0

    @property
    def bias(self) -> np.ndarray:
        """Current bias estimate ``(6,)`` [N, N·m]."""
        return self._bias.copy()

    @property
    def std(self) -> np.ndarray:
        """Its standard deviation ``(6,)`` [N, N·m]."""
        return np.sqrt(self._variance)

    # -------------------------------------------------------------- tick
    def observe(self, contact_wrench, dt: float, *, q=None, free: bool | None = None, fault: bool = False) -> bool:
        """Feed one tick; True when the bias estimate changed (read :attr:`bias`).

        Args:
            contact_wrench: ``(6,)`` raw − current bias − tool gravity [N, N·m].
            dt: Time since the previous tick [s].
            q: Joint positions ``(nq,)`` [rad], for the arm's speed (None: taken as still).
            free: True: the controller declares the tool free of contact;
                False: in contact (never update); None: detect.
            fault: The tick is a sensor fault (never update).
        """
        dt = float(dt)
        if not (math.isfinite(dt) and dt > 0.0):
            self.interrupt()
            return False
        self._variance = self._variance + self.rate**2 * dt
        speed = 0.0
        if q is not None:
            q = np.array(q, dtype=float)
            if self._previous_q is not None and self._previous_q.shape == q.shape:
                speed = float(np.max(np.abs(q - self._previous_q))) / dt
            self._previous_q = q
        contact = np.asarray(contact_wrench, dtype=float)
        limit = self.max_speed if free else self.still_speed
        if fault or free is False or speed > limit or not np.all(np.isfinite(contact)):
            self.interrupt()
            return False
        if free is None and np.any(np.abs(contact) > self.k * np.sqrt(self.noise**2 + self._variance)):
            self.interrupt()
            return False
        if not free and self._settle < self.guard:
            self._settle += dt
            return False
        self._sum += contact
        self._count += 1
        self._elapsed += dt
        updated = False
        if self._pending is not None:
            self._pending[2] += dt
            self._pending[3] += 1
            if self._pending[2] >= self.guard:
                updated = self._update(self._pending[0], self._pending[1], self._pending[1] + self._pending[3] - 1)
                self._pending = None
        if self._elapsed >= self.window:
            mean, count = self._sum / self._count, self._count
            self._start_block()
            if free:
                updated = self._update(mean, count, count - 1) or updated
            elif np.all(np.abs(mean) <= self.k * np.sqrt(self.noise**2 / count + self._variance)):
                self._pending = [mean, count, 0.0, 0]
        return updated

    def _update(self, mean: np.ndarray, count: int, span: int) -> bool:
        """Kalman measurement update with a block mean of ``count`` ticks (the first ``span`` ticks ago)."""
        measurement_variance = self.noise**2 / count
        gain = self._variance / (self._variance + measurement_variance)
        step = gain * mean
        self._bias = self._bias + step
        self._sum -= step * self._count  # the ticks gathered since were compensated with the old bias
        self._variance = (1.0 - gain) * self._variance
        self.update_count += 1
        self.last_update_span = span
        return True
