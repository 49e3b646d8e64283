"""The control loop on a robot: read the state and the sensor, step the controller, command.

:func:`run_admittance` paces ``rate_hz`` ticks of

    q, dq = robot.joint_state();  t, wrench = sensor.read();
    dq_cmd = controller.step(q, wrench, dt);  robot.command_velocity(dq_cmd)

(a :class:`~ftkin.control.joint_admittance.JointAdmittance`), and returns :class:`LoopStats`.
A controller with an IMU compensator (``JointAdmittance(..., imu=ImuCompensator(calibration))``)
is given each tick's specific force too: the sensor's ``read_sample()`` (the adapters of
:mod:`ftkin.sensors` with an IMU), and the tool's acceleration is compensated as the
accelerometer sees it.
It stops the robot, in the tick the fault shows, and returns (never raises for these) on:

* a sensor fault: ``read()`` raising, a value that is not finite (``"read_failed"``,
  ``"not_finite"``), or a stamp that does not advance for ``stale_after`` (``"stale"``); a
  sensor that raises :class:`~ftkin.exceptions.SensorError` itself (the adapters of
  :mod:`ftkin.sensors`) stops the loop with its own kind (``"status"``, ``"stall"``,
  ``"silence"``, ``"driver"``, ...);
* a sample without the accelerometer for a controller that compensates with it (``"imu"``);
* a robot error (``"robot"``) or a lost connection (``"connection"``);
* the controller's safety stop (contact beyond its limits, ``"safety"``) or an oscillating loop
  (``"oscillation"``): both latch in the controller;
* Ctrl-C (``"interrupt"``).

Ticks the controller holds by itself (a saturated channel, a dropped tick, a stuck reading:
:class:`~ftkin.control.sensor_faults.SensorFault`) are counted by kind and the loop goes on;
the controller recovers from them. The robot's own watchdog stops the arm if the loop dies
without a word: a velocity command is held only ``watchdog`` seconds.
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np

from ..control.sensor_faults import SensorFault
from ..exceptions import InvalidInput, RobotConnectionLost, RobotError, SensorError
from .stillness import CheckedSensor, SampleTap

logger = logging.getLogger(__name__)

DEFAULT_RATE = 250.0
"""Default loop rate [Hz]."""

FINISHED = "duration"
"""The stop reason of a loop that ran its full duration."""


@dataclass(frozen=True)
class LoopStats:
    """What a control loop did.

    Attributes:
        ticks: Ticks run (commands sent).
        duration: Wall time from the first to the last tick [s].
        rate_hz: Achieved rate, ``(ticks − 1) / duration`` [Hz].
        nominal_rate_hz: The rate asked for [Hz].
        period_p50: Median tick period [s].
        period_p99: 99th percentile of the tick period [s].
        period_max: Longest tick period [s].
        faults: ``{kind: count}``: held ticks by the controller's fault kind, and the fault that
            stopped the loop (counted once).
        stop_reason: ``"duration"`` (ran to the end) or the fault that stopped it.
        message: The stopping fault's message ("" when the loop ran to the end).
        fault_time: ``time.monotonic()`` when the stopping fault showed, else None.
        stop_time: ``time.monotonic()`` when the stop command was sent.
    """

    ticks: int
    duration: float
    rate_hz: float
    nominal_rate_hz: float
    period_p50: float
    period_p99: float
    period_max: float
    faults: Mapping[str, int] = field(default_factory=dict)
    stop_reason: str = FINISHED
    message: str = ""
    fault_time: float | None = None
    stop_time: float | None = None

    @property
    def completed(self) -> bool:
        """True when the loop ran its whole duration without a stopping fault."""
        return self.stop_reason == FINISHED

    def report(self) -> str:
        """A few lines: rate, periods, faults, why it stopped."""
        faults = ", ".join(f"{kind}: {count}" for kind, count in self.faults.items()) or "none"
        lines = [
            f"{self.ticks} ticks in {self.duration:.2f} s: {self.rate_hz:.1f} Hz "
            f"(asked {self.nominal_rate_hz:g} Hz)",
            f"period p50 {self.period_p50 * 1e3:.2f} ms, p99 {self.period_p99 * 1e3:.2f} ms, "
            f"max {self.period_max * 1e3:.2f} ms",
            f"faults: {faults}",
            f"stopped: {self.stop_reason}" + (f" ({self.message})" if self.message else ""),
        ]
        return "\n".join(lines)


def run_admittance(
    robot,
    sensor,
    controller,
    *,
    duration: float | None = None,
    rate_hz: float = DEFAULT_RATE,
    stale_after: float | None = None,
    on_tick: Callable[[float, np.ndarray, np.ndarray], bool | None] | None = None,
) -> LoopStats:
    """Run the admittance loop until ``duration`` [s] (None: until a fault or Ctrl-C).

    Args:
        robot: A :class:`~ftkin.robot.protocols.Robot`.
        sensor: A :class:`~ftkin.robot.protocols.ForceTorqueSensor`.
        controller: A :class:`~ftkin.control.joint_admittance.JointAdmittance` (anything with
            ``step(q, raw_wrench, dt) -> dq``, ``last_status`` and ``reset()``) for this robot's
            joints. One warm-up step (not commanded) runs before the loop, then ``reset()``.
        duration: Run time [s]; None runs until stopped.
        rate_hz: Loop rate [Hz].
        stale_after: The sensor's stamp not advancing this long is a fault [s] (default: 10
            periods, at least 20 ms, and twice the sensor's own ``silence_after`` when it has
            one, so that an adapter of :mod:`ftkin.sensors` names a silence or a stall itself).
        on_tick: Called after each command with ``(time.monotonic(), q, dq_cmd)`` (logging,
            tests, an end condition); it must be fast. Returning True ends the loop as its
            duration would.

    Returns:
        :class:`LoopStats` (the robot is stopped).
    """
    rate_hz = _check_loop_inputs(rate_hz, duration, controller)
    period = 1.0 / rate_hz
    if stale_after is None:  # a sensor that watches its own silence (ftkin.sensors) speaks first
        own_limit = getattr(sensor, "silence_after", None)
        numeric = isinstance(own_limit, (int, float)) and not isinstance(own_limit, bool)
        own_limit = float(own_limit) if numeric else 0.0
        stale_after = max(10.0 * period, 0.02, 2.0 * own_limit)
    stale_after = float(stale_after)
    tap = _imu_tap(sensor, controller)
    checked = CheckedSensor(sensor if tap is None else tap, stale_after)
    faults: dict[str, int] = {}
    stamps: list[float] = []
    reason, message, fault_time = FINISHED, "", None
    try:
        _warm_up(robot, checked, controller, period, tap)
        start = next_tick = time.monotonic()
        deadline = math.inf if duration is None else start + float(duration)
        previous = start - period
        while True:
            now = time.monotonic()
            if now >= deadline:
                break
            q, _ = robot.joint_state()
            _, wrench, _ = checked.read()
            if tap is None:
                command = controller.step(q, wrench, now - previous)
            else:
                command = controller.step(
                    q, wrench, now - previous, specific_force=_specific_force(tap)
                )
            previous = now
            if not command.any():  # a held tick commands exactly zero: ask why
                ending = _held_tick(controller.last_status, faults)
                if ending is not None:
                    (reason, message), fault_time = ending, now
                    break
            robot.command_velocity(command)
            stamps.append(now)
            if on_tick is not None and on_tick(now, q, command):
                break
            next_tick += period
            delay = next_tick - time.monotonic()
            if delay > 0.0:
                time.sleep(delay)
            elif delay < -period:  # late by more than a tick: do not try to catch up
                next_tick = time.monotonic()
    except SensorError as error:
        reason, message, fault_time = error.kind, str(error), time.monotonic()
    except RobotConnectionLost as error:
        reason, message, fault_time = "connection", str(error), time.monotonic()
    except RobotError as error:
        reason, message, fault_time = "robot", str(error), time.monotonic()
    except KeyboardInterrupt:
        reason, message, fault_time = "interrupt", "Ctrl-C", time.monotonic()
    finally:
        robot.stop()
        stop_time = time.monotonic()
    if reason != FINISHED:
        faults[reason] = faults.get(reason, 0) + 1
        logger.warning("control loop stopped: %s: %s", reason, message)
    return _stats(stamps, rate_hz, faults, reason, message, fault_time, stop_time)


def _imu_tap(sensor, controller) -> SampleTap | None:
    """The tap the loop reads a sensor through when the controller compensates with the IMU.

    Raises:
        InvalidInput: the controller compensates with the IMU and the sensor has no
            ``read_sample()``.
    """
    if getattr(controller, "imu", None) is None:
        return None
    tap = SampleTap(sensor)
    if not tap.full:
        raise InvalidInput(
            "the controller compensates with the IMU, but the sensor has no read_sample() (an "
            f"adapter of ftkin.sensors with an IMU): {type(sensor).__name__}"
        )
    return tap


def _specific_force(tap: SampleTap) -> np.ndarray:
    """The last sample's specific force [m/s², IMU frame].

    Raises:
        SensorError: the sample has none (``"imu"``).
    """
    accel = tap.sample.specific_force
    if accel is None:
        raise SensorError("imu", "the sensor's sample has no specific force (no accelerometer)")
    return accel


def _check_loop_inputs(rate_hz, duration, controller) -> float:
    """``rate_hz`` as a float [Hz], once the loop's arguments are checked."""
    rate_hz = float(rate_hz)
    if not (math.isfinite(rate_hz) and 0.0 < rate_hz <= 1000.0):
        raise InvalidInput(f"rate_hz must be in (0, 1000] Hz, got {rate_hz!r}")
    if duration is not None and not (math.isfinite(float(duration)) and float(duration) > 0.0):
        raise InvalidInput(f"duration must be > 0 s or None, got {duration!r}")
    if not callable(getattr(controller, "step", None)):
        raise InvalidInput(f"controller must have step(q, wrench, dt), got {controller!r}")
    return rate_hz


