"""Static readings on a robot: wait until the arm is still and the readings are stationary.

A reading taken while the arm moves holds the tool's inertial wrench, and one taken while the
arm still rings holds its vibration: a calibration fed with either is biased. A pose is recorded
only when, at once,

* every joint speed is below :attr:`Stillness.joint_speed` for :attr:`Stillness.settle_time`;
* the last :attr:`Stillness.window` readings are stationary: the standard deviation of each
  force (torque) channel is below :attr:`Stillness.force_std` (:attr:`Stillness.torque_std`),
  and the means of the window's two halves differ by less than the same bound (no trend);

and a recording in which a joint moves again is thrown away and restarted. :class:`CheckedSensor`
turns a sensor's failures into :class:`~ftkin.exceptions.SensorError`: a read that raises, a
value that is not finite, a stamp that does not advance for :attr:`Stillness.stale_after`; a
sensor that raises a ``SensorError`` itself (the adapters of :mod:`ftkin.sensors`) keeps its
``kind`` (``"status"``, ``"stall"``, ``"silence"``, ...).
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, RobotError, SensorError
from ..options import integer, number, option

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Stillness:
    """When the arm counts as still and the readings as stationary.

    Attributes:
        joint_speed: Largest joint speed of a still arm [rad/s].
        settle_time: The arm stays still this long before readings count [s].
        window: Readings in the stationarity test.
        force_std: Largest standard deviation (and half-window trend) of a force channel [N].
        torque_std: The same for a torque channel [N·m].
        timeout: Give up on a pose after this long [s].
        stale_after: A sensor whose stamp has not advanced for this long is stale [s].
        poll_period: Sleep between polls of the robot and the sensor [s].
    """

    joint_speed: float = option(
        0.005,
        "a pose is recorded when every joint is slower than this",
        unit="rad/s",
        flag="--still-joint-speed",
        parse=number(0.0, above=True),
        metavar="RAD_S",
    )
    settle_time: float = option(
        0.2,
        "and has been for this long",
        unit="s",
        flag="--still-settle-time",
        parse=number(0.0, above=True),
        metavar="S",
    )
    window: int = option(
        30,
        "readings in the stationarity test of each pose",
        flag="--still-window",
        parse=integer(4, 100_000),
        metavar="N",
    )
    force_std: float = option(
        0.15,
        "largest spread (and half-window trend) of a force channel of a stationary reading",
        unit="N",
        flag="--still-force-std",
        parse=number(0.0, above=True),
        metavar="N",
    )
    torque_std: float = option(
        0.01,
        "the same for a torque channel",
        unit="N·m",
        flag="--still-torque-std",
        parse=number(0.0, above=True),
        metavar="NM",
    )
    timeout: float = option(
        15.0,
        "give up on a pose that does not come still within this",
        unit="s",
        flag="--pose-timeout",
        parse=number(0.0, above=True),
        metavar="S",
    )
    stale_after: float = option(
        0.1,
        "a sensor whose stamp has not advanced for this long is a fault (raise it for a loaded "
        "simulator)",
        unit="s",
        flag="--stale-after",
        parse=number(0.0, above=True),
        metavar="S",
    )
    poll_period: float = 0.001

    def __post_init__(self):
        numbers = [
            self.joint_speed,
            self.settle_time,
            self.force_std,
            self.torque_std,
            self.timeout,
            self.stale_after,
        ]
        if not all(isinstance(v, (int, float)) and math.isfinite(v) and v > 0 for v in numbers) or (
            not (isinstance(self.poll_period, (int, float)) and 0.0 <= self.poll_period < 1.0)
        ):
            raise InvalidInput(
                f"stillness thresholds must be finite and > 0 (poll_period in [0, 1) s), got {self}"
            )
        if isinstance(self.window, bool) or not isinstance(self.window, int) or self.window < 4:
            raise InvalidInput(f"window must be an integer >= 4 readings, got {self.window!r}")


class CheckedSensor:
    """A sensor whose failures are :class:`~ftkin.exceptions.SensorError`.

    Args:
        sensor: Anything with ``read() -> (t [s], wrench (6,))``.
        stale_after: The stamp not advancing for this long [s, wall clock] is a stale sensor.
    """

    def __init__(self, sensor, stale_after: float):
        if not callable(getattr(sensor, "read", None)):
            raise InvalidInput(
                f"the sensor must have read() -> (t, wrench (6,)), got {type(sensor).__name__}"
            )
        self.sensor = sensor
        self.stale_after = float(stale_after)
        self.last_stamp: float | None = None
        self._changed_at = time.monotonic()

    def read(self) -> tuple[float, np.ndarray, bool]:
        """``(t [s], wrench (6,) [N, N·m], new)``; ``new`` is False for a repeated stamp.

        Raises:
            SensorError: the read raised, a value is not finite, or the sensor is stale.
        """
        try:
            stamp, values = self.sensor.read()
            stamp = float(stamp)
            wrench = np.asarray(values, dtype=float).reshape(6)
        except SensorError:  # a sensor that names its own fault (ftkin.sensors): keep its kind
            raise
        except Exception as error:  # a vendor driver may raise anything: a sensor fault
            raise SensorError(
                "read_failed", f"the sensor's read failed: {type(error).__name__}: {error}"
            ) from None
        if not (math.isfinite(stamp) and np.all(np.isfinite(wrench))):
            raise SensorError(
                "not_finite", f"the sensor returned a value that is not finite: t={stamp}, {wrench}"
            )
        now = time.monotonic()
        new = stamp != self.last_stamp
        if new:
            self.last_stamp, self._changed_at = stamp, now
        elif now - self._changed_at > self.stale_after:
            raise SensorError(
                "stale",
                f"the sensor is stale: its stamp {stamp} has not advanced for "
                f"{now - self._changed_at:.3f} s (limit {self.stale_after:g} s)",
            )
        return stamp, wrench, new


class SampleTap:
    """``read() -> (t, wrench)`` of a sensor for :class:`CheckedSensor`, keeping its full sample
    (``read_sample()``, a :class:`~ftkin.sensors.sample.SensorSample` with the IMU and the
    temperature) in :attr:`sample` where the sensor has one (else :attr:`sample` stays None)."""

    def __init__(self, sensor):
        self.sensor = sensor
        self.full = callable(getattr(sensor, "read_sample", None))
        self.sample = None

    def read(self):
        if not self.full:
            return self.sensor.read()
        self.sample = sample = self.sensor.read_sample()
        return sample.t, sample.wrench

    def imu(self) -> np.ndarray | None:
        """The last sample's ``[ax, ay, az]`` [m/s²] (and ``[wx, wy, wz]`` [rad/s]), or None."""
        sample = self.sample
        if sample is None:
            return None
        parts = [v for v in (sample.specific_force, sample.angular_velocity) if v is not None]
        return np.concatenate(parts) if parts else None


