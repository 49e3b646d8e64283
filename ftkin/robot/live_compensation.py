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

import os
import time
from collections.abc import Iterator

import numpy as np

from ..calibration.model import WRENCH_CHANNELS, SensorModel
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
    load=None,
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
        load: A :class:`~ftkin.control.load_events.LoadTracker` (docs/load.md): the contact is
            then also free of the load the gripper holds, and the tracker's events follow the
            samples (its clock advances by its ``period`` per sample: give the sensor's).

    The contact wrench is in the sensor frame, about its origin: what the environment exerts on
    the tool. The stream ends only when the caller stops iterating (or on a fault).

    Raises:
        InvalidInput: no arm given or recorded, a bad argument, or joint angles that are not
            the arm's (another number of joints).
        SensorError: the sensor failed, returned a non-finite value, or went stale.
        RobotConnectionLost: from the joint reader.
    """
    if arm is None:
        arm = _recorded_arm(calibration)
    if not callable(getattr(arm_reader, "joint_positions", None)):
        raise InvalidInput(
            f"arm_reader must have joint_positions() -> q, got {type(arm_reader).__name__}"
        )
    if not (isinstance(poll_period, int | float) and 0.0 <= poll_period < 0.1):
        raise InvalidInput(f"poll_period must be in [0, 0.1) s, got {poll_period!r}")
    compensator = Compensator(calibration, arm, allow_other_arm=allow_other_arm, load=load)
    paired = _PairedSensor(sensor) if callable(getattr(sensor, "read_with_joints", None)) else None
    checked = CheckedSensor(paired or sensor, stale_after)
    return _stream(compensator, arm_reader, checked, paired, float(poll_period))


def _recorded_arm(calibration) -> Arm:
    """The arm a calibration records, or :class:`InvalidInput` asking for one."""
    recorded = calibration.kinematics if isinstance(calibration, CalibrationResult) else None
    if recorded is None:
        raise InvalidInput("the calibration records no arm: pass arm= (e.g. load_robot('ur5e'))")
    return recorded.build_arm()


def _stream(compensator, arm_reader, checked, paired, poll_period) -> Iterator:
    compensate, sleep = compensator.compensate, time.sleep
    while True:
        stamp, wrench, new = checked.read()
        if not new:
            sleep(poll_period)
            continue
        q = paired.q if paired is not None else arm_reader.joint_positions()
        yield stamp, np.asarray(q, dtype=float), compensate(q, wrench)


class PackageLog:
    """Every RTDE package of a UR's built-in sensor, compensated and written to a CSV as it comes
    (a thread), none missed: :class:`~ftkin.robot.rtde_packages.RtdePackages` reads them in
    order on a connection of its own, however late this process is (ur_rtde's getters skip
    packages then: see that module).

    Each batch of packages is turned into the sensor frame
    (:func:`~ftkin.robot.ur.wrench_in_sensor`), compensated at once
    (:meth:`~ftkin.control.compensation.Compensator.compensate_batch`, the package's own
    ``actual_q``) and written as ``t`` [s, the controller's clock], the joints [rad] and
    ``fx..mz`` [N, N·m, sensor frame], flushed with each batch. The file is created new (never
    over an existing one) and synced when :meth:`close` ends the thread.

    Args:
        calibration: The calibration (with ``arm``, or recording its arm).
        host: The controller's address.
        path: The CSV to create.
        arm: The kinematics (default: the calibration's recorded arm).
        wrench_frame: The axes of ``ft_raw_wrench`` (``"base"``: UR's convention).
        timeout: No package for this long [s] is a lost controller (the thread stops and
            :attr:`error` holds it).
        allow_other_arm: Accept an ``arm`` other than the recorded one.

    Raises:
        RobotConnectionLost: the controller does not answer RTDE.
        FileExistsError: ``path`` exists.
    """

    def __init__(
        self,
        calibration,
        host: str,
        path,
        *,
        arm: Arm | None = None,
        wrench_frame: str = "base",
        timeout: float = 1.0,
        allow_other_arm: bool = False,
    ):
        import threading

        from .rtde_packages import RtdePackages

        arm = arm if arm is not None else _recorded_arm(calibration)
        self.compensator = Compensator(calibration, arm, allow_other_arm=allow_other_arm)
        self.wrench_frame, self.path = wrench_frame, path
        self.packages = RtdePackages(host, timeout=timeout)
        try:
            self.stream = open(path, "x", encoding="utf-8", newline="")  # noqa: SIM115 (close())
        except BaseException:
            self.packages.close()
            raise
        self.stream.write(",".join(["t", *arm.joint_names, *WRENCH_CHANNELS]) + "\n")
        self.count, self.error = 0, None
        self.stamps: list[np.ndarray] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="ftkin-package-log", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        from .ur import wrench_in_sensor

        try:
            while not self._stop.is_set():
                batch = self.packages.read()
                raw = wrench_in_sensor(batch.joint_positions, batch.wrenches, self.wrench_frame)
                contact = self.compensator.compensate_batch(batch.joint_positions, raw)
                table = np.column_stack([batch.timestamps, batch.joint_positions, contact])
                self.stream.write("\n".join(",".join(map(repr, row)) for row in table.tolist()))
                self.stream.write("\n")
                self.stream.flush()
                self.stamps.append(batch.timestamps)
                self.count += len(batch)
        except Exception as error:  # noqa: BLE001 (kept for the caller, who stops on it)
            if not self._stop.is_set():
                self.error = error

    def timestamps(self) -> np.ndarray:
        """``(n,)`` the controller's stamps of the packages logged so far [s]."""
        return np.concatenate(self.stamps) if self.stamps else np.zeros(0)

    def close(self) -> None:
        """Stop the thread, close the connection, sync and close the file."""
        self._stop.set()
        self._thread.join(2.0 * self.packages.timeout + 1.0)
        self.packages.close()
        self.stream.flush()
        os.fsync(self.stream.fileno())
        self.stream.close()