def _warm_up(robot, checked: CheckedSensor, controller, period: float, tap) -> None:
    """A warm-up tick, not commanded: the first step of a controller loads what it needs.

    A sensor or robot fault here is met again by the loop's first tick, which stops as for any
    tick; a Ctrl-C (it comes once) propagates and stops the loop.
    """
    try:
        q, _ = robot.joint_state()
        wrench = checked.read()[1]
        if tap is None:
            controller.step(q, wrench, period)
        else:
            controller.step(q, wrench, period, specific_force=_specific_force(tap))
    except (SensorError, RobotError):
        pass
    finally:
        controller.reset()


def _held_tick(status, faults: dict[str, int]) -> tuple[str, str] | None:
    """Count a held tick's fault; ``(reason, message)`` when it ends the loop, else None."""
    fault = status.fault
    if fault is not SensorFault.NONE:
        faults[str(fault)] = faults.get(str(fault), 0) + 1
        if fault is SensorFault.OSCILLATION:
            return "oscillation", status.event
        return None
    if status.safety_stop:
        return "safety", status.event
    return None


def _stats(stamps, rate_hz, faults, reason, message, fault_time, stop_time) -> LoopStats:
    ticks = len(stamps)
    periods = np.diff(stamps) if ticks > 1 else np.zeros(1)
    span = float(stamps[-1] - stamps[0]) if ticks > 1 else 0.0
    return LoopStats(
        ticks=ticks,
        duration=span,
        rate_hz=(ticks - 1) / span if span > 0 else 0.0,
        nominal_rate_hz=rate_hz,
        period_p50=float(np.percentile(periods, 50)),
        period_p99=float(np.percentile(periods, 99)),
        period_max=float(periods.max()),
        faults=dict(faults),
        stop_reason=reason,
        message=message,
        fault_time=fault_time,
        stop_time=stop_time,
    )
