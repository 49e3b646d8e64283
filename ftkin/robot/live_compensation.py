"""Compensated samples as they come: a joint reader and a sensor in, ``(t, q, contact)`` out.

:func:`compensated_stream` is the loop a user writes around a calibration, done once: wait for
the sensor's next sample, take the joint angles of that instant, remove bias and tool gravity
(:class:`~ftkin.control.compensation.Compensator`), yield. It never yields a sample twice and
never an old one: a sensor whose stamp stands still for ``stale_after`` raises
:class:`~ftkin.exceptions.SensorError` (kind ``"stale"``), a value that is not finite or a read
that raises does too (:class:`~ftkin.robot.stillness.CheckedSensor`), and the joint reader's own
errors (:class:`~ftkin.exceptions.RobotConnectionLost`) pass through.

A sensor that carries the joint angles of its own sample (UR's built-in sensor,
:meth:`~ftkin.robot.ur.UrWristSensor.read_with_joints`: one RTDE package) gives them itself;
for any other the joints are read right after each new sample (``arm_reader.joint_positions()``).
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import numpy as np

from ..calibration.model import SensorModel
from ..calibration.result import CalibrationResult
from ..control.compensation import Compensator
from ..exceptions import InvalidInput
from ..kinematics.arm import Arm
from .stillness import CheckedSensor

DEFAULT_POLL_PERIOD = 0.0002
"""Sleep between polls of a sensor without a new sample [s] (10 polls per 500 Hz period)."""


class _PairedSensor:
    """``read()`` of a sensor with ``read_with_joints()``, keeping the joints of the sample."""

    def __init__(self, sensor):
        self.sensor, self.q = sensor, None

    def read(self):
        stamp, self.q, wrench = self.sensor.read_with_joints()
        return stamp, wrench


def compensated_stream(
    calibration: SensorModel,
    arm_reader,
    sensor,
    *,
    arm: Arm | None = None,
    stale_after: float = 0.1,
    poll_period: float = DEFAULT_POLL_PERIOD,
    allow_other_arm: bool = False,
) -> Iterator[tuple[float, np.ndarray, np.ndarray]]:
    """Yield ``(t [s], q (nq,) [rad], contact (6,) [N, N·m])`` for each new sensor sample.

    Args:
        calibration: The calibration (:class:`~ftkin.calibration.CalibrationResult`).
        arm_reader: Anything with ``joint_positions() -> (nq,)`` [rad] (a
            :class:`~ftkin.robot.ur.UrArm`, a :class:`~ftkin.robot.protocols.Robot`).
        sensor: A :class:`~ftkin.robot.protocols.ForceTorqueSensor` (``read() -> (t, wrench)``,
            sensor frame, the load on it).
        arm: The kinematics (default: the arm the calibration records,
            ``calibration.kinematics.build_arm()``).
        stale_after: The sensor's stamp not advancing for this long is a fault [s].
        poll_period: Sleep between polls while no new sample has come [s].
        allow_other_arm: Accept an ``arm`` other than the recorded one.

    The contact wrench is in the sensor frame, about its origin: what the environment exerts on
    the tool. The stream ends only when the caller stops iterating (or on a fault).

    Raises:
        InvalidInput: no arm given or recorded, a bad argument, or joint angles that are not
            the arm's (another number of joints).
        SensorError: the sensor failed, returned a non-finite value, or went stale.
        RobotConnectionLost: from the joint reader.
    """
    if arm is None:
        recorded = calibration.kinematics if isinstance(calibration, CalibrationResult) else None
        if recorded is None:
            raise InvalidInput(
                "the calibration records no arm: pass arm= (e.g. load_robot('ur5e'))"
            )
        arm = recorded.build_arm()
    if not callable(getattr(arm_reader, "joint_positions", None)):
        raise InvalidInput(
            f"arm_reader must have joint_positions() -> q, got {type(arm_reader).__name__}"
        )
    if not (isinstance(poll_period, int | float) and 0.0 <= poll_period < 0.1):
        raise InvalidInput(f"poll_period must be in [0, 0.1) s, got {poll_period!r}")
    compensator = Compensator(calibration, arm, allow_other_arm=allow_other_arm)
    paired = _PairedSensor(sensor) if callable(getattr(sensor, "read_with_joints", None)) else None
    checked = CheckedSensor(paired or sensor, stale_after)
    return _stream(compensator, arm_reader, checked, paired, float(poll_period))


def _stream(compensator, arm_reader, checked, paired, poll_period) -> Iterator:
    compensate, sleep = compensator.compensate, time.sleep
    while True:
        stamp, wrench, new = checked.read()
        if not new:
            sleep(poll_period)
            continue
        q = paired.q if paired is not None else arm_reader.joint_positions()
        yield stamp, np.asarray(q, dtype=float), compensate(q, wrench)
