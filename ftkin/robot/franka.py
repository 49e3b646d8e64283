"""A Franka FR3 (or Panda) through franky-control, as a :class:`~ftkin.robot.protocols.Robot`.

franky (``pip install -e '.[franka]'``) bundles libfranka and talks to the robot's FCI, or to
franky-sim on localhost. libfranka refuses to run its control thread without real-time
scheduling unless told to ignore it: ``realtime=False`` maps to ``RealtimeConfig.Ignore`` (for a
simulator or a kernel without ``PREEMPT_RT``; on a real arm a control loop without it may miss
its 1 kHz deadlines and the robot stops with a communication-constraints error).

Every franky exception is turned into ftkin's: :class:`~ftkin.exceptions.RobotConnectionLost`
(network, server gone), :class:`~ftkin.exceptions.RealtimeUnavailable`, or
:class:`~ftkin.exceptions.RobotError` (a refused command, a reflex, a control error; the robot's
errors are cleared with ``recover_from_errors`` so the next command can run).
"""

from __future__ import annotations

import logging
import os
import signal
import threading
import time
from contextlib import contextmanager, suppress

import numpy as np

from ..calibration.model import SensorModel
from ..exceptions import (
    FtkinError,
    InvalidInput,
    MissingDependency,
    RealtimeUnavailable,
    RobotConnectionLost,
    RobotError,
)
from ..io.export import arm_problems, recorded_arm
from ..io.payload_export import payload_in_flange, with_held_load
from ..io.payload_held_load import HeldLoad
from ..io.payload_inertia import Payload, RigidBody, controller_load
from ..validation import as_vector

logger = logging.getLogger(__name__)

END_EFFECTOR_SETTING = (
    "the end effector configured on the robot (Desk > Settings > End effector; libfranka m_ee, "
    "F_x_Cee, I_ee)"
)


def import_franky():
    """The ``franky`` module, or :class:`MissingDependency` naming the ``franka`` extra."""
    try:
        import franky
    except ImportError as error:
        raise MissingDependency(
            "franky-control", "franka", "driving a Franka robot (FR3, Panda)"
        ) from error
    return franky


@contextmanager
def calling_thread_scheduling_kept():
    """Restore the calling thread's scheduling policy and priority on exit.

    libfranka raises the thread that creates a robot to ``SCHED_FIFO`` 99 whenever it may (as
    root, even with ``RealtimeConfig.Ignore``). For ftkin's Python thread that is harmful: every
    process it starts afterwards (a browser for a screenshot, a simulator) inherits the policy,
    and a busy child at FIFO 99 starves the machine. franky's control loops raise their own
    threads, so the calling thread keeps the policy it had.
    """
    try:
        policy, param = os.sched_getscheduler(0), os.sched_getparam(0)
    except (AttributeError, OSError):  # not Linux: nothing to keep
        yield
        return
    try:
        yield
    finally:
        with suppress(OSError):
            if os.sched_getscheduler(0) != policy:
                os.sched_setscheduler(0, policy, param)


class watching_interrupts:
    """Note a Ctrl-C (SIGINT) that reaches the process inside the block, then raise it as usual.

    franky catches the KeyboardInterrupt raised inside ``join_motion`` and reports a preempted
    motion (``ControlException``); :attr:`fired` tells the two apart. Off the main thread (where
    Python delivers no signal) it does nothing.
    """

    def __init__(self):
        self.fired = False
        self._previous = None

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.getsignal(signal.SIGINT)
            signal.signal(signal.SIGINT, self._handler)
        return self

    def _handler(self, signum, frame):
        self.fired = True
        if callable(self._previous):
            self._previous(signum, frame)
        elif self._previous != signal.SIG_IGN:
            raise KeyboardInterrupt

    def __exit__(self, *exc):
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)
        return False


