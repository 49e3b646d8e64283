"""Where an admittance works: the control frame and the wrench/twist transports.

:class:`ControlFrame` moves the compensated wrench from the sensor to the
control point (lever arm and axes) and the admittance's twist back to the
sensor origin: Pinocchio's force and motion transports
(:meth:`ControlFrame.wrench_from_sensor`, :meth:`ControlFrame.twist_to_sensor_origin`), and
their fast paths on Python floats for the control tick (the 3-vector arithmetic is written
out on purpose). :func:`control_frame_for` builds one from an
arm's sensor and tool frames.
"""

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..kinematics.arm import Arm
from ..validation import as_rotation_batch, as_vector

FRAMES = ("sensor", "tool", "base")
"""Frames an admittance can work in (see :class:`ControlFrame`)."""


class ControlFrame:
    """Where ``ΔF`` and ``ΔV`` live, and the conversions from/to the sensor.

    * ``"sensor"``: sensor origin, sensor axes;
    * ``"tool"``: the tool point ``r`` (sensor frame) [m], tool axes (``R_ST``, tool to sensor);
    * ``"base"``: the control point ``r``, base axes.

    Wrench transport to the control point: ``M_p = M_s − r × F`` (moment about
    the new point), then a rotation of both parts. Twist transport back to the
    sensor origin for the sensor Jacobian: ``v_s = v_p − ω × r`` (base axes).

    Args:
        frame: One of :data:`FRAMES`.
        point_in_sensor: Control point in the sensor frame [m] (ignored for ``"sensor"``).
        rotation_tool_to_sensor: ``R_ST`` ``(3, 3)``, only used for ``"tool"``.
    """

    def __init__(
        self, frame: str = "sensor", point_in_sensor=(0.0, 0.0, 0.0), rotation_tool_to_sensor=None
    ):
        if frame not in FRAMES:
            raise InvalidInput(f"frame must be one of {FRAMES}, got {frame!r}")
        self.frame = frame
        point = as_vector(point_in_sensor, 3, "control point in the sensor frame")
        self.point_in_sensor = np.zeros(3) if frame == "sensor" else point.copy()
        self.rotation_tool_to_sensor = np.eye(3)
        if rotation_tool_to_sensor is not None:
            rotations, single = as_rotation_batch(
                rotation_tool_to_sensor, "rotation_tool_to_sensor"
            )
            if not single:
                raise InvalidInput(
                    "rotation_tool_to_sensor must be one (3, 3) rotation matrix, got shape "
                    f"{rotations.shape}"
                )
            if frame == "tool":
                self.rotation_tool_to_sensor = rotations[0].copy()
        # The transports' constants as Python floats (the arrays above are copies: the caller's stay
        # theirs).
        self._r, self._rotation_rows, self._inverse_rows = (
            self.point_in_sensor.tolist(),
            self.rotation_tool_to_sensor.tolist(),
            self.rotation_tool_to_sensor.T.tolist(),
        )

    def placement_in_sensor(self, rotation_sensor_to_base: np.ndarray) -> pin.SE3:
        """The control frame in the sensor frame: origin ``r`` [m] and axes ``R_SC``."""
        if self.frame == "base":
            return pin.SE3(np.asarray(rotation_sensor_to_base, dtype=float).T, self.point_in_sensor)
        return pin.SE3(self.rotation_tool_to_sensor, self.point_in_sensor)  # identity for "sensor"

    def wrench_from_sensor(
        self, wrench_in_sensor: np.ndarray, rotation_sensor_to_base: np.ndarray
    ) -> np.ndarray:
        """``(6,)`` wrench at the control point in this frame's axes, from the sensor's ``(6,)``.

        Pinocchio's force transport ``M_SC⁻¹ · f``; :meth:`wrench_floats` is its fast path.
        """
        return (
            self.placement_in_sensor(rotation_sensor_to_base)
            .actInv(pin.Force(np.asarray(wrench_in_sensor, dtype=float)))
            .vector
        )

    def twist_to_sensor_origin(
        self, twist: np.ndarray, rotation_sensor_to_base: np.ndarray
    ) -> np.ndarray:
        """Twist ``[v; ω]`` of the sensor origin in base axes, from a control-point twist in this
        frame's axes.

        Pinocchio's motion transport ``(R_BS, 0) · M_SC · ν``; :meth:`twist_floats` is its fast
        path.
        """
        rotation = np.asarray(rotation_sensor_to_base, dtype=float)
        return (
            (pin.SE3(rotation, np.zeros(3)) * self.placement_in_sensor(rotation))
            .act(pin.Motion(np.asarray(twist, dtype=float)))
            .vector
        )

    # The two transports on Python floats (the control tick's path, several times faster than
    # Pinocchio through Python); tests check them against the methods above to 1e-12.
    def wrench_floats(self, wrench_in_sensor, rotation_rows) -> tuple[float, ...]:
        """:meth:`wrench_from_sensor` on six floats and ``R_BS.tolist()``; returns six floats."""
        fx, fy, fz, mx, my, mz = wrench_in_sensor
        rx, ry, rz = self._r
        mx, my, mz = mx - (ry * fz - rz * fy), my - (rz * fx - rx * fz), mz - (rx * fy - ry * fx)
        if self.frame == "sensor":
            return fx, fy, fz, mx, my, mz
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = (
            rotation_rows if self.frame == "base" else self._inverse_rows
        )
        return (
            r00 * fx + r01 * fy + r02 * fz,
            r10 * fx + r11 * fy + r12 * fz,
            r20 * fx + r21 * fy + r22 * fz,
            r00 * mx + r01 * my + r02 * mz,
            r10 * mx + r11 * my + r12 * mz,
            r20 * mx + r21 * my + r22 * mz,
        )

    def twist_floats(self, twist, rotation_rows) -> tuple[float, ...]:
        """:meth:`twist_to_sensor_origin` on six floats and ``R_BS.tolist()``; returns six
        floats.
        """
        vx, vy, vz, wx, wy, wz = twist
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation_rows  # R_BS, written out below
        if self.frame == "tool":  # tool axes to sensor axes (R_ST, written out)
            (t00, t01, t02), (t10, t11, t12), (t20, t21, t22) = self._rotation_rows
            vx, vy, vz = (
                t00 * vx + t01 * vy + t02 * vz,
                t10 * vx + t11 * vy + t12 * vz,
                t20 * vx + t21 * vy + t22 * vz,
            )
            wx, wy, wz = (
                t00 * wx + t01 * wy + t02 * wz,
                t10 * wx + t11 * wy + t12 * wz,
                t20 * wx + t21 * wy + t22 * wz,
            )
        if self.frame != "base":  # sensor axes to base axes
            vx, vy, vz = (
                r00 * vx + r01 * vy + r02 * vz,
                r10 * vx + r11 * vy + r12 * vz,
                r20 * vx + r21 * vy + r22 * vz,
            )
            wx, wy, wz = (
                r00 * wx + r01 * wy + r02 * wz,
                r10 * wx + r11 * wy + r12 * wz,
                r20 * wx + r21 * wy + r22 * wz,
            )
        rx, ry, rz = self._r
        px, py, pz = (
            r00 * rx + r01 * ry + r02 * rz,
            r10 * rx + r11 * ry + r12 * rz,
            r20 * rx + r21 * ry + r22 * rz,
        )
        return (
            vx - (wy * pz - wz * py),
            vy - (wz * px - wx * pz),
            vz - (wx * py - wy * px),
            wx,
            wy,
            wz,
        )  # v − ω × p


