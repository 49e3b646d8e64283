"""A Universal Robots arm through ur_rtde, read-only: joints, flange pose, built-in wrist sensor.

:class:`UrArm` reads RTDE (TCP port 30004) with ur_rtde's ``RTDEReceiveInterface``
(``pip install -e '.[ur]'``): ``actual_q``, ``actual_qd``, ``actual_TCP_pose`` and
``ft_raw_wrench`` with the controller's ``timestamp``, all from one RTDE package
(:meth:`UrArm.state`). It commands nothing: moving the arm needs URScript running on the
controller, which ftkin leaves to the pendant (freedrive, a program) or to ``RTDEControlInterface``.

**The wrench frame.** ``ft_raw_wrench`` is the built-in sensor's raw reading: not compensated for
the payload and not zeroed by the controller (unlike ``actual_TCP_force``, which must not be
calibrated). UR's RTDE guide does not name its axes; the wrench convention UR documents for its
controller is base axes with the force at the tool flange (``get_tcp_force()`` in the URScript
manual; UR's ROS 2 driver takes the RTDE wrench as "a wrench at the flange, oriented in the base
frame" and rotates it with the flange orientation, Universal_Robots_ROS2_Driver #1615). That is
the default, ``wrench_frame="base"``: ``F_S = ᴮR_tool0ᵀ F_B``, ``M_S = ᴮR_tool0ᵀ M_B`` (torque kept
about the flange origin), with ``ᴮR_tool0`` from the package's own ``actual_q``
(:func:`~ftkin.kinematics.ur_eseries.flange_rotation`, the same for every UR model and independent
of the TCP set on the pendant). ``wrench_frame="sensor"`` takes the reading as it comes. A wrong
choice is caught from recorded poses, not guessed:
:func:`~ftkin.calibration.wrench_frame.check_wrench_frame` names the flag to change.

**Faults.** After a lost connection ur_rtde raises nothing: its getters go on returning the last
values and only ``isConnected()`` turns False; a frozen controller keeps the connection up and
stops sending. Every read here checks both: ``isConnected()`` False, or a ``timestamp`` that has
not advanced for ``stale_after`` [s], raises :class:`~ftkin.exceptions.RobotConnectionLost` (the
joint reads) or :class:`~ftkin.exceptions.SensorError` (the wrist sensor, kinds ``"read_failed"``
and ``"stale"``), never a stream of old values.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, RobotConnectionLost, SensorError
from ..kinematics.ur_eseries import flange_rotation

logger = logging.getLogger(__name__)

WRENCH_FRAMES = ("base", "sensor")
"""Axes ``ft_raw_wrench`` can be read in; the first is UR's convention and the default."""
DEFAULT_STALE_AFTER = 0.1
"""A timestamp that has not advanced for this long [s] is a frozen controller (50 packages at
500 Hz; ur_rtde itself gives up after about 2.5 s)."""


def wrench_in_sensor(q, raw, wrench_frame: str) -> np.ndarray:
    """``ft_raw_wrench`` in the sensor (flange) frame: ``(6,)`` or ``(n, 6)`` [N, N·m] from the
    package's ``actual_q`` ``(6,)`` or ``(n, 6)`` [rad] (module docstring: ``F_S = ᴮR_tool0ᵀ
    F_B``, the torque alike, for ``"base"``; as it came for ``"sensor"``)."""
    raw = np.array(raw, dtype=float)
    if wrench_frame == "sensor":
        return raw
    if wrench_frame != "base":
        raise InvalidInput(f"wrench_frame must be one of {WRENCH_FRAMES}, got {wrench_frame!r}")
    q = np.asarray(q, dtype=float)
    if q.ndim == 1:
        rotation = flange_rotation(q)
        return np.concatenate([rotation.T @ raw[:3], rotation.T @ raw[3:]])
    rotations = np.array([flange_rotation(row) for row in q])  # (n, 3, 3) ᴮR_tool0
    return np.einsum("nji,nkj->nki", rotations, raw.reshape(-1, 2, 3)).reshape(-1, 6)


def import_rtde_receive():
    """ur_rtde's ``rtde_receive`` module, or :class:`MissingDependency` naming the ``ur`` extra."""
    try:
        import rtde_receive
    except ImportError as error:
        raise MissingDependency("ur_rtde", "ur", "reading a Universal Robots arm") from error
    return rtde_receive


@dataclass(frozen=True)
class UrState:
    """One RTDE package (its arrays are read-only: one package is shared by every read of it).

    Attributes:
        timestamp: The controller's clock [s] (advances one period per package).
        q: ``actual_q`` ``(6,)`` [rad].
        dq: ``actual_qd`` ``(6,)`` [rad/s].
        tcp_pose: ``actual_TCP_pose`` ``(6,)``: position [m] and rotation vector [rad] in the
            base frame (the flange when the TCP offset is zero).
        raw_wrench: ``ft_raw_wrench`` ``(6,)`` [N, N·m] as the controller sent it.
        wrench_in_sensor: The same in the sensor (flange) frame, per ``wrench_frame``.
    """

    timestamp: float
    q: np.ndarray
    dq: np.ndarray
    tcp_pose: np.ndarray
    raw_wrench: np.ndarray
    wrench_in_sensor: np.ndarray


