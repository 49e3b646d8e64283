"""Tell the robot controller its payload: Franka's ``SetLoad`` and UR's ``set_payload``.

The controller compensates the tool's weight in its own dynamics when told
the payload mass and centre of mass in its **flange** frame. ftkin knows the
centre of mass ``P`` in the real sensor frame; it is moved to the flange frame
through the mount and the URDF:

    P_F = R_FS · R_Mᵀ · P + t_FS

with ``(R_FS, t_FS)`` the URDF placement of the sensor frame in the flange
frame and ``R_M`` the estimated mount (identity if none). The flange frame is the frame the
robot's controller takes the payload in, never guessed
(:func:`ftkin.kinematics.robots.flange_frame_name`): the robot table's for a robot loaded by
name (``fr3_link8`` for the FR3, ``panda_link8`` for the Panda, ``tool0`` for a UR, the bundled
arm's ``flange``); for an arm from a URDF, the one frame that follows the format's controller
rule (``<prefix>_link8`` for ``franka-load``, ``tool0`` for ``ur-payload``); else it must be
named (``flange_frame=``, ``--flange-frame``). The mass is the tool's ``G / g``: everything below
the sensor's measuring plane (the sensor's sensitive end included; the
sensor's own body above that plane is not seen by it and belongs to the robot
or must be added by hand).

Formats (registered in :mod:`ftkin.io.export`):

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

import numpy as np
import pinocchio as pin

from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from ..kinematics.robots import flange_frame_name
from ..options import number
from ..validation import as_float_array
from .export_format import ExportFormat, ExportOption, ExportRequest
from .payload_held_load import HeldLoad, combined_payload, read_held_load
from .payload_inertia import Payload, RigidBody, checked_inertia, controller_load

UR_SET_PAYLOAD_SERVICE = "/io_and_status_controller/set_payload"
FRANKA_SET_LOAD_SERVICE = "/service_server/set_load"

FLANGE_FRAME = ExportOption(
    "flange_frame",
    "--flange-frame",
    "the frame the robot's controller takes the payload in (default: the robot table's, e.g. "
    "fr3_link8, tool0; for a URDF the one frame named as the format's controller names it: "
    "<prefix>_link8 for franka-load, tool0 for ur-payload)",
    {"metavar": "NAME"},
)
INERTIA = ExportOption(
    "inertia",
    "--inertia",
    "tool inertia about its centre of mass in flange axes [kg·m²] (default: a dynamic "
    "calibration's, else unknown, written as zero)",
    {"type": number(), "nargs": 6, "metavar": ("IXX", "IYY", "IZZ", "IXY", "IXZ", "IYZ")},
)

END_EFFECTOR = ExportOption(
    "end_effector",
    "--end-effector",
    "subtract the end effector the controller already models (libfranka m_ee, F_x_Cee) "
    "[kg, m, flange frame]",
    {"type": number(), "nargs": 4, "metavar": ("MASS", "CX", "CY", "CZ")},
)
SENSOR_BODY = ExportOption(
    "sensor_body",
    "--sensor-body",
    "add the sensor's own body above its measuring plane (datasheet) [kg, m, flange frame]",
    {"type": number(), "nargs": 4, "metavar": ("MASS", "CX", "CY", "CZ")},
)
HELD_LOAD = ExportOption(
    "held_load",
    "--held-load",
    'add a load the gripper holds below the tool: its JSON {"mass": KG, "center_of_mass": '
    "[X, Y, Z]} (sensor frame, m; e.g. what ftkin's load tracker identified), combined with the "
    "tool as one rigid body",
    {"metavar": "LOAD.json"},
)


def sensor_in_flange(arm, flange_frame: str) -> pin.SE3:
    """URDF placement of the sensor frame in ``flange_frame`` (both must move with the same
    joint).
    """
    flange_id, sensor_id = arm.frame_id(flange_frame), arm.sensor_frame_id
    flange, sensor = arm.model.frames[flange_id], arm.model.frames[sensor_id]
    if flange.parentJoint != sensor.parentJoint:
        raise InvalidInput(
            f"the flange frame {flange_frame!r} and the sensor frame {arm.sensor_frame!r} are not "
            f"fixed to each other (they hang from joints {arm.model.names[flange.parentJoint]!r} "
            f"and {arm.model.names[sensor.parentJoint]!r})"
        )
    return flange.placement.inverse() * sensor.placement


def payload_in_flange(
    calibration, arm, flange_frame: str | None = None, inertia=None, controller: str | None = None
) -> Payload:
    """The calibrated tool as a payload in the flange frame (see the module docstring).

    Args:
        calibration: A calibration (its mount, if any, is applied).
        arm: The arm **as its URDF describes it** (the sensor frame not mounted).
        flange_frame: Flange frame name (default:
            :func:`~ftkin.kinematics.robots.flange_frame_name` of ``arm`` and ``controller``).
        inertia: ``(3, 3)`` inertia about the centre of mass in flange axes
            [kg·m²], or ``(6,)`` ``[ixx, iyy, izz, ixy, ixz, iyz]``; None: the
            calibration's own (a dynamic calibration's
            ``inertia_about_com_in_sensor``, turned into flange axes), else unknown.
        controller: The controller family the payload is for (``"franka"``, ``"ur"``: a key of
            :data:`~ftkin.kinematics.robots.CONTROLLERS`): its rule finds the flange of a URDF
            arm, and a named robot of another family is refused.

    Raises:
        InvalidInput: no tool weight, a bad inertia, a flange frame not fixed to the sensor, or
            a flange frame that is not known (name it).
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
    flange_frame = flange_frame or flange_frame_name(arm, controller)
    placement = sensor_in_flange(arm, flange_frame)
    sensor_to_flange = placement.rotation @ calibration.mount_rotation.T
    com = sensor_to_flange @ np.asarray(calibration.center_of_mass, dtype=float)
    in_sensor = calibration.inertia_about_com_in_sensor
    if inertia is None and in_sensor is not None:
        inertia = sensor_to_flange @ np.asarray(in_sensor, dtype=float) @ sensor_to_flange.T
    return Payload(mass, com + placement.translation, flange_frame, checked_inertia(inertia))


