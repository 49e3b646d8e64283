"""A calibration in the parameter formats of the ROS controllers people run.

Three formats (parameter names and sign conventions checked against each project's sources; see
docs/bags-and-exports.md):

``admittance``
    ros2_controllers ``admittance_controller``: ``gravity_compensation.frame.id``
    (frame of the CoG), ``gravity_compensation.CoG.pos`` [m] and
    ``gravity_compensation.CoG.force`` — the tool **weight** [N], positive; the
    controller subtracts ``[0, 0, -force]`` along its ``fixed_world_frame`` z
    and the matching torque ``(R·pos) × weight``.
``gravity-compensation``
    control_toolbox ``control_filters/GravityCompensationWrench`` filter:
    ``world_frame``, ``sensor_frame``, ``tool.CoG`` [m, sensor frame],
    ``tool.mass`` [kg] and ``tool.gravity_field`` [m/s², world frame]; the
    filter subtracts ``mass · gravity_field`` (rotated to the sensor) and
    ``CoG × (mass · gravity_field)``. ftkin writes ``gravity_field = a / mass``,
    the **tilted** gravity it estimated (``|gravity_field| = g``).
``ft-calib``
    force_torque_tools (KTH) ``ft_calib`` / ``gravity_compensation`` YAML:
    ``bias`` ``[fx, fy, fz, tx, ty, tz]`` (subtracted from the raw reading),
    ``gripper_mass`` [kg], ``gripper_com_frame_id``, ``gripper_com_child_frame_id``
    and ``gripper_com_pose`` ``[x, y, z, roll, pitch, yaw]`` [m, rad].

All three use ftkin's signs: raw = bias + weight + contact in the sensor
frame, the weight vector pointing down. What a format cannot hold (the torque
or force bias, the base tilt, the mount, a reversed sign) is listed by
:meth:`RosControllerFormat.notes` and written as comments in the file. Every
name written (node, frames) is checked against ROS's rules first.
"""

import math
import xml.etree.ElementTree as ET
from typing import ClassVar

import numpy as np

from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from ..validation import as_ros_name
from .export_format import ExportFormat, ExportOption, ExportRequest

DEFAULT_SENSOR_FRAME = "ft_sensor"
DEFAULT_WORLD_FRAME = "base_link"
_TILT_NOTE_DEG = 0.01  # tilts smaller than this [deg] are not worth a note

FRAME_ID = ExportOption(
    "frame_id",
    "--frame-id",
    "sensor frame name in ROS (default: the calibration's sensor frame)",
    {"metavar": "NAME"},
    ros_name="frame",
)
WORLD_FRAME = ExportOption(
    "world_frame",
    "--world-frame",
    "fixed frame of gravity_field (default: the URDF root link)",
    {"metavar": "NAME"},
    ros_name="frame",
)
NODE_NAME = ExportOption(
    "node_name",
    "--node-name",
    "ROS 2 node the parameters belong to",
    {"metavar": "NAME"},
    ros_name="node",
)


def _short(values) -> str:
    return "[" + ", ".join(f"{float(v):.6g}" for v in values) + "]"


def urdf_root_link(urdf) -> str | None:
    """Name of the URDF's root link (the base frame of ftkin's kinematics), or None if
    unreadable.
    """
    try:
        root = ET.parse(urdf).getroot()
    except (OSError, ET.ParseError, TypeError):
        return None
    links = [link.get("name") for link in root.iter("link")]
    children = {child.get("link") for child in root.iter("child")}
    roots = [name for name in links if name not in children]
    return roots[0] if len(roots) == 1 else None


def sensor_frame_id(request: ExportRequest) -> str:
    """``--frame-id``, else the calibration's sensor frame, else ``ft_sensor``; a valid ROS
    frame id.
    """
    calibration = CalibrationResult.from_model(request.calibration)
    default = calibration.sensor_frame or DEFAULT_SENSOR_FRAME
    return as_ros_name(request.option("frame_id", default), "frame", "the sensor frame id")


