"""What ftkin needs from a robot and from a force/torque sensor: small protocols.

Any object with these methods works (structural typing, :class:`typing.Protocol`): ftkin ships
:class:`~ftkin.robot.franka.FrankaRobot` (franky-control), a simulated FR3
(:mod:`ftkin.robot.franka_sim`) and a read-only UR arm with its built-in sensor
(:class:`~ftkin.robot.ur.UrArm`, docs/other-robots.md); :mod:`ftkin.sensors` ships sensors (an
ATI Net F/T, a Bota Systems sensor). A :class:`JointStateSource` is the part of a robot that
``ftkin record`` reads from an arm it does not drive (:mod:`ftkin.robot.recorder`).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np


@runtime_checkable
class ForceTorqueSensor(Protocol):
    """A wrist force/torque sensor.

    ``read()`` returns the latest sample: its time stamp ``t`` [s] (monotonic; the same stamp
    twice means no new sample) and the raw wrench ``(6,)`` ``[fx, fy, fz, mx, my, mz]``
    [N, N·m] in the sensor frame, the load ON the sensor (ftkin's convention), bias included.
    It may raise on a driver error; ftkin treats that as a sensor fault.
    """

    def read(self) -> tuple[float, np.ndarray]: ...


@runtime_checkable
class JointStateSource(Protocol):
    """Where the joint state of an arm comes from, read-only.

    ``joint_state()`` returns the joint positions ``(nq,)`` [rad] and velocities ``(nq,)``
    [rad/s] of one state, in the arm model's joint order. A :class:`Robot` is one (reading it
    commands nothing), and so is a reader of a controller ftkin cannot command (UR's RTDE).
    Errors are ftkin's: :class:`~ftkin.exceptions.RobotConnectionLost` for a source that is
    gone or frozen.
    """

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]: ...


@runtime_checkable
class Robot(Protocol):
    """A robot arm ftkin can drive.

    * ``joint_state()``: joint positions ``(nq,)`` [rad] and velocities ``(nq,)`` [rad/s];
      ``joint_positions()`` and ``joint_velocities()`` each half of it;
    * ``move_to(q, while_moving=None)``: move to ``q`` [rad], speed-limited, return when done;
      call ``while_moving()`` regularly meanwhile (if it raises: stop the arm, raise it);
    * ``command_velocity(dq)``: joint velocities [rad/s], without waiting; the robot stops by
      itself (a watchdog) when the command is not renewed within its hold time;
    * ``stop()``: stop any motion now; never raises;
    * ``set_payload(calibration, **options)``: tell the controller the load (returns what was
      sent); ``payload()``: the load the controller reports, ``(mass [kg], com_flange (3,) [m],
      inertia_flange (3, 3) [kg·m²])``.

    Errors are ftkin's: :class:`~ftkin.exceptions.RobotError` and its
    :class:`~ftkin.exceptions.RobotConnectionLost`.
    """

    def joint_state(self) -> tuple[np.ndarray, np.ndarray]: ...

    def joint_positions(self) -> np.ndarray: ...

    def joint_velocities(self) -> np.ndarray: ...

    def move_to(self, q, while_moving=None) -> None: ...

    def command_velocity(self, dq) -> None: ...

    def stop(self) -> None: ...

    def set_payload(self, calibration, **options): ...

    def payload(self) -> tuple[float, np.ndarray, np.ndarray]: ...