def rotation_from_vector(rotation_vector) -> np.ndarray:
    """The rotation matrix ``(3, 3)`` of a rotation vector (axis × angle [rad], RTDE's pose form):
    Pinocchio's ``exp3``."""
    import pinocchio as pin

    return pin.exp3(np.asarray(rotation_vector, dtype=float).reshape(3))


class UrArm:
    """A UR arm read through RTDE.

    Args:
        host: The controller's address.
        wrench_frame: Axes of ``ft_raw_wrench``: ``"base"`` (UR's convention, the default) or
            ``"sensor"``; see the module docstring.
        stale_after: A timestamp not advancing for this long is a fault [s].
        frequency: RTDE output rate [Hz]; -1 lets ur_rtde choose (500 Hz on an e-Series).

    Attributes:
        host, wrench_frame, stale_after: As given.
        sensor: The built-in wrist sensor, a :class:`UrWristSensor`.

    Raises:
        MissingDependency: ur_rtde is not installed (extra ``ur``).
        InvalidInput: a bad argument.
        RobotConnectionLost: nothing answers RTDE at ``host`` (or it refused the setup).
    """

    def __init__(
        self,
        host: str,
        *,
        wrench_frame: str = "base",
        stale_after: float = DEFAULT_STALE_AFTER,
        frequency: float = -1.0,
    ):
        if not isinstance(host, str) or not host.strip():
            raise InvalidInput(f"host must be the controller's address, got {host!r}")
        if wrench_frame not in WRENCH_FRAMES:
            raise InvalidInput(
                f"wrench_frame must be one of {WRENCH_FRAMES} (--wrench-frame base|sensor), got "
                f"{wrench_frame!r}"
            )
        if not (isinstance(stale_after, int | float) and 0.0 < stale_after < 60.0):
            raise InvalidInput(f"stale_after must be in (0, 60) s, got {stale_after!r}")
        if not (
            isinstance(frequency, int | float) and (frequency == -1.0 or 0.0 < frequency <= 500.0)
        ):
            raise InvalidInput(
                f"frequency must be -1 (ur_rtde's choice) or in (0, 500] Hz, got {frequency!r}"
            )
        self.host, self.wrench_frame, self.stale_after = host, wrench_frame, float(stale_after)
        rtde_receive = import_rtde_receive()
        try:
            self._rtde = rtde_receive.RTDEReceiveInterface(host, float(frequency))
        except RuntimeError as error:
            raise RobotConnectionLost(
                f"cannot read RTDE from {host} (port 30004)", host, str(error).strip()
            ) from None
        self._last_stamp: float | None = None
        self._stamp_changed_at = time.monotonic()
        self._cached: UrState | None = None

    @property
    def sensor(self) -> UrWristSensor:
        """The built-in wrist sensor (a new light handle on this arm each time: no reference
        cycle keeps a closed arm's connection alive)."""
        return UrWristSensor(self)

    def __repr__(self) -> str:
        return f"UrArm({self.host!r}, wrench_frame={self.wrench_frame!r})"

    def __enter__(self) -> UrArm:
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def close(self, *, wait: bool = True) -> None:
        """Disconnect (never raises); reads afterwards raise :class:`RobotConnectionLost`.

        ur_rtde's interface disconnects when it is destroyed, which takes 0.5 s with the GIL
        held (its receive thread's stop), and as long again for an explicit ``disconnect()``
        before: the reference is dropped, once. ``wait=False`` is for a process about to exit
        (the command line): the interface is never destroyed, the operating system closes its
        socket when the process ends, and a command stopped by a lost controller ends at once
        instead of 0.5 s later. In a process that goes on, each such close leaves ur_rtde's
        receive thread behind.
        """
        if self._rtde is None:
            return
        rtde, self._rtde = self._rtde, None
        if not wait:
            import ctypes

            ctypes.pythonapi.Py_IncRef(ctypes.py_object(rtde))  # never destroyed: no 0.5 s wait
        del rtde

    # -------------------------------------------------------------- reading
    def _connection(self, error_type=RobotConnectionLost):
        if self._rtde is None:
            message = f"UrArm({self.host!r}) is closed"
            if error_type is SensorError:
                raise SensorError("read_failed", message)
            raise RobotConnectionLost(message, self.host)
        return self._rtde

    def _check(self, stamp: float, error_type) -> None:
        """Raise ``error_type`` when the connection is lost or ``stamp`` has stood still for
        ``stale_after`` (the staleness clock advances here).
        """
        now = time.monotonic()
        if not self._rtde.isConnected():
            message = (
                f"the RTDE connection to {self.host} is lost (ur_rtde's isConnected() is False)"
            )
            fault = "read_failed"
        elif stamp != self._last_stamp:
            self._last_stamp, self._stamp_changed_at = stamp, now
            return
        elif now - self._stamp_changed_at > self.stale_after:
            message = (
                f"no new RTDE package from {self.host} for {now - self._stamp_changed_at:.3f} s "
                f"(limit {self.stale_after:g} s): the controller's timestamp stands still at "
                f"{stamp:.3f} s"
            )
            fault = "stale"
        else:
            return
        if error_type is SensorError:
            raise SensorError(fault, message)
        raise RobotConnectionLost(message, self.host)

    def state(self) -> UrState:
        """The latest package: timestamp, joints, TCP pose and wrench, all of one package.

        The fields are read between two reads of the timestamp, and again when it changed in
        between (a newer package came). A package is read once; further calls before the next
        one return the same (read-only) arrays.

        Raises:
            RobotConnectionLost: the connection is lost, or the timestamp has stood still for
                ``stale_after``.
        """
        return self._read(RobotConnectionLost)

    def sample(self) -> tuple[float, np.ndarray, np.ndarray]:
        """``(timestamp [s], actual_q (6,) [rad], wrench (6,) [N, N·m] in the sensor frame)`` of
        one package (:meth:`state`): the wrist sensor's read.

        Raises:
            SensorError: ``"read_failed"`` for a lost connection, ``"stale"`` for a timestamp
                that has stood still for ``stale_after``.
        """
        state = self._read(SensorError)
        return state.timestamp, state.q, state.wrench_in_sensor

    def _read(self, error_type) -> UrState:
        rtde = self._connection(error_type)
        try:
            stamp = rtde.getTimestamp()
            self._check(stamp, error_type)
            if self._cached is not None and self._cached.timestamp == stamp:
                return self._cached
            for _ in range(3):
                q, dq = rtde.getActualQ(), rtde.getActualQd()
                pose, wrench = rtde.getActualTCPPose(), rtde.getFtRawWrench()
                latest = rtde.getTimestamp()
                if latest == stamp:
                    break
                stamp = latest  # a newer package came meanwhile: read that one
        except BaseException:
            # the traceback keeps this frame: it must not keep the interface alive (its
            # destructor takes 0.5 s, and would run wherever the traceback is dropped)
            del rtde
            raise
        q, raw = self._arrays(q, wrench)
        arrays = (q, np.array(dq, dtype=float), np.array(pose, dtype=float), raw)
        state = UrState(float(stamp), *arrays, self._in_sensor(q, raw))
        for array in (*arrays, state.wrench_in_sensor):
            array.flags.writeable = False
        self._cached = state
        return state

    def _arrays(self, q, wrench) -> tuple[np.ndarray, np.ndarray]:
        q, raw = np.array(q, dtype=float), np.array(wrench, dtype=float)
        if q.shape != (6,) or raw.shape != (6,):
            raise RobotConnectionLost(
                f"the RTDE package from {self.host} is incomplete (actual_q {q.shape}, "
                f"ft_raw_wrench {raw.shape})",
                self.host,
            )
        return q, raw

    def _in_sensor(self, q: np.ndarray, raw: np.ndarray) -> np.ndarray:
        if not np.all(np.isfinite(q)):
            return raw.copy()
        return wrench_in_sensor(q, raw, self.wrench_frame)

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        """``actual_q`` ``(6,)`` [rad] and ``actual_qd`` ``(6,)`` [rad/s] of one package.

        Raises:
            RobotConnectionLost: see :meth:`state`.
        """
        state = self.state()
        return state.q, state.dq

    def joint_positions(self) -> np.ndarray:
        """``actual_q`` ``(6,)`` [rad]."""
        return self.state().q

    def joint_velocities(self) -> np.ndarray:
        """``actual_qd`` ``(6,)`` [rad/s]."""
        return self.state().dq

    def flange_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """Rotation ``(3, 3)`` (flange to base) and position ``(3,)`` [m] from ``actual_TCP_pose``.

        This is the flange (``tool0``) only when the TCP offset set on the controller is zero.
        """
        pose = self.state().tcp_pose
        return rotation_from_vector(pose[3:]), pose[:3].copy()