@dataclass(frozen=True)
class PoseReadings:
    """The readings of one still pose.

    Attributes:
        joint_positions: ``(n, nq)`` [rad], read with each reading (``nq`` may be 0: no joints).
        wrenches: ``(n, 6)`` raw readings [N, N·m], sensor frame.
        times: ``(n,)`` sensor stamps [s].
        wait: Time spent waiting for stillness [s].
        extra: ``(n, k)`` values taken with each reading (e.g. the IMU's), or None.
    """

    joint_positions: np.ndarray
    wrenches: np.ndarray
    times: np.ndarray
    wait: float
    extra: np.ndarray | None = None


def stationary(window: np.ndarray, stillness: Stillness) -> bool:
    """True when each channel's spread and half-window trend are within bounds."""
    bounds = np.repeat([stillness.force_std, stillness.torque_std], 3)
    half = len(window) // 2
    trend = np.abs(window[:half].mean(axis=0) - window[half:].mean(axis=0))
    return bool(np.all(window.std(axis=0) <= bounds) and np.all(trend <= bounds))


class StillnessDetector:
    """The test of :func:`record_still`, one poll at a time (also what a recorder that waits
    for an arm it does not drive polls: :mod:`ftkin.robot.recorder`).

    Each :meth:`update` takes one poll: the largest joint speed [rad/s] and the sensor's
    reading. A speed above ``stillness.joint_speed`` restarts everything (a recording in which
    a joint moves is thrown away); once still for ``settle_time`` with a full stationary
    window, the next ``count`` new readings are taken.

    Args:
        count: Readings to take once still.
        stillness: The thresholds.
    """

    def __init__(self, count: int, stillness: Stillness):
        self.count, self.stillness = int(count), stillness
        self.window: deque = deque(maxlen=stillness.window)
        self.speed = math.inf
        self.reset()

    def reset(self) -> None:
        """Forget the window and the readings taken (the arm moved)."""
        self.still_since: float | None = None
        self.rows: list[tuple] = []
        self.window.clear()

    def spread(self) -> np.ndarray:
        """``(6,)`` standard deviation of the window's readings [N, N·m] (NaN before two)."""
        return np.array(self.window).std(axis=0) if len(self.window) > 1 else np.full(6, math.nan)

    def update(self, now: float, speed: float, q, stamp, wrench, new: bool, extra=None) -> bool:
        """One poll at ``now`` [s]; True once ``count`` readings are taken (:meth:`readings`)."""
        self.speed = speed
        if speed > self.stillness.joint_speed:
            if self.rows:
                logger.info("a joint moved (%.3g rad/s) while recording: recording again", speed)
            self.reset()
        elif self.still_since is None:
            self.still_since = now
        if new and self.still_since is not None:
            if self.rows:
                self.rows.append((q, wrench, stamp, extra))
            else:
                self.window.append(wrench)
                if (
                    now - self.still_since >= self.stillness.settle_time
                    and len(self.window) == self.stillness.window
                    and stationary(np.array(self.window), self.stillness)
                ):
                    self.rows = [(q, wrench, stamp, extra)]
        return len(self.rows) >= self.count

    def readings(self, wait: float) -> PoseReadings:
        """The readings taken (after :meth:`update` returned True), waited ``wait`` [s]."""
        q, wrenches, times, extra = zip(*self.rows[: self.count])
        return PoseReadings(
            np.array(q),
            np.array(wrenches),
            np.array(times),
            wait,
            None if extra[0] is None else np.array(extra),
        )


