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
value that is not finite, a stamp that does not advance for :attr:`Stillness.stale_after`.
"""

from __future__ import annotations

import logging
import math
import time
from collections import deque
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, RobotError, SensorError

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

    joint_speed: float = 0.005
    settle_time: float = 0.2
    window: int = 30
    force_std: float = 0.15
    torque_std: float = 0.01
    timeout: float = 15.0
    stale_after: float = 0.1
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
        except SensorError:  # a sensor that names its own fault keeps its kind
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


@dataclass(frozen=True)
class PoseReadings:
    """The readings of one still pose.

    Attributes:
        joint_positions: ``(n, nq)`` [rad], read with each reading.
        wrenches: ``(n, 6)`` raw readings [N, N·m], sensor frame.
        times: ``(n,)`` sensor stamps [s].
        wait: Time spent waiting for stillness [s].
    """

    joint_positions: np.ndarray
    wrenches: np.ndarray
    times: np.ndarray
    wait: float


def stationary(window: np.ndarray, stillness: Stillness) -> bool:
    """True when each channel's spread and half-window trend are within bounds."""
    bounds = np.repeat([stillness.force_std, stillness.torque_std], 3)
    half = len(window) // 2
    trend = np.abs(window[:half].mean(axis=0) - window[half:].mean(axis=0))
    return bool(np.all(window.std(axis=0) <= bounds) and np.all(trend <= bounds))


def record_still(robot, sensor: CheckedSensor, count: int, stillness: Stillness) -> PoseReadings:
    """Wait until the arm is still and the readings stationary, then take ``count`` readings.

    Raises:
        SensorError: the sensor failed (see :class:`CheckedSensor`).
        RobotError: the arm did not come to rest within ``stillness.timeout`` (the message says
            which test failed), or the robot failed.
    """
    start = time.monotonic()
    window: deque = deque(maxlen=stillness.window)
    still_since: float | None = None
    rows_q, rows_w, rows_t = [], [], []
    speed = math.inf
    while True:
        now = time.monotonic()
        if now - start > stillness.timeout:
            spread = np.array(window).std(axis=0) if len(window) > 1 else np.full(6, math.nan)
            raise RobotError(
                f"the arm did not settle within {stillness.timeout:g} s: largest joint speed "
                f"{speed:.3g} rad/s (limit {stillness.joint_speed:g}), reading spread "
                f"{np.round(spread, 4).tolist()} (limits {stillness.force_std:g} N, "
                f"{stillness.torque_std:g} N·m). A noisier sensor needs larger limits "
                "(Stillness(force_std=..., torque_std=...))"
            )
        q, dq = robot.joint_state()
        speed = float(np.max(np.abs(dq)))
        stamp, wrench, new = sensor.read()
        if speed > stillness.joint_speed:
            if rows_w:
                logger.info("a joint moved (%.3g rad/s) while recording: recording again", speed)
            still_since, rows_q, rows_w, rows_t = None, [], [], []
            window.clear()
        elif still_since is None:
            still_since = now
        if new and still_since is not None:
            if rows_w:
                rows_q.append(q)
                rows_w.append(wrench)
                rows_t.append(stamp)
            else:
                window.append(wrench)
                if (
                    now - still_since >= stillness.settle_time
                    and len(window) == stillness.window
                    and stationary(np.array(window), stillness)
                ):
                    rows_q, rows_w, rows_t = [q], [wrench], [stamp]
            if len(rows_w) == count:
                taken = (np.array(rows_q), np.array(rows_w), np.array(rows_t))
                return PoseReadings(*taken, now - start)
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
