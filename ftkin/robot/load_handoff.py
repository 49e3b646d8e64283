"""From the load tracker to the robot's controller: the tool and the held load, kept up to date.

A :class:`~ftkin.control.load_events.LoadTracker` identifies what the gripper took, in the
sensor frame (docs/load.md). The controller models the payload it is told
(:meth:`~ftkin.robot.franka.FrankaRobot.set_payload`: the tool below the sensor, minus the
configured end effector, plus the sensor's own body); :class:`LoadHandoff` adds the held load to
it as one rigid body when a grasp settles, sends it again once turning the wrist has determined
the load's whole centre of mass, and goes back to the tool alone on a release.

Right after a grasp held at one orientation, the centre of mass along gravity is not known
(or, the arm having tilted by a fraction of a degree, known to metres): until its standard
error is below :data:`COM_STD_LIMIT` on every axis the load is sent with its centre of mass
across gravity only (the component along the present gravity direction removed), which gives the
controller the right gravity torque at that orientation.
"""

from __future__ import annotations

import logging

import numpy as np

from ..calibration.model import SensorModel
from ..control.load_estimator import LoadEstimate
from ..control.load_events import HOLDING, LoadTracker
from ..exceptions import InvalidInput
from ..io.payload_held_load import HeldLoad
from ..io.payload_inertia import Payload

logger = logging.getLogger(__name__)

SENT_KINDS = ("grasp", "release", "tool_change")
"""The tracker's events after which the controller's load changes."""

MASS_CHANGE = 0.01
"""The held load is sent again when its mass estimate moved by more than this share of the mass
sent (the first blocks after a grasp are few) [1]."""
CHECK_BLOCKS = 50
"""The held load's estimate is solved at most every this many blocks of the tracker (0.25 s of
its 5 ms blocks)."""

COM_STD_LIMIT = 0.002
"""A held load's centre of mass is sent whole once its standard error is below this on every
sensor axis [m]; until then across gravity only."""


def com_known(estimate: LoadEstimate | None) -> bool:
    """Whether ``estimate``'s centre of mass is known on every axis (within
    :data:`COM_STD_LIMIT`)."""
    return estimate is not None and bool(np.all(estimate.com_std < COM_STD_LIMIT))


def held_load_of(source, gravity_in_sensor=None) -> HeldLoad | None:
    """What ``source`` holds below the tool, in the sensor frame (None: nothing).

    Args:
        source: A :class:`~ftkin.control.load_events.LoadTracker`: its held load (the estimate's
            centre of mass when :func:`com_known`, else across ``gravity_in_sensor`` only) plus
            what tool changes added to the tool (``[m, m c]`` summed), or a
            :class:`~ftkin.control.load_estimator.LoadEstimate` (its centre of mass must be
            determined; its inertia is used when identified).
        gravity_in_sensor: ``(3,)`` gravity's direction in the sensor frame now (any length):
            needed for a tracker whose load's centre of mass is not yet known.

    Raises:
        InvalidInput: another type, an estimate with an undetermined centre of mass, or a
            tracker's load not known along gravity and no ``gravity_in_sensor``.
    """
    if isinstance(source, LoadTracker):
        first = source.tool_offset
        estimate = source.estimate()
        if estimate is not None:
            moment = estimate.mass * np.nan_to_num(estimate.com_in_sensor)
            if not com_known(estimate):
                if gravity_in_sensor is None:
                    raise InvalidInput(
                        "the held load's centre of mass is not known along gravity yet (turn the "
                        "wrist): give gravity_in_sensor to send it across gravity only"
                    )
                down = np.asarray(gravity_in_sensor, dtype=float)
                down = down / np.linalg.norm(down)
                moment = source.load_parameters[1:]
                moment = moment - (moment @ down) * down
            first = first + np.concatenate([[estimate.mass], moment])
        mass = float(first[0])
        if not mass > 0.0:
            return None
        return HeldLoad(mass, first[1:] / mass)
    if isinstance(source, LoadEstimate):
        inertia = None
        if source.inertial_parameters is not None and np.all(
            np.isfinite(source.inertial_parameters)
        ):
            ixx, ixy, iyy, ixz, iyz, izz = source.inertial_parameters[4:]
            about_origin = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
            c = source.com_in_sensor
            inertia = about_origin - source.mass * (float(c @ c) * np.eye(3) - np.outer(c, c))
        return HeldLoad(source.mass, source.com_in_sensor, inertia)
    raise InvalidInput(
        f"expected an ftkin LoadTracker or LoadEstimate, got {type(source).__name__}"
    )