def record_still(
    robot, sensor: CheckedSensor, count: int, stillness: Stillness, tap: SampleTap | None = None
) -> PoseReadings:
    """Wait until the arm is still and the readings stationary, then take ``count`` readings.

    With ``tap`` (the :class:`SampleTap` ``sensor`` reads through) the IMU's values of each
    reading are taken too (:attr:`PoseReadings.extra`).

    Raises:
        SensorError: the sensor failed (see :class:`CheckedSensor`).
        RobotError: the arm did not come to rest within ``stillness.timeout`` (the message says
            which test failed), or the robot failed.
    """
    start = time.monotonic()
    detector = StillnessDetector(count, stillness)
    while True:
        now = time.monotonic()
        if now - start > stillness.timeout:
            raise RobotError(
                f"the arm did not settle within {stillness.timeout:g} s: largest joint speed "
                f"{detector.speed:.3g} rad/s (limit {stillness.joint_speed:g}), reading spread "
                f"{np.round(detector.spread(), 4).tolist()} (limits {stillness.force_std:g} N, "
                f"{stillness.torque_std:g} N·m). A noisier sensor needs larger limits "
                "(Stillness(force_std=..., torque_std=...))"
            )
        q, dq = robot.joint_state()
        stamp, wrench, new = sensor.read()
        extra = None if tap is None else tap.imu()
        if detector.update(now, float(np.max(np.abs(dq))), q, stamp, wrench, new, extra):
            return detector.readings(now - start)
        time.sleep(stillness.poll_period)


def wait_still(robot, stillness: Stillness | None = None) -> float:
    """Wait until every joint speed stays below ``stillness.joint_speed`` for its settle time.

    Returns the time waited [s]. Start a control loop from a still arm: after a move a real
    arm (and franky-sim's) still catches up with the trajectory for a moment.

    Raises:
        RobotError: the arm did not come to rest within ``stillness.timeout``.
    """
    stillness = stillness if stillness is not None else Stillness()
    start = time.monotonic()
    still_since = None
    while True:
        now = time.monotonic()
        speed = float(np.max(np.abs(robot.joint_state()[1])))
        if speed > stillness.joint_speed:
            still_since = None
        elif still_since is None:
            still_since = now
        elif now - still_since >= stillness.settle_time:
            return now - start
        if now - start > stillness.timeout:
            raise RobotError(
                f"the arm did not come to rest within {stillness.timeout:g} s (joint speed "
                f"{speed:.3g} rad/s, limit {stillness.joint_speed:g})"
            )
        time.sleep(stillness.poll_period)
