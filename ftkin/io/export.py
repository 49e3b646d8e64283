"""Write a calibration in the parameter formats of the ROS controllers people run.

Three targets (parameter names and sign conventions checked against each
project's sources; see the README section "Export to ROS controllers"):

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
frame, the weight vector pointing down. What a target cannot hold (the torque
or force bias, the base tilt) is listed by :func:`export_notes` and written
as comments in the file.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from ..calibration.model import SensorModel
from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from .atomic import atomic_write_text
from .yaml_text import yaml_text

EXPORT_FORMATS = ("admittance", "gravity-compensation", "ft-calib")
"""Targets :func:`export_text` knows."""

DEFAULT_SENSOR_FRAME = "ft_sensor"
DEFAULT_WORLD_FRAME = "base_link"
_TILT_NOTE_DEG = 0.01  # tilts smaller than this [deg] are not worth a note


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


def export_notes(calibration: SensorModel, fmt: str) -> list[str]:
    """What ``fmt`` cannot represent about ``calibration``, one sentence each."""
    _check_format(fmt)
    calibration = CalibrationResult.from_model(calibration)
    notes = []
    f0, m0 = np.asarray(calibration.force_offset), np.asarray(calibration.torque_offset)
    if fmt in ("admittance", "gravity-compensation"):
        target = (
            "admittance_controller" if fmt == "admittance" else "the GravityCompensation filter"
        )
        notes.append(
            f"{target} has no sensor bias: remove F0 = {_short(f0)} N and M0 = {_short(m0)} N·m "
            "before it "
            "(zero the sensor in the driver, or subtract these values upstream)"
        )
    tilt_deg = np.rad2deg(np.asarray(calibration.base_tilt, dtype=float))
    if np.max(np.abs(tilt_deg)) >= _TILT_NOTE_DEG and fmt in ("admittance", "ft-calib"):
        weight = calibration.tool_weight
        error = weight * math.sin(math.radians(float(np.hypot(*tilt_deg))))
        where = (
            "admittance_controller assumes gravity along -z of fixed_world_frame"
            if fmt == "admittance"
            else "ft_calib takes gravity from an IMU/TF, not from this file"
        )
        notes.append(
            f"the base tilt U = {tilt_deg[0]:.4f}°, V = {tilt_deg[1]:.4f}° is not representable "
            f"({where}); "
            f"ignoring it leaves up to {error:.4f} N of force error"
        )
    if calibration.has_mount:
        rpy = ", ".join(f"{value:.3f}" for value in calibration.mount_rpy_deg)
        notes.append(
            "the real sensor frame is turned from the URDF's by the estimated mount (R_M roll, "
            f"pitch, yaw = {rpy}°): the "
            "values are in the real sensor frame; the ROS sensor frame must be the real one (fix "
            "the URDF's sensor joint "
            "rpy by R_M^T)"
        )
    if calibration.sensor_sign != 1 or calibration.flip_axis:
        notes.append(
            f"the readings need sensor_sign {calibration.sensor_sign:+d}"
            + (f" and the {calibration.flip_axis} axis reversed" if calibration.flip_axis else "")
            + " before these parameters apply: fix the sign in the sensor driver"
        )
    return notes


def _check_format(fmt: str) -> None:
    if fmt not in EXPORT_FORMATS:
        raise InvalidInput(
            f"unknown export format {fmt!r}; expected one of {', '.join(EXPORT_FORMATS)}"
        )


def export_tree(
    calibration: SensorModel, fmt: str, frame_id: str | None = None, world_frame: str | None = None
) -> dict:
    """The parameters of ``fmt`` as nested dicts (the YAML that :func:`export_text` writes).

    Args:
        calibration: A :class:`~ftkin.calibration.model.SensorModel` (or calibration result).
        fmt: One of :data:`EXPORT_FORMATS`.
        frame_id: Sensor frame name in the ROS system (default: the
            calibration's sensor frame, else ``ft_sensor``).
        world_frame: Fixed frame of ``gravity_field`` (default: the URDF's root
            link, else ``base_link``); ftkin's base frame is the URDF root.
    """
    _check_format(fmt)
    calibration = CalibrationResult.from_model(calibration)
    frame_id = frame_id or calibration.sensor_frame or DEFAULT_SENSOR_FRAME
    com = [float(v) for v in calibration.center_of_mass]
    if fmt == "admittance":
        return {
            "gravity_compensation": {
                "frame": {"id": frame_id},
                "CoG": {"pos": com, "force": float(calibration.tool_weight)},
            }
        }
    mass = float(calibration.tool_mass)
    if fmt == "gravity-compensation":
        if mass <= 0.0:
            raise InvalidInput(
                "the calibration has no tool weight (a = 0): gravity_field = a / mass is undefined"
            )
        if world_frame is None:
            urdf = calibration.urdf
            world_frame = (urdf_root_link(urdf) if urdf else None) or DEFAULT_WORLD_FRAME
        field = np.asarray(calibration.gravity_in_base, dtype=float) / mass
        return {
            "world_frame": world_frame,
            "sensor_frame": frame_id,
            "tool": {"CoG": com, "mass": mass, "gravity_field": [float(v) for v in field]},
        }
    bias = [float(v) for v in np.concatenate([calibration.force_offset, calibration.torque_offset])]
    return {
        "bias": bias,
        "gripper_mass": mass,
        "gripper_com_frame_id": frame_id,
        "gripper_com_child_frame_id": f"{frame_id}_tool_com",
        "gripper_com_pose": com + [0.0, 0.0, 0.0],
    }


def export_text(
    calibration: SensorModel,
    fmt: str,
    frame_id: str | None = None,
    world_frame: str | None = None,
    node_name: str | None = None,
) -> str:
    """YAML text of ``calibration`` in format ``fmt`` (see the module docstring), with notes as
    comments.

    ``node_name`` is the ROS 2 node the parameters belong to (``admittance``:
    default ``admittance_controller``; ``gravity-compensation``: default
    ``/**``, any node, with the filter as ``sensor_filter_chain.filter1``).
    ``ft-calib`` is a flat ROS 1 parameter file (``rosparam load``) and takes
    no ``node_name``.

    Raises:
        InvalidInput: unknown format, ``node_name`` with ``ft-calib``, or a
            non-finite parameter.
    """
    if fmt == "ft-calib" and node_name is not None:
        raise InvalidInput(
            "ft-calib is a flat ROS 1 parameter file without a node name; drop node_name "
            "(--node-name)"
        )
    tree = export_tree(calibration, fmt, frame_id, world_frame)
    header = [
        f"# ftkin calibration exported for {fmt}",
        f"# tool mass {float(calibration.tool_mass):.6g} kg (g = {float(calibration.g):.6g} m/s²), "
        f"weight {float(calibration.tool_weight):.6g} N, COM in the sensor frame [m]",
    ]
    header += [f"# NOTE: {note}" for note in export_notes(calibration, fmt)]
    if fmt == "admittance":
        tree = {node_name or "admittance_controller": {"ros__parameters": tree}}
    elif fmt == "gravity-compensation":
        chain = {
            "filter1": {
                "name": "gravity_compensation",
                "type": "control_filters/GravityCompensationWrench",
                "params": tree,
            }
        }
        tree = {node_name or "/**": {"ros__parameters": {"sensor_filter_chain": chain}}}
        header.append(
            "# gravity_field = tilted gravity in world_frame, tool weight = mass · gravity_field"
        )
    else:
        header.append(
            "# bias = [fx, fy, fz, tx, ty, tz] subtracted from the raw reading; the model is"
        )
        header.append(
            "# raw = bias + [m·g_S; com × m·g_S] with g_S the gravity acceleration (pointing down) "
            "in the sensor frame"
        )
    return yaml_text(tree, comments=[line.removeprefix("# ") for line in header])


def export_calibration(calibration: SensorModel, path, fmt: str, **options) -> Path:
    """Write :func:`export_text` to ``path`` atomically; returns the path."""
    return atomic_write_text(Path(path), export_text(calibration, fmt, **options))