class FrankaRobot:
    """A Franka arm through franky-control.

    Args:
        host: The robot's FCI address (a franky-sim server: its loopback address).
        realtime: Require real-time scheduling (libfranka's default). False:
            ``RealtimeConfig.Ignore``, for simulators and kernels without it.
        speed: franky's relative dynamics factor for :meth:`move_to` (0–1]: the fraction of the
            velocity, acceleration and jerk limits used.
        watchdog: A velocity command is held this long [s] unless renewed, then the arm stops
            (franky ``JointVelocityMotion`` duration, whole milliseconds).
        poll_period: Sleep between checks while :meth:`move_to` waits [s] (Ctrl-C is answered
            within it).
        move_timeout: :meth:`move_to` gives up (stops the arm, raises) after this long [s].
        state_timeout: :meth:`joint_state` raises :class:`RobotConnectionLost` when the robot's
            clock has not advanced for this long [s] (libfranka itself notices after ~2 s).

    Raises:
        MissingDependency: franky-control is not installed.
        RealtimeUnavailable: ``realtime=True`` on a kernel without real-time scheduling.
        RobotConnectionLost: nothing answers at ``host``.
    """

    nq = 7
    controller = "franka"
    """The controller family: libfranka takes the load in the flange ``<prefix>_link8``
    (:data:`ftkin.kinematics.robots.CONTROLLERS`)."""

    def __init__(
        self,
        host: str,
        *,
        realtime: bool = True,
        speed: float = 0.3,
        watchdog: float = 0.05,
        poll_period: float = 0.005,
        move_timeout: float = 60.0,
        state_timeout: float = 0.1,
    ):
        if not isinstance(host, str) or not host.strip():
            raise InvalidInput(f"host must be the robot's address, got {host!r}")
        numbers = as_vector(
            [speed, watchdog, poll_period, move_timeout, state_timeout], 5, "robot timing"
        )
        if not 0.0 < speed <= 1.0 or np.any(numbers[1:] <= 0.0) or watchdog < 0.001:
            raise InvalidInput(
                "speed must be in (0, 1], watchdog >= 0.001 s, poll_period, move_timeout and "
                f"state_timeout > 0 s; got speed={speed!r}, watchdog={watchdog!r}, "
                f"poll_period={poll_period!r}, move_timeout={move_timeout!r}, "
                f"state_timeout={state_timeout!r}"
            )
        self.host = host
        self._franky = franky = import_franky()
        config = franky.RealtimeConfig.Enforce if realtime else franky.RealtimeConfig.Ignore
        try:
            with calling_thread_scheduling_kept():
                self._robot = franky.Robot(host, realtime_config=config)
        except franky.RealtimeException as error:
            raise RealtimeUnavailable(
                "this kernel has no real-time scheduling and FrankaRobot(realtime=True) asked for "
                "it: use a PREEMPT_RT kernel on the real robot, or pass realtime=False "
                "(--no-realtime) for a simulator",
                host,
                str(error),
            ) from None
        except Exception as error:  # NetworkException and libfranka's others
            raise self._wrap(error, f"cannot connect to the robot at {host}") from None
        self._robot.relative_dynamics_factor = float(speed)
        self._watchdog = franky.Duration(max(1, round(watchdog * 1000)))
        self.watchdog, self.poll_period, self.move_timeout = (
            float(watchdog),
            float(poll_period),
            float(move_timeout),
        )
        self.state_timeout = float(state_timeout)
        self._robot_time, self._state_at = -1, time.monotonic()
        self._polled_at = self._state_at

    def __repr__(self) -> str:
        return f"FrankaRobot({self.host!r})"

    # -------------------------------------------------------------- errors
    def _wrap(self, error: BaseException, doing: str) -> RobotError:
        franky = self._franky
        text = str(error)
        lost = ("UDP", "TCP", "Net Exception", "onnection")
        if isinstance(error, franky.NetworkException) or any(word in text for word in lost):
            return RobotConnectionLost(f"{doing}: the connection is lost", self.host, text)
        return RobotError(f"{doing}: the robot refused", self.host, text)

    def _failed(self, error: BaseException, doing: str) -> RobotError:
        """``error`` of franky as an ftkin error, after recovering the robot when it can be.

        A lost connection is not recovered: there is nothing to recover, and asking (reading
        ``has_errors``) blocks for libfranka's 1 s network timeout before it fails, which delayed
        the stop of a session by that second.
        """
        wrapped = self._wrap(error, doing)
        if not isinstance(wrapped, RobotConnectionLost):
            self._recover()
        return wrapped

    def _recover(self) -> None:
        try:
            if self._robot.has_errors:
                self._robot.recover_from_errors()
        except Exception as error:  # the connection may be gone as well: nothing more to do
            logger.debug("recover_from_errors failed: %s", error)

    # -------------------------------------------------------------- state
    def joint_state(self) -> tuple[np.ndarray, np.ndarray]:
        """Joint positions ``(7,)`` [rad] and velocities ``(7,)`` [rad/s], one state.

        Raises:
            RobotConnectionLost: the robot's clock has not advanced for ``state_timeout`` (no
                state arrives: the robot or its server is gone) or the connection failed.
        """
        try:
            state = self._robot.state
        except Exception as error:
            raise self._wrap(error, "reading the joint state") from None
        now, robot_time = time.monotonic(), state.time.to_msec()
        if now - self._polled_at > self.state_timeout:
            # we did not ask for a while (a fit, a print): the robot's clock is judged from now
            # on, not blamed for our absence (franky's state is the last motion's while idle)
            self._state_at = now
        self._polled_at = now
        if robot_time != self._robot_time:
            self._robot_time, self._state_at = robot_time, now
        elif now - self._state_at > self.state_timeout:
            raise RobotConnectionLost(
                f"no new state from the robot for {now - self._state_at:.3f} s (limit "
                f"{self.state_timeout:g} s): the robot or its server is gone",
                self.host,
            )
        return np.array(state.q, dtype=float), np.array(state.dq, dtype=float)

    def joint_positions(self) -> np.ndarray:
        """Joint positions ``(7,)`` [rad]."""
        return self.joint_state()[0]

    def joint_velocities(self) -> np.ndarray:
        """Joint velocities ``(7,)`` [rad/s]."""
        return self.joint_state()[1]

    # -------------------------------------------------------------- motion
    def move_to(self, q, while_moving=None) -> None:
        """Move to ``q`` ``(7,)`` [rad] and return when the motion is done (speed-limited).

        The motion runs asynchronously and is polled every ``poll_period``: the robot's state
        is checked (:meth:`joint_state`: a robot that stops sending state is a lost
        connection), ``while_moving()`` is called if given (an exception from it stops the arm
        and is raised: e.g. a sensor fault), and Ctrl-C stops the arm.

        Raises:
            RobotError: the robot refused or aborted the motion (the arm is stopped).
            RobotConnectionLost: the connection dropped.
        """
        target = as_vector(q, self.nq, "target joint positions q [rad]")
        franky = self._franky
        with watching_interrupts() as interrupt:
            try:
                self._move_to(franky, target, while_moving)
            except KeyboardInterrupt:
                raise
            except Exception:  # franky turns Ctrl-C during a motion into a preempted motion
                if interrupt.fired:
                    self.stop()
                    raise KeyboardInterrupt from None
                raise

    def _move_to(self, franky, target: np.ndarray, while_moving) -> None:
        try:
            self._robot.move(franky.JointMotion(franky.JointState(target)), asynchronous=True)
            deadline = time.monotonic() + self.move_timeout
            # join with a timeout, not poll_motion: a motion whose robot vanished counts as
            # finished for poll_motion while join_motion waits for libfranka's timeout
            while not self._robot.join_motion(timeout=self.poll_period):
                if time.monotonic() > deadline:
                    raise TimeoutError(f"the motion took longer than {self.move_timeout:g} s")
                self.joint_state()
                if while_moving is not None:
                    while_moving()
        except (KeyboardInterrupt, FtkinError):
            self.stop()
            raise
        except TimeoutError as error:
            self.stop()
            doing = f"moving to {target.round(3).tolist()}"
            raise RobotError(doing, self.host, str(error)) from None
        except Exception as error:
            raise self._failed(error, f"moving to {np.round(target, 3).tolist()}") from None

    def command_velocity(self, dq) -> None:
        """Command joint velocities ``(7,)`` [rad/s] without waiting; held for ``watchdog``.

        Each call replaces the previous command; when calls stop, the arm stops after
        ``watchdog`` (franky decelerates within its limits).
        """
        franky = self._franky
        try:
            self._robot.move(
                franky.JointVelocityMotion(np.asarray(dq, dtype=float), duration=self._watchdog),
                asynchronous=True,
            )
        except Exception as error:
            raise self._failed(error, "commanding joint velocities") from None

    def stop(self) -> None:
        """Stop the running motion (a no-op when none runs); never raises.

        Errors are logged: ``stop`` is what a failure path calls, and must not hide the failure.
        """
        try:
            self._robot.stop()
        except Exception as error:
            logger.warning("stopping %s: %s", self.host, error)
            return
        try:
            self._robot.join_motion(timeout=1.0)
        except Exception as error:  # "Move command preempted!" is the stop itself
            logger.debug("after stop: %s", error)
        self._recover()

    # -------------------------------------------------------------- payload
    def end_effector(self) -> RigidBody:
        """The end effector configured on the robot (``m_ee``, ``F_x_Cee``, ``I_ee``; flange)."""
        try:
            state = self._robot.state
        except Exception as error:
            raise self._wrap(error, "reading the robot state") from None
        return RigidBody.from_franka(
            float(state.m_ee),
            np.asarray(state.F_x_Cee, dtype=float),
            np.asarray(state.I_ee, dtype=float).reshape(-1),
        )

    def set_payload(
        self,
        calibration: SensorModel,
        *,
        arm=None,
        end_effector: RigidBody | None = None,
        sensor_mass: float = 0.0,
        sensor_com=(0.0, 0.0, 0.0),
        inertia=None,
        allow_other_arm: bool = False,
        held_load: HeldLoad | None = None,
    ) -> Payload:
        """Send the load below the sensor, minus the configured end effector, to the robot.

        ``load = measured − end effector + sensor body`` as rigid bodies in the flange frame
        (:func:`~ftkin.io.payload_inertia.controller_load`; see docs/robot.md for why nothing
        may be counted twice), sent with franky's ``set_load``.

        Args:
            calibration: The calibration (its tool mass and centre of mass).
            arm: The arm the calibration was made with (default: the one it records, else the
                bundled FR3, sensor at the hand frame).
            end_effector: What the controller already models; default: what the robot reports
                (``m_ee``, ``F_x_Cee``, ``I_ee``).
            sensor_mass: The sensor's own mass above its measuring plane [kg] (datasheet).
            sensor_com: Its centre of mass in the flange frame [m].
            inertia: The measured load's inertia about its centre of mass, flange axes
                [kg·m²] (default: the calibration's, if dynamic, else a point mass).
            allow_other_arm: Accept an ``arm`` other than the one the calibration recorded
                (another robot, URDF or sensor offset), as ``ftkin export --allow-other-arm``.
            held_load: A load the gripper holds below the tool (sensor frame; e.g.
                :func:`~ftkin.robot.load_handoff.held_load_of` a load tracker), added to the
                tool as one rigid body (:func:`~ftkin.io.payload_held_load.combined_payload`);
                None: the tool alone (:meth:`set_load_from` does this from a tracker).

        Returns:
            The load sent (flange frame).

        Raises:
            NonPhysicalPayload: the difference is not a body (names the end-effector setting).
            InvalidInput: ``arm`` differs from the calibration's (the centre of mass would be off
                by the sensor offset), or a negative sensor mass.
            RobotError: the robot refused the load.
        """
        if arm is None:
            arm = recorded_arm(calibration)
        if arm is None:
            from ..kinematics.fr3 import fr3_arm

            arm = fr3_arm()
        problems = [] if allow_other_arm else arm_problems(calibration, arm)
        if problems:
            raise InvalidInput(
                "the arm differs from the one the calibration was made with: "
                + "; ".join(problems)
                + ". Pass the calibration's arm, or allow_other_arm=True if that is deliberate"
            )
        measured = payload_in_flange(calibration, arm, None, inertia, self.controller)
        if end_effector is None:
            end_effector = self.end_effector()
        sensor_body = RigidBody.point(sensor_mass, sensor_com)  # refuses a negative mass
        load = controller_load(measured, end_effector, sensor_body, setting=END_EFFECTOR_SETTING)
        load = with_held_load(load, calibration, arm, held_load)
        body = RigidBody(
            load.mass,
            load.center_of_mass,
            np.zeros((3, 3)) if load.inertia is None else load.inertia,
        )
        try:
            self._robot.set_load(body.mass, body.center_of_mass.tolist(), body.franka_inertia())
        except Exception as error:
            raise self._failed(error, f"setting the load ({body.mass:.4g} kg)") from None
        deadline = time.monotonic() + 1.0  # the next states report it
        while abs(self.payload()[0] - body.mass) > 1e-6 * max(1.0, body.mass):
            if time.monotonic() > deadline:
                logger.warning("the robot does not report the load sent yet")
                break
            time.sleep(self.poll_period)
        logger.info(
            "sent the load %.4g kg at %s m (flange frame) to %s",
            body.mass,
            np.round(body.center_of_mass, 4).tolist(),
            self.host,
        )
        return load

    def set_load_from(self, tracker, calibration: SensorModel, **options) -> Payload:
        """Send the tool and what ``tracker`` holds now (the tool alone when it holds nothing).

        Args:
            tracker: A :class:`~ftkin.control.load_events.LoadTracker` (its load, and what tool
                changes added to the tool), or a :class:`~ftkin.control.load_estimator.
                LoadEstimate` (its centre of mass must be determined).
            calibration: The calibration the tracker's compensation uses.
            **options: Those of :meth:`set_payload` (``arm``, ``end_effector``,
                ``sensor_mass``, ...).

        A held load's centre of mass not yet known along gravity (held at one orientation) is
        sent across the present gravity direction only
        (:func:`~ftkin.robot.load_handoff.held_load_of`).

        Returns:
            The load sent (flange frame).
        """
        from .load_handoff import held_load_of  # the control layer's types, on first use

        arm = options.pop("arm", None) or recorded_arm(calibration)
        if arm is None:
            from ..kinematics.fr3 import fr3_arm

            arm = fr3_arm()
        rotation = arm.rotation_sensor_to_base(self.joint_positions()[None])[0]
        down = rotation.T @ np.asarray(calibration.gravity_in_base, dtype=float)  # the weight's
        held = held_load_of(tracker, down)
        return self.set_payload(calibration, arm=arm, held_load=held, **options)

    def payload(self) -> tuple[float, np.ndarray, np.ndarray]:
        """The load the robot reports: ``(mass [kg], com_flange (3,) [m], inertia_flange (3, 3)
        [kg·m²])`` (libfranka ``m_load``, ``F_x_Cload``, ``I_load``; float32 on the wire).
        """
        try:
            state = self._robot.state
        except Exception as error:
            raise self._wrap(error, "reading the robot state") from None
        inertia = np.asarray(state.I_load, dtype=float).reshape(3, 3)
        return (
            float(state.m_load),
            np.asarray(state.F_x_Cload, dtype=float).reshape(3),
            0.5 * (inertia + inertia.T),
        )