class LoadHandoff:
    """Keep the robot's load equal to the tool plus what ``tracker`` holds.

    Call :meth:`update` with the joint positions after ticks of the tracker (e.g. from the
    control loop's ``on_tick``): it sends (:meth:`~ftkin.robot.franka.FrankaRobot.set_payload`)
    after each grasp, release or tool change the tracker decides, again when the held load's
    mass estimate has moved by more than :data:`MASS_CHANGE` from the one sent, and once more
    when its centre of mass becomes known on every axis (:func:`com_known`).

    Args:
        robot: Anything with ``set_payload(calibration, held_load=..., **options)`` (a
            :class:`~ftkin.robot.franka.FrankaRobot`).
        calibration: The calibration the tracker's compensation uses.
        tracker: The :class:`~ftkin.control.load_events.LoadTracker`.
        arm: The arm the compensation uses (the sensor's orientation from the joints).
        **options: :meth:`~ftkin.robot.franka.FrankaRobot.set_payload`'s (``end_effector``,
            ``sensor_mass``, ``sensor_com``).

    Attributes:
        sent: ``(why, Payload)`` of each load sent (``why``: the event's kind, ``"mass"`` or
            ``"com"``).
    """

    def __init__(self, robot, calibration: SensorModel, tracker: LoadTracker, arm, **options):
        if not isinstance(tracker, LoadTracker):
            raise InvalidInput(f"tracker must be an ftkin LoadTracker, got {tracker!r}")
        if not callable(getattr(robot, "set_payload", None)):
            raise InvalidInput(f"the robot takes no payload (no set_payload): {robot!r}")
        self.robot, self.calibration, self.tracker = robot, calibration, tracker
        self.arm, self.options = arm, options
        self.sent: list[tuple[str, Payload]] = []
        self._seen = len(tracker.events)
        self._version = tracker.version
        self._com_sent = False
        self._mass_sent = 0.0

    def send(self, why: str, q) -> Payload:
        """Send the tool and the held load now, the joints at ``q`` ``(nq,)`` [rad] (``why`` is
        recorded in :attr:`sent`)."""
        rotation = self.arm.rotation_sensor_to_base(np.asarray(q, dtype=float)[None])[0]
        down = rotation.T @ np.asarray(self.tracker.gravity_in_base)
        held = held_load_of(self.tracker, down)
        estimate = self.tracker.estimate()  # the held load alone (a tool change's is the tool's)
        self._mass_sent = 0.0 if estimate is None else estimate.mass
        payload = self.robot.set_payload(
            self.calibration, arm=self.arm, held_load=held, **self.options
        )
        self.sent.append((why, payload))
        logger.info("sent the load after %s: %.4g kg", why, payload.mass)
        return payload

    def update(self, q) -> Payload | None:
        """Send when the tracker's load changed as described above (the joints at ``q``
        ``(nq,)`` [rad]); the load sent, else None."""
        tracker = self.tracker
        events = tracker.events
        new = [event for event in events[self._seen :] if event.kind in SENT_KINDS]
        self._seen = len(events)
        if new:
            self._com_sent = False
            self._version = tracker.version
            return self.send(new[-1].kind, q)
        if tracker.state != HOLDING or tracker.version - self._version < CHECK_BLOCKS:
            return None
        self._version = tracker.version
        estimate = tracker.estimate()
        if not self._com_sent and com_known(estimate):
            self._com_sent = True
            return self.send("com", q)
        if abs(estimate.mass - self._mass_sent) > MASS_CHANGE * max(self._mass_sent, 1e-3):
            return self.send("mass", q)
        return None


MOVING_SPEED = 0.005
"""A joint faster than this moves the arm, for :class:`MotionFlag` [rad/s]."""
SETTLE_TIME = 0.15
"""The arm counts as moving this long after its joints slowed below :data:`MOVING_SPEED` [s]."""


class MotionFlag:
    """Set a tracker's ``moving`` from the joint velocities, so that only readings held still
    join the load's estimate (a static compensation leaves the arm's inertial wrench in them).

    Args:
        tracker: The :class:`~ftkin.control.load_events.LoadTracker`.
        speed: :data:`MOVING_SPEED` [rad/s].
        settle: :data:`SETTLE_TIME` [s].
    """

    def __init__(self, tracker: LoadTracker, speed: float = MOVING_SPEED, settle=SETTLE_TIME):
        if not isinstance(tracker, LoadTracker):
            raise InvalidInput(f"tracker must be an ftkin LoadTracker, got {tracker!r}")
        self.tracker, self.speed, self.settle = tracker, float(speed), float(settle)
        self._moved_at = -np.inf

    def update(self, now: float, joint_velocities) -> bool:
        """Mark the tracker moving or still at ``now`` [s] from ``joint_velocities`` ``(nq,)``
        [rad/s] (measured or commanded); returns the flag."""
        if np.max(np.abs(np.asarray(joint_velocities, dtype=float)), initial=0.0) > self.speed:
            self._moved_at = now
        self.tracker.moving = now - self._moved_at < self.settle
        return self.tracker.moving