def held_load_in_flange(calibration, arm, held: HeldLoad, flange_frame: str) -> RigidBody:
    """A held load (sensor frame) as a rigid body in ``flange_frame``.

    Its centre of mass moves as the tool's does (``P_F = R_FS · R_Mᵀ · P + t_FS``, the module
    docstring); its inertia turns with the axes (a point mass when not given).
    """
    if not isinstance(held, HeldLoad):
        raise InvalidInput(f"held must be an ftkin HeldLoad, got {type(held).__name__}")
    calibration = CalibrationResult.from_model(calibration)
    placement = sensor_in_flange(arm, flange_frame)
    sensor_to_flange = placement.rotation @ calibration.mount_rotation.T
    com = sensor_to_flange @ held.center_of_mass + placement.translation
    inertia = np.zeros((3, 3)) if held.inertia is None else held.inertia
    return RigidBody(held.mass, com, sensor_to_flange @ inertia @ sensor_to_flange.T)


def with_held_load(payload: Payload, calibration, arm, held) -> Payload:
    """``payload`` (flange frame) and the held load as one rigid body (None: ``payload``).

    ``held``: a :class:`~ftkin.io.payload_held_load.HeldLoad` or the path of its JSON.
    """
    if held is None:
        return payload
    if not isinstance(held, HeldLoad):
        held = read_held_load(held)
    body = held_load_in_flange(calibration, arm, held, payload.flange_frame)
    return combined_payload(payload, body)


def _body(value):
    """A :class:`~ftkin.io.payload_inertia.RigidBody`, or ``[mass, cx, cy, cz]`` [kg, m, flange
    frame] as a point mass; None stays None.
    """
    if value is None or isinstance(value, RigidBody):
        return value
    numbers = as_float_array(value, "a body [mass, cx, cy, cz]")
    if numbers.shape != (4,):
        raise InvalidInput(
            f"a body must be [mass, cx, cy, cz] [kg, m, flange frame], got shape {numbers.shape}"
        )
    return RigidBody.point(numbers[0], numbers[1:])


def _numbers(values) -> list[float]:
    return [float(v) for v in np.asarray(values, dtype=float).reshape(-1)]


class PayloadFormat(ExportFormat):
    """A robot controller's payload request: the tool in the flange frame (``header_lines``:
    how to send it).
    """

    needs_arm = True
    options = (FLANGE_FRAME,)
    header_lines: tuple[str, ...] = ()
    controller: str | None = None
    """The controller family the format is for (its flange rule)."""

    def tool_payload(self, request: ExportRequest) -> Payload:
        """The request's calibration (the tool) as a payload in the flange frame."""
        return payload_in_flange(
            request.calibration,
            request.arm,
            request.option("flange_frame"),
            request.option("inertia"),
            self.controller,
        )

    def payload(self, request: ExportRequest) -> Payload:
        """:meth:`tool_payload` and the held load (``held_load``), when given, as one body."""
        tool = self.tool_payload(request)
        return with_held_load(tool, request.calibration, request.arm, request.option("held_load"))

    def header(self, request: ExportRequest) -> list[str]:
        return [
            f"ftkin payload for {self.name}: centre of mass in the flange frame "
            f"{self.payload(request).flange_frame!r} [m], mass [kg]",
            *self.header_lines,
        ]

    def summary_line(self, request: ExportRequest) -> str:
        payload = self.payload(request)
        com = ", ".join(f"{value:.6g}" for value in payload.center_of_mass)
        return (
            f": mass {payload.mass:.6g} kg, centre of mass [{com}] m in the flange frame "
            f"{payload.flange_frame!r}"
        )