class UrWristSensor:
    """The built-in wrist sensor of an e-Series arm, as a
    :class:`~ftkin.robot.protocols.ForceTorqueSensor` on ``ft_raw_wrench``.

    ``read()`` returns the controller's timestamp [s] (one new stamp per package) and the raw
    wrench in the sensor (flange) frame [N, N·m], bias and payload included;
    ``read_with_joints()`` also the package's ``actual_q``, so that a wrench and its joint angles
    are never from two packages. A lost connection raises ``SensorError("read_failed", ...)``, a
    timestamp that stands still for the arm's ``stale_after`` ``SensorError("stale", ...)``.
    """

    def __init__(self, arm: UrArm):
        self.arm = arm

    def __repr__(self) -> str:
        return f"UrWristSensor({self.arm.host!r}, wrench_frame={self.arm.wrench_frame!r})"

    def read(self) -> tuple[float, np.ndarray]:
        """``(timestamp [s], wrench (6,) [N, N·m] in the sensor frame)``."""
        stamp, _, wrench = self.arm.sample()
        return stamp, wrench

    def read_with_joints(self) -> tuple[float, np.ndarray, np.ndarray]:
        """``(timestamp [s], actual_q (6,) [rad], wrench (6,) [N, N·m])`` of one package."""
        return self.arm.sample()
