"""A fake robot and a fake sensor for the robot stage's unit tests (no network, no franky)."""

from __future__ import annotations

import math
import time

import numpy as np

from ftkin.exceptions import RobotConnectionLost, RobotError


class FakeRobot:
    """Joint state from a schedule; records every command and stop with its time.

    ``moving_until``: joint speed 0.1 rad/s until this many ``joint_state`` calls, then 0.
    ``fail_at``: ``{call number: exception}`` raised by ``command_velocity``.
    """

    def __init__(self, nq=7, moving_until=0, fail_at=None):
        self.q = np.zeros(nq)
        self.calls = 0
        self.moving_until = moving_until
        self.fail_at = dict(fail_at or {})
        self.commands: list[tuple[float, np.ndarray]] = []
        self.stops: list[float] = []
        self.moves: list[np.ndarray] = []

    def joint_state(self):
        self.calls += 1
        speed = 0.1 if self.calls <= self.moving_until else 0.0
        return self.q.copy(), np.full(self.q.shape, speed)

    def joint_positions(self):
        return self.joint_state()[0]

    def joint_velocities(self):
        return self.joint_state()[1]

    def move_to(self, q, while_moving=None):
        if while_moving is not None:
            while_moving()
        self.moves.append(np.asarray(q, dtype=float))
        self.q = np.asarray(q, dtype=float).copy()

    def command_velocity(self, dq):
        error = self.fail_at.get(len(self.commands))
        if error is not None:
            raise error
        self.commands.append((time.monotonic(), np.asarray(dq, dtype=float)))

    def stop(self):
        self.stops.append(time.monotonic())

    def set_payload(self, calibration, **options):
        return None

    def payload(self):
        return 0.0, np.zeros(3), np.zeros((3, 3))


class FakeSensor:
    """Readings from a function of the read count; faults from ``fault_at``: ``{n: kind}``."""

    def __init__(self, wrench=None, noise=0.0, seed=0, fault_at=None):
        self.wrench = np.zeros(6) if wrench is None else np.asarray(wrench, dtype=float)
        self.noise = noise
        self.rng = np.random.default_rng(seed)
        self.count = 0
        self.fault_at = dict(fault_at or {})
        self.fault = None
        self.fault_time = None
        self.last = None

    def read(self):
        self.count += 1
        if self.count in self.fault_at:
            self.fault = self.fault_at[self.count]
            self.fault_time = time.monotonic()
        if self.fault == "raise":
            raise OSError("no answer")
        if self.fault == "stale" and self.last is not None:
            return self.last
        reading = self.wrench + self.noise * self.rng.standard_normal(6)
        if self.fault == "nan":
            reading = np.full(6, math.nan)
        self.last = (float(self.count) * 1e-3, reading)
        return self.last


ERRORS = {
    "robot": RobotError("the robot refused", "fake", "reflex"),
    "connection": RobotConnectionLost("gone", "fake"),
}