class FrankaLoadExport(PayloadFormat):
    name = "franka-load"
    controller = "franka"
    options = (FLANGE_FRAME, INERTIA, END_EFFECTOR, SENSOR_BODY, HELD_LOAD)
    summary = "franka_msgs/srv/SetLoad request: mass, center_of_mass, load_inertia"
    header_lines = (
        f"franka_msgs/srv/SetLoad request (ros2 service call {FRANKA_SET_LOAD_SERVICE} "
        "franka_msgs/srv/SetLoad ...);",
        "libfranka: robot.setLoad(mass, F_x_Cload = center_of_mass, load_inertia) "
        "(column-major 3x3 [kg*m^2])",
    )

    def tool_payload(self, request: ExportRequest) -> Payload:
        """The measured payload, minus ``end_effector`` plus ``sensor_body`` when given
        (:func:`ftkin.io.payload_inertia.controller_load`); the held load is added after.
        """
        measured = super().tool_payload(request)
        bodies = [_body(request.option(name)) for name in ("end_effector", "sensor_body")]
        if all(body is None for body in bodies):
            return measured
        return controller_load(measured, *bodies)

    def document(self, request: ExportRequest) -> dict:
        payload = self.payload(request)
        inertia = np.zeros((3, 3)) if payload.inertia is None else payload.inertia
        return {
            "mass": float(payload.mass),
            "center_of_mass": _numbers(payload.center_of_mass),
            "load_inertia": _numbers(inertia.T),
        }

    def notes(self, request: ExportRequest) -> list[str]:
        if self.payload(request).inertia is not None:
            return []
        return [
            "a static calibration does not determine the inertia: load_inertia is zero (point "
            "mass); give --inertia if known"
        ]


def urscript_line(payload: Payload) -> str:
    """The URScript line that sets the payload [kg, m, tool flange frame; kg·m² about the centre
    of gravity in flange axes]: ``set_target_payload(mass, [cx, cy, cz], [Ixx, Iyy, Izz, Ixy,
    Ixz, Iyz])`` when the inertia is known (PolyScope 5.10 and later; the e-Series), else
    ``set_payload(mass, [cx, cy, cz])`` (a point mass: every controller)."""
    cx, cy, cz = _numbers(payload.center_of_mass)
    head = f"{float(payload.mass)!r}, [{cx!r}, {cy!r}, {cz!r}]"
    if payload.inertia is None:
        return f"set_payload({head})"
    i = np.asarray(payload.inertia, dtype=float)
    terms = [i[0, 0], i[1, 1], i[2, 2], i[0, 1], i[0, 2], i[1, 2]]
    return f"set_target_payload({head}, [{', '.join(repr(float(v)) for v in terms)}])"


class UrPayloadExport(PayloadFormat):
    name = "ur-payload"
    controller = "ur"
    options = (FLANGE_FRAME, INERTIA, HELD_LOAD)
    summary = (
        "ur_msgs/srv/SetPayload request for the ROS 2 UR driver (mass, centre of gravity; the "
        "inertia, when known, as URScript set_target_payload); OUT.script: the URScript line only"
    )

    def document(self, request: ExportRequest) -> dict:
        payload = self.payload(request)
        com = _numbers(payload.center_of_mass)
        return {"mass": float(payload.mass), "center_of_gravity": dict(zip("xyz", com))}

    def header(self, request: ExportRequest) -> list[str]:
        return [
            *super().header(request),
            f"ur_msgs/srv/SetPayload request: ros2 service call {UR_SET_PAYLOAD_SERVICE} "
            'ur_msgs/srv/SetPayload "{mass: ..., center_of_gravity: {x: ..., y: ..., z: ...}}"',
            f"URScript: {urscript_line(self.payload(request))}",
        ]

    def notes(self, request: ExportRequest) -> list[str]:
        if self.payload(request).inertia is not None:
            return [
                "the ROS 2 driver's SetPayload takes no inertia: the URScript line above "
                "(set_target_payload, PolyScope 5.10 or later) carries it"
            ]
        return [
            "a static calibration does not determine the inertia: a point mass (give --inertia, "
            "or export a dynamic calibration, for set_target_payload)"
        ]

    def text(self, request: ExportRequest) -> str:
        """YAML, or for a ``.script`` / ``.urscript`` path the URScript line alone."""
        if request.path is None or request.path.suffix.lower() not in (".script", ".urscript"):
            return super().text(request)
        return (
            "# ftkin payload: mass [kg], centre of gravity [m] in the tool flange frame"
            + (", inertia [kg*m^2] about it" if self.payload(request).inertia is not None else "")
            + f"\n{urscript_line(self.payload(request))}\n"
        )
