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

Every tick that passed is one Kalman measurement of the bias (noise ``σ²``),
applied in time order by a filter that runs ``guard`` seconds behind the
clock (declared free: no delay): a tick is used only once the ``guard``
seconds after it passed too, in batches every ``window`` seconds (so a
detected update rarely falls on the first, small tick of a contact); after any failed tick the first
``guard`` seconds are skipped, and the mean of the ticks not yet used must
stay within ``k`` standard deviations (``σ² / n +`` bias variance) of the
prediction. So the small first and last ticks of a contact (its ramps, below
``k σ``) are never absorbed into the bias, while every other free reading
is. A failed tick ends the run: the waiting ticks that had ``guard`` seconds of
consistent ticks after them (in a run that lasted ``window + guard``) are still
used (they are the most recent free readings, the most telling for the
contact that follows), the others thrown away. The delayed filter is
exact for a random walk: the bias now is predicted by the filtered bias at
the last used tick, its variance grown by ``q²`` times the time since.
"""

import math
from collections import deque

import numpy as np

from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from ..validation import as_six_channels, as_vector


class BiasTracker:
    """Online random-walk estimate of the sensor bias from contact-free readings.

    Args:
        rate: Drift rate ``q`` [N/√s, N·m/√s]: ``[force, torque]`` or ``(6,)``.
        noise: Noise of one reading ``σ`` [N, N·m]: ``[force, torque]`` or ``(6,)`` (positive).
        window: Consistent time (detected) before the first update of a run [s].
        guard: Consistent time (detected) needed after a tick before it is used [s].
        k: Consistency threshold in standard deviations (per channel).
        still_speed: Fastest joint speed [rad/s] at which the arm counts as still (detection).
        max_speed: Fastest joint speed [rad/s] at which even a declared-free tick is used.
        initial_std: Standard deviation of the initial bias [N, N·m] (``[force, torque]`` or
        ``(6,)``).

    Attributes:
        update_count: Measurement updates made so far.
        last_update_span: Ticks from the last update's tick back to the oldest
            reading it used (to audit which readings moved the bias).
        last_update_ticks: ``(first, last)`` tick numbers of the readings the
            last update used (ticks counted from 1 since :meth:`reset`; the
            current tick is :attr:`tick_count`).
    """

    def __init__(
        self,
        rate,
        noise,
        *,
        window: float = 0.5,
        guard: float = 0.25,
        k: float = 4.0,
        still_speed: float = 0.01,
        max_speed: float = 0.2,
        initial_std=0.0,
    ):
        self.rate = as_six_channels(rate, "rate", non_negative=True)
        self.noise = as_six_channels(noise, "noise", non_negative=True)
        if np.any(self.noise <= 0):
            raise InvalidInput(f"noise must be positive, got {self.noise}")
        numbers = np.array([window, guard, k, still_speed, max_speed], dtype=float)
        if not np.all(np.isfinite(numbers)) or np.any(numbers[[0, 2, 3, 4]] <= 0) or numbers[1] < 0:
            raise InvalidInput(
                "window, k, still_speed and max_speed must be finite and > 0, guard ≥ 0, got "
                f"{numbers}"
            )
        self.window, self.guard, self.k, self.still_speed, self.max_speed = (
            float(v) for v in numbers
        )
        self._initial_std = as_six_channels(initial_std, "initial_std", non_negative=True)
        self._rate2, self._noise2 = (
            (self.rate**2).tolist(),
            (self.noise**2).tolist(),
        )  # the per-tick gate runs on floats
        self.update_count, self.last_update_span, self.last_update_ticks = 0, 0, (0, 0)
        self.reset(np.zeros(6))

    @classmethod
    def from_calibration(cls, calibration, rate=None, noise=None, **options) -> "BiasTracker":
        """A tracker whose rate and noise come from a calibration unless given.

        The rate is the calibration's random-walk rate (``drift.rate``), the
        noise its per-reading noise (``diagnostics.noise``), the initial
        uncertainty the standard error of its bias.

        Raises:
            InvalidInput: neither given nor in the calibration (e.g. a
                calibration without times: give ``rate=``).
        """
        drift, diagnostics, errors = (
            (calibration.drift, calibration.diagnostics, calibration.std_errors)
            if isinstance(calibration, CalibrationResult)
            else (None, None, None)  # a bare SensorModel has none of them
        )
        if rate is None:
            if drift is None or drift.rate is None:
                raise InvalidInput(
                    "the calibration has no random-walk drift rate: give rate=[N/√s, N·m/√s]"
                )
            rate = drift.rate
        if noise is None:
            if diagnostics is None:
                raise InvalidInput(
                    "the calibration has no noise estimate (method 'linear'?): give noise=[N, N·m]"
                )
            noise = diagnostics.noise.channel_std
        if errors is not None and "initial_std" not in options:
            options["initial_std"] = np.concatenate(
                [errors["force_offset"], errors["torque_offset"]]
            )
        tracker = cls(rate, noise, **options)
        tracker.reset(calibration.bias)
        return tracker

    # ------------------------------------------------------------- state
    def reset(self, bias, std=None) -> None:
        """Restart from ``bias`` ``(6,)`` [N, N·m] with standard deviation ``std`` (default:
        ``initial_std``).
        """
        self._bias = as_vector(bias, 6, "bias [F0, M0]").copy()
        self._filter_variance = (
            self._initial_std if std is None else as_six_channels(std, "std", non_negative=True)
        ) ** 2
        # the clock and the time of the filter's last measurement (the delayed filter's clock) [s]
        self._clock = self._filter_time = 0.0
        self._tick, self._previous_q = 0, None
        self.interrupt()

    def interrupt(self) -> None:
        """Throw the readings not yet used away (a fault, a contact, a jump)."""
        # (time [s], tick, measured bias: six floats) of consistent ticks not yet used, their sum
        self._waiting, self._waiting_sum = deque(), [0.0] * 6
        self._settle, self._run_start = 0.0, None  # _run_start: first waiting tick's time [s]

    def _end_run(self, dt: float) -> bool:
        """A failed tick at the clock: use the waiting ticks that had ``guard`` s of consistent
        ticks after them, drop the rest.

        True when that moved the bias.
        """
        tolerance, last_consistent = 1e-9 * max(dt, 1.0), self._clock - dt
        used = (
            self._run_start is not None
            and last_consistent - self._run_start >= self.window + self.guard - tolerance
            and self._use(last_consistent - self.guard + tolerance)
        )
        self.interrupt()
        return used

    @property
    def tick_count(self) -> int:
        """Ticks observed since :meth:`reset`."""
        return self._tick

    @property
    def bias(self) -> np.ndarray:
        """Current bias estimate ``(6,)`` [N, N·m]."""
        return self._bias.copy()

    @property
    def std(self) -> np.ndarray:
        """Its standard deviation ``(6,)`` [N, N·m]."""
        return np.sqrt(self._filter_variance + self.rate**2 * (self._clock - self._filter_time))

    # -------------------------------------------------------------- tick
    def observe(
        self, contact_wrench, dt: float, *, q=None, free: bool | None = None, fault: bool = False
    ) -> bool:
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
        self._clock += dt
        self._tick += 1
        contact, speed = self._read(contact_wrench, q, dt)
        if len(contact) != 6:
            raise InvalidInput(f"contact_wrench must have six values [N, N·m], got {len(contact)}")
        limit = self.max_speed if free else self.still_speed  # declared free: up to max_speed
        if fault or free is False or speed > limit or not all(map(math.isfinite, contact)):
            return self._end_run(dt)
        elapsed, k = self._clock - self._filter_time, self.k
        variance = [v + r2 * elapsed for v, r2 in zip(self._filter_variance.tolist(), self._rate2)]
        if free is None and any(
            abs(c) > k * math.sqrt(n2 + v) for c, n2, v in zip(contact, self._noise2, variance)
        ):
            return self._end_run(dt)
        if not free and self._settle < self.guard:
            self._settle += dt
            return False
        bias = self._bias.tolist()
        measured = [
            c + b for c, b in zip(contact, bias)
        ]  # raw − tool gravity: this tick's measurement of the bias
        if self._run_start is None:
            self._run_start = self._clock
        self._waiting.append((self._clock, self._tick, measured))
        self._waiting_sum = [s + m for s, m in zip(self._waiting_sum, measured)]
        if free:
            return self._use(self._clock)
        count = len(self._waiting)
        if any(
            abs(s / count - b) > k * math.sqrt(n2 / count + v)
            for s, b, n2, v in zip(self._waiting_sum, bias, self._noise2, variance)
        ):
            self.interrupt()  # the waiting ticks together are inconsistent: none of them is used
            return False
        tolerance = 1e-9 * max(dt, 1.0)
        if self._clock - self._waiting[0][0] < self.window + self.guard - tolerance:
            return False
        return self._use(self._clock - self.guard + tolerance)

    def _read(self, contact_wrench, q, dt: float) -> tuple[list, float]:
        """The tick's contact wrench as six floats and the fastest joint speed [rad/s] (0 without
        ``q``; inf on the first tick with positions).
        """
        # on Python floats, as the rest of the tick: numpy's per-call cost dominates on 6-vectors
        try:
            positions = (
                None
                if q is None
                else q.tolist()
                if type(q) is np.ndarray
                else [float(value) for value in q]
            )
            contact = (
                contact_wrench.tolist()
                if type(contact_wrench) is np.ndarray
                else [float(value) for value in contact_wrench]
            )
        except (TypeError, ValueError) as error:
            raise InvalidInput(f"q and contact_wrench must be numbers: {error}") from None
        if positions is None:
            return contact, 0.0
        previous, self._previous_q = self._previous_q, positions
        if previous is None or len(previous) != len(positions):
            return contact, math.inf  # the first tick with positions: the speed is not known yet
        return contact, max(map(abs, map(float.__sub__, positions, previous)), default=0.0) / dt

    def _use(self, until: float) -> bool:
        """Kalman updates, in time order, with every waiting tick taken at or before ``until``
        [s].
        """
        waiting = self._waiting
        if not waiting or waiting[0][0] > until:
            return False
        bias, variance, filter_time = (
            self._bias.tolist(),
            self._filter_variance.tolist(),
            self._filter_time,
        )
        rate_squared, noise_squared = self._rate2, self._noise2
        first_tick = last_tick = waiting[0][1]
        while (
            waiting and waiting[0][0] <= until
        ):  # per channel, on floats (six-element numpy calls cost more)
            time, last_tick, measured = waiting.popleft()
            self._waiting_sum = [s - m for s, m in zip(self._waiting_sum, measured)]
            elapsed = time - filter_time
            for c in range(6):
                predicted = variance[c] + rate_squared[c] * elapsed
                gain = predicted / (predicted + noise_squared[c])
                bias[c] += gain * (measured[c] - bias[c])
                variance[c] = (1.0 - gain) * predicted
            filter_time = time
        self._bias, self._filter_variance, self._filter_time = (
            np.array(bias),
            np.array(variance),
            filter_time,
        )
        self.update_count += 1
        self.last_update_span, self.last_update_ticks = (
            self._tick - first_tick,
            (first_tick, last_tick),
        )
        return True
