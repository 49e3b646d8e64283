"""Tell the robot controller its payload: Franka's ``SetLoad`` and UR's ``set_payload``.

The controller compensates the tool's weight in its own dynamics when told
the payload mass and centre of mass in its **flange** frame. ftkin knows the
centre of mass ``P`` in the real sensor frame; it is moved to the flange frame
through the mount and the URDF:

    P_F = R_FS · R_Mᵀ · P + t_FS

with ``(R_FS, t_FS)`` the URDF placement of the sensor frame in the flange
frame and ``R_M`` the estimated mount (identity if none). The flange frame is,
unless named, the first of :data:`FLANGE_FRAMES` the model has (``tool0`` for
UR, ``panda_link8`` for Franka, the bundled arm's ``flange``), else the frame
the sensor frame hangs from. The mass is the tool's ``G / g``: everything below
the sensor's measuring plane (the sensor's sensitive end included; the
sensor's own body above that plane is not seen by it and belongs to the robot
or must be added by hand).

Formats (:data:`PAYLOAD_FORMATS`):

``franka-load``
    The request of ``franka_msgs/srv/SetLoad`` (franka_ros2): ``mass`` [kg],
    ``center_of_mass`` [m, flange frame F] and ``load_inertia`` (3×3 about the
    centre of mass, flange axes, column-major, [kg·m²]); the same numbers as
    libfranka's ``Robot::setLoad(load_mass, F_x_Cload, load_inertia)`` (franka_ros 1
    calls the second field ``F_x_center_load``).
``ur-payload``
    The request of the ROS 2 UR driver's ``/io_and_status_controller/set_payload``
    service (``ur_msgs/srv/SetPayload``: ``mass`` [kg], ``center_of_gravity``
    ``{x, y, z}`` [m, tool flange frame ``tool0``]), with the URScript line
    ``set_payload(mass, [cx, cy, cz])`` as a comment; a ``.script`` output holds
    the URScript line alone.

A static calibration does not determine the inertia: it is written when given
(``inertia=``, CLI ``--inertia``), else as zeros (a point mass) with a note.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..calibration.model import SensorModel
from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from .atomic import atomic_write_text
from .yaml_text import yaml_text

PAYLOAD_FORMATS = ("franka-load", "ur-payload")
"""Robot-controller payload formats of :func:`payload_text`."""

FLANGE_FRAMES = ("tool0", "flange", "panda_link8", "fr3_link8")
"""Frames taken as the robot flange, in order of preference."""

UR_SET_PAYLOAD_SERVICE = "/io_and_status_controller/set_payload"
FRANKA_SET_LOAD_SERVICE = "/service_server/set_load"


@dataclass(frozen=True)
class Payload:
    """The tool as a robot controller's payload.

    Attributes:
        mass: Tool mass [kg].
        center_of_mass: Centre of mass in the flange frame [m].
        flange_frame: Name of that frame in the URDF.
        inertia: ``(3, 3)`` inertia about the centre of mass, flange axes [kg·m²], or None
        (unknown).
    """

    mass: float
    center_of_mass: np.ndarray
    flange_frame: str
    inertia: np.ndarray | None = None


def flange_frame_name(arm) -> str:
    """The arm's flange frame: the first of :data:`FLANGE_FRAMES` it has, else the sensor frame's
    parent frame.
    """
    for name in FLANGE_FRAMES:
        if arm.model.existFrame(name):
            return name
    return arm.model.frames[arm.model.frames[arm.sensor_frame_id].parentFrame].name


def sensor_in_flange(arm, flange_frame: str) -> pin.SE3:
    """URDF placement of the sensor frame in ``flange_frame`` (both must move with the same
    joint).
    """
    flange_id, sensor_id = arm.frame_id(flange_frame), arm.sensor_frame_id
    flange, sensor = arm.model.frames[flange_id], arm.model.frames[sensor_id]
    if flange.parentJoint != sensor.parentJoint:
        raise InvalidInput(
            f"the flange frame {flange_frame!r} and the sensor frame {arm.sensor_frame!r} are not "
            "fixed to each other "
            f"(they hang from joints {arm.model.names[flange.parentJoint]!r} and "
            f"{arm.model.names[sensor.parentJoint]!r})"
        )
    return flange.placement.inverse() * sensor.placement


def payload_in_flange(
    calibration: SensorModel, arm, flange_frame: str | None = None, inertia=None
) -> Payload:
    """The calibrated tool as a payload in the flange frame (see the module docstring).

    Args:
        calibration: A calibration (its mount, if any, is applied).
        arm: The arm **as its URDF describes it** (the sensor frame not mounted).
        flange_frame: Flange frame name (default: :func:`flange_frame_name`).
        inertia: ``(3, 3)`` inertia about the centre of mass in flange axes
            [kg·m²], or ``(6,)`` ``[ixx, iyy, izz, ixy, ixz, iyz]``; None: the
            calibration's own (a dynamic calibration's
            ``inertia_about_com_in_sensor``, turned into flange axes), else unknown.

    Raises:
        InvalidInput: no tool weight, a bad inertia, or a flange frame not fixed to the sensor.
        FrameNotFound: ``flange_frame`` is not in the model.
    """
    if arm.mount_rotation is not None:
        raise InvalidInput(
            "give the arm as its URDF describes it (not the mounted copy of a Compensator)"
        )
    calibration = CalibrationResult.from_model(calibration)
    mass = float(calibration.tool_mass)
    if not mass > 0.0:
        raise InvalidInput("the calibration has no tool weight: there is no payload to export")
    flange_frame = flange_frame or flange_frame_name(arm)
    placement = sensor_in_flange(arm, flange_frame)
    rotation_sensor_to_flange = placement.rotation @ calibration.mount_rotation.T
    com = (
        rotation_sensor_to_flange @ np.asarray(calibration.center_of_mass, dtype=float)
        + placement.translation
    )
    in_sensor = calibration.inertia_about_com_in_sensor
    if inertia is None and in_sensor is not None:
        inertia = (
            rotation_sensor_to_flange
            @ np.asarray(in_sensor, dtype=float)
            @ rotation_sensor_to_flange.T
        )
    return Payload(mass, com, flange_frame, _inertia(inertia))


def _inertia(value) -> np.ndarray | None:
    if value is None:
        return None
    array = np.asarray(value, dtype=float)
    if array.shape == (6,):
        ixx, iyy, izz, ixy, ixz, iyz = array
        array = np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])
    if array.shape != (3, 3) or not np.all(np.isfinite(array)) or not np.allclose(array, array.T):
        raise InvalidInput(
            "inertia must be a symmetric (3, 3) matrix or [ixx, iyy, izz, ixy, ixz, iyz] [kg·m²], "
            f"got {value!r}"
        )
    if np.linalg.eigvalsh(array)[0] < -1e-12:
        raise InvalidInput("inertia must be positive semidefinite")
    return array


def _numbers(values) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=float).reshape(-1)]


def payload_tree(payload: Payload, fmt: str) -> dict:
    """The service request of ``fmt`` as a dict (what :func:`payload_text` writes as YAML)."""
    if fmt not in PAYLOAD_FORMATS:
        raise InvalidInput(
            f"unknown payload format {fmt!r}; expected one of {', '.join(PAYLOAD_FORMATS)}"
        )
    com = _numbers(payload.center_of_mass)
    if fmt == "franka-load":
        inertia = np.zeros((3, 3)) if payload.inertia is None else payload.inertia
        return {
            "mass": float(payload.mass),
            "center_of_mass": com,
            "load_inertia": _numbers(inertia.T),
        }
    return {"mass": float(payload.mass), "center_of_gravity": dict(zip("xyz", com))}


def urscript_line(payload: Payload) -> str:
    """URScript ``set_payload(mass, [cx, cy, cz])`` [kg, m, tool flange frame]."""
    cx, cy, cz = _numbers(payload.center_of_mass)
    return f"set_payload({float(payload.mass)!r}, [{cx!r}, {cy!r}, {cz!r}])"


def payload_text(payload: Payload, fmt: str, urscript_only: bool = False) -> str:
    """The payload file of ``fmt`` (see the module docstring): YAML request with explanatory
    comments.
    """
    if urscript_only:
        if fmt != "ur-payload":
            raise InvalidInput("a URScript file is for --format ur-payload only")
        return (
            "# ftkin payload: mass [kg], centre of gravity [m] in the tool flange "
            f"frame\n{urscript_line(payload)}\n"
        )
    tree = payload_tree(payload, fmt)
    header = [
        f"# ftkin payload for {fmt}: centre of mass in the flange frame {payload.flange_frame!r} "
        "[m], mass [kg]"
    ]
    if fmt == "franka-load":
        header += [
            f"# franka_msgs/srv/SetLoad request (ros2 service call {FRANKA_SET_LOAD_SERVICE} "
            "franka_msgs/srv/SetLoad ...);",
            "# libfranka: robot.setLoad(mass, F_x_Cload = center_of_mass, load_inertia) "
            "(column-major 3x3 [kg*m^2])",
        ]
        if payload.inertia is None:
            header.append(
                "# NOTE: a static calibration does not determine the inertia: load_inertia is zero "
                "(point mass); "
                "give --inertia if known"
            )
    else:
        header += [
            f"# ur_msgs/srv/SetPayload request: ros2 service call {UR_SET_PAYLOAD_SERVICE} "
            "ur_msgs/srv/SetPayload "
            '"{mass: ..., center_of_gravity: {x: ..., y: ..., z: ...}}"',
            f"# URScript: {urscript_line(payload)}",
        ]
    return yaml_text(tree, [line.removeprefix("# ") for line in header])


def controller_payload(
    calibration, arm, fmt, flange_frame=None, inertia=None, end_effector=None, sensor_body=None
) -> Payload:
    """:func:`payload_in_flange`, minus ``end_effector`` plus ``sensor_body`` when given."""
    payload = payload_in_flange(calibration, arm, flange_frame, inertia)
    if end_effector is None and sensor_body is None:
        return payload
    if fmt != "franka-load":
        raise InvalidInput("--end-effector and --sensor-body go with --format franka-load")
    from .payload_inertia import controller_load  # it imports this module

    return controller_load(payload, end_effector, sensor_body)


def export_payload(
    calibration: SensorModel,
    arm,
    path,
    fmt: str,
    flange_frame: str | None = None,
    inertia=None,
    *,
    end_effector=None,
    sensor_body=None,
) -> Path:
    """Write the payload of ``calibration`` in ``fmt`` to ``path`` atomically (``.script``: URScript
    only).

    ``end_effector`` and ``sensor_body`` (``franka-load``; flange-frame
    :class:`~ftkin.io.payload_inertia.RigidBody`): write ``measured − end_effector +
    sensor_body``, the load for a controller that already models the end effector
    (:mod:`ftkin.io.payload_inertia`).
    """
    payload = controller_payload(
        calibration, arm, fmt, flange_frame, inertia, end_effector, sensor_body
    )
    urscript = Path(path).suffix.lower() in (".script", ".urscript")
    return atomic_write_text(Path(path), payload_text(payload, fmt, urscript_only=urscript))