class RosControllerFormat(ExportFormat):
    """The parameters of a ROS controller; the notes say what it cannot hold.

    ``bias_target`` names the controller when it has no sensor bias (None: it has one);
    ``tilt_target`` says where the controller takes gravity from when it cannot hold the
    estimated base tilt (None: it can); ``header_lines`` explain the format's parameters.
    """

    bias_target: ClassVar[str | None] = None
    tilt_target: ClassVar[str | None] = None
    header_lines: ClassVar[tuple[str, ...]] = ()

    def header(self, request: ExportRequest) -> list[str]:
        calibration = request.calibration
        return [
            f"ftkin calibration exported for {self.name}",
            f"tool mass {float(calibration.tool_mass):.6g} kg (g = {float(calibration.g):.6g} "
            f"m/s²), weight {float(calibration.tool_weight):.6g} N, COM in the sensor frame [m]",
            *self.header_lines,
        ]

    def notes(self, request: ExportRequest) -> list[str]:
        calibration, notes = CalibrationResult.from_model(request.calibration), []
        if self.bias_target is not None:
            f0, m0 = calibration.force_offset, calibration.torque_offset
            notes.append(
                f"{self.bias_target} has no sensor bias: remove F0 = {_short(f0)} N and "
                f"M0 = {_short(m0)} N·m before it (zero the sensor in the driver, or subtract "
                "these values upstream)"
            )
        tilt_deg = np.rad2deg(np.asarray(calibration.base_tilt, dtype=float))
        if self.tilt_target is not None and np.max(np.abs(tilt_deg)) >= _TILT_NOTE_DEG:
            error = calibration.tool_weight * math.sin(math.radians(float(np.hypot(*tilt_deg))))
            notes.append(
                f"the base tilt U = {tilt_deg[0]:.4f}°, V = {tilt_deg[1]:.4f}° is not "
                f"representable ({self.tilt_target}); ignoring it leaves up to {error:.4f} N of "
                "force error"
            )
        if calibration.has_mount:
            rpy = ", ".join(f"{value:.3f}" for value in calibration.mount_rpy_deg)
            notes.append(
                "the real sensor frame is turned from the URDF's by the estimated mount (R_M "
                f"roll, pitch, yaw = {rpy}°): the values are in the real sensor frame; the ROS "
                "sensor frame must be the real one (fix the URDF's sensor joint rpy by R_M^T)"
            )
        flip = calibration.flip_axis
        if calibration.sensor_sign != 1 or flip:
            notes.append(
                f"the readings need sensor_sign {calibration.sensor_sign:+d}"
                + (f" and the {flip} axis reversed" if flip else "")
                + " before these parameters apply: fix the sign in the sensor driver"
            )
        return notes


class AdmittanceExport(RosControllerFormat):
    name = "admittance"
    summary = "ros2_controllers admittance_controller gravity_compensation.*"
    options = (FRAME_ID, NODE_NAME)
    bias_target = "admittance_controller"
    tilt_target = "admittance_controller assumes gravity along -z of fixed_world_frame"

    def document(self, request: ExportRequest) -> dict:
        calibration = request.calibration
        parameters = {
            "frame": {"id": sensor_frame_id(request)},
            "CoG": {
                "pos": [float(v) for v in calibration.center_of_mass],
                "force": float(calibration.tool_weight),
            },
        }
        node = request.option("node_name", "admittance_controller")
        return {node: {"ros__parameters": {"gravity_compensation": parameters}}}


class GravityCompensationExport(RosControllerFormat):
    name = "gravity-compensation"
    summary = (
        "control_toolbox GravityCompensationWrench filter tool.CoG/mass/gravity_field, with the "
        "tilted gravity"
    )
    options = (FRAME_ID, WORLD_FRAME, NODE_NAME)
    bias_target = "the GravityCompensation filter"
    header_lines = (
        "gravity_field = tilted gravity in world_frame, tool weight = mass · gravity_field",
    )

    def document(self, request: ExportRequest) -> dict:
        calibration = request.calibration
        mass = float(calibration.tool_mass)
        if mass <= 0.0:
            raise InvalidInput(
                "the calibration has no tool weight (a = 0): gravity_field = a / mass is undefined"
            )
        urdf = CalibrationResult.from_model(calibration).urdf
        world = (urdf_root_link(urdf) if urdf else None) or DEFAULT_WORLD_FRAME
        field = np.asarray(calibration.gravity_in_base, dtype=float) / mass
        parameters = {
            "world_frame": as_ros_name(request.option("world_frame", world), "frame", "world"),
            "sensor_frame": sensor_frame_id(request),
            "tool": {
                "CoG": [float(v) for v in calibration.center_of_mass],
                "mass": mass,
                "gravity_field": [float(v) for v in field],
            },
        }
        chain = {
            "filter1": {
                "name": "gravity_compensation",
                "type": "control_filters/GravityCompensationWrench",
                "params": parameters,
            }
        }
        node = request.option("node_name", "/**")
        return {node: {"ros__parameters": {"sensor_filter_chain": chain}}}


class FtCalibExport(RosControllerFormat):
    name = "ft-calib"
    summary = (
        "force_torque_tools ft_calib YAML (a flat ROS 1 parameter file): bias, gripper_mass, "
        "gripper_com_pose"
    )
    options = (FRAME_ID,)
    tilt_target = "ft_calib takes gravity from an IMU/TF, not from this file"
    header_lines = (
        "bias = [fx, fy, fz, tx, ty, tz] subtracted from the raw reading; the model is",
        "raw = bias + [m·g_S; com × m·g_S] with g_S the gravity acceleration (pointing down) "
        "in the sensor frame",
    )

    def document(self, request: ExportRequest) -> dict:
        calibration, frame_id = request.calibration, sensor_frame_id(request)
        bias = np.concatenate([calibration.force_offset, calibration.torque_offset])
        return {
            "bias": [float(v) for v in bias],
            "gripper_mass": float(calibration.tool_mass),
            "gripper_com_frame_id": frame_id,
            "gripper_com_child_frame_id": f"{frame_id}_tool_com",
            "gripper_com_pose": [float(v) for v in calibration.center_of_mass] + [0.0, 0.0, 0.0],
        }