def control_frame_for(arm: Arm, frame: str, control_point: str | None = None) -> ControlFrame:
    """The :class:`ControlFrame` for an arm: tool point and axes taken from its tool frame.

    Raises:
        InvalidInput: the tool frame is not rigidly attached to the sensor (not
            on the same joint), or a tool control point is asked of an arm without one.
    """
    if control_point is None:
        control_point = "sensor" if frame == "sensor" or arm.tool_frame_id is None else "tool"
    if control_point not in ("sensor", "tool"):
        raise InvalidInput(f"control_point must be 'sensor' or 'tool', got {control_point!r}")
    if frame == "tool" and control_point != "tool":
        raise InvalidInput("frame 'tool' needs the tool control point")
    if control_point == "sensor" or frame == "sensor":
        return ControlFrame(frame)
    if arm.tool_frame_id is None:
        raise InvalidInput(
            "this Arm has no tool frame: load it with tool_frame= or use control_point='sensor'"
        )
    sensor, tool = arm.model.frames[arm.sensor_frame_id], arm.model.frames[arm.tool_frame_id]
    if sensor.parentJoint != tool.parentJoint:
        raise InvalidInput(
            f"tool frame {arm.tool_frame!r} is not on the same joint as sensor frame "
            f"{arm.sensor_frame!r}; "
            "the control point must be rigidly attached to the sensor"
        )
    relative = sensor.placement.inverse() * tool.placement
    return ControlFrame(frame, relative.translation, relative.rotation)
