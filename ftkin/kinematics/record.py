"""How the sensor frame of a calibration was obtained, so that it can be rebuilt and checked.

A :class:`KinematicsRecord` is written into the calibration file: the
``--robot`` name and ``--sensor-offset``, or the ``--urdf`` path with
``--sensor-parent`` and its offset, plus what identifies the kinematics
exactly (the URDF's SHA-256 and the sensor frame's placement on its parent
joint). ``compensate``, ``view`` and ``report`` rebuild the arm from it
(:meth:`KinematicsRecord.build_arm`), and
:class:`~ftkin.control.compensation.Compensator` refuses an arm that differs
(:meth:`KinematicsRecord.mismatches`).
"""

import hashlib
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..validation import as_vector

_PLACEMENT_TOLERANCE = 1e-9  # m and rad


def file_sha256(path) -> str | None:
    """SHA-256 of a file's bytes (hex), or None when it cannot be read."""
    try:
        return hashlib.sha256(Path(path).read_bytes()).hexdigest()
    except (OSError, TypeError):
        return None


def sensor_placement(arm) -> tuple[str, list[float]]:
    """The sensor frame's parent joint and placement on it: ``(joint, [x, y, z, roll, pitch, yaw])``
    [m, rad].
    """
    frame = arm.model.frames[arm.sensor_frame_id]
    rpy = pin.rpy.matrixToRpy(frame.placement.rotation)
    return arm.model.names[frame.parentJoint], [
        *map(float, frame.placement.translation),
        *map(float, rpy),
    ]


@dataclass(frozen=True)
class KinematicsRecord:
    """The kinematics a calibration was made with.

    Attributes:
        sensor_frame: Name of the sensor frame.
        robot: ``--robot`` name, or None for a URDF given by path.
        urdf: Path of the URDF (absolute).
        urdf_sha256: SHA-256 of the URDF's bytes.
        sensor_parent: Frame the sensor frame was added at (``--sensor-parent`` or the robot's
        flange), or None
            when the URDF has the sensor frame.
        sensor_offset: ``[x, y, z, roll, pitch, yaw]`` [m, rad] of the sensor on ``sensor_parent``,
        or None.
        parent_joint: Joint the sensor frame moves with.
        placement: ``[x, y, z, roll, pitch, yaw]`` [m, rad] of the sensor frame on ``parent_joint``.
        tool_frame: The tool (control point) frame, or None.
    """

    sensor_frame: str
    robot: str | None = None
    urdf: str | None = None
    urdf_sha256: str | None = None
    sensor_parent: str | None = None
    sensor_offset: tuple[float, ...] | None = None
    parent_joint: str | None = None
    placement: tuple[float, ...] | None = None
    tool_frame: str | None = None

    @classmethod
    def from_arm(cls, arm) -> "KinematicsRecord":
        """The record of an :class:`~ftkin.kinematics.arm.Arm` (its robot name and mount when it has
        them).
        """
        mount = arm.sensor_mount
        joint, placement = sensor_placement(arm)
        return cls(
            sensor_frame=arm.sensor_frame,
            robot=arm.robot_name,
            urdf=str(arm.urdf_path) if arm.urdf_path is not None else None,
            urdf_sha256=file_sha256(arm.urdf_path) if arm.urdf_path is not None else None,
            sensor_parent=mount.parent_frame if mount is not None else None,
            sensor_offset=None
            if mount is None
            else tuple(float(v) for v in (*mount.translation, *mount.rpy)),
            parent_joint=joint,
            placement=tuple(placement),
            tool_frame=arm.tool_frame,
        )

    def to_dict(self) -> dict:
        """Plain data for the calibration file."""
        return {
            "sensor_frame": self.sensor_frame,
            "robot": self.robot,
            "urdf": self.urdf,
            "urdf_sha256": self.urdf_sha256,
            "sensor_parent": self.sensor_parent,
            "sensor_offset": list(self.sensor_offset) if self.sensor_offset is not None else None,
            "parent_joint": self.parent_joint,
            "placement": list(self.placement) if self.placement is not None else None,
            "tool_frame": self.tool_frame,
        }

    @classmethod
    def from_dict(cls, data: dict) -> "KinematicsRecord":
        """Inverse of :meth:`to_dict`; raises :class:`InvalidInput` on malformed data."""
        if not isinstance(data, dict) or not isinstance(data.get("sensor_frame"), str):
            raise InvalidInput("expected an object with a sensor_frame name")
        values = {f.name: data.get(f.name) for f in fields(cls) if f.name != "sensor_frame"}
        for key, value in values.items():
            if value is None:
                continue
            if key in ("sensor_offset", "placement"):
                if not isinstance(value, list) or len(value) != 6:
                    raise InvalidInput(
                        f"{key} must be 6 numbers [x, y, z, roll, pitch, yaw] or null, got "
                        f"{value!r}"
                    )
                values[key] = tuple(as_vector(value, 6, key).tolist())
            elif not isinstance(value, str):
                raise InvalidInput(f"{key} must be a string or null, got {value!r}")
        return cls(sensor_frame=data["sensor_frame"], **values)

    def describe(self) -> str:
        """How the sensor frame was obtained, as CLI options."""
        offset = (
            ""
            if self.sensor_offset is None
            else " --sensor-offset " + " ".join(f"{v:g}" for v in self.sensor_offset)
        )
        if self.robot is not None:
            return f"--robot {self.robot}{offset}"
        parent = f" --sensor-parent {self.sensor_parent}" if self.sensor_parent else ""
        frame = "" if self.sensor_frame == "ft_sensor" else f" --sensor-frame {self.sensor_frame}"
        return f"--urdf {self.urdf}{frame}{parent}{offset}"

    def build_arm(self, package_dirs=()):
        """Rebuild the arm this record describes.

        Raises:
            InvalidInput: the recorded URDF is gone or was changed since (its SHA-256 differs).
        """
        from .arm import Arm, SensorMount
        from .robots import load_robot

        offset = self.sensor_offset or (0.0,) * 6  # a robot's mount needs its recorded offset
        mount = None
        if self.sensor_parent is not None and (
            self.robot is None or self.sensor_offset is not None
        ):
            mount = SensorMount(self.sensor_parent, offset[:3], offset[3:])
        if self.robot is not None:
            arm = load_robot(self.robot, mount, self.tool_frame)
            arm.package_dirs += list(package_dirs)
        elif self.urdf is None or not Path(self.urdf).is_file():
            raise InvalidInput(
                f"the calibration's URDF {self.urdf} is not there any more: give --urdf (and "
                "the mount options)"
            )
        else:
            arm = Arm.from_urdf(
                self.urdf,
                self.sensor_frame,
                self.tool_frame,
                sensor_mount=mount,
                package_dirs=package_dirs,
            )
        problems = self.mismatches(arm)
        if problems:
            raise InvalidInput(
                f"cannot rebuild the calibration's arm ({self.describe()}): " + "; ".join(problems)
            )
        return arm

    def mismatches(self, arm) -> list[str]:
        """How ``arm`` differs from this record (empty when it is the same kinematics)."""
        problems = []
        if arm.sensor_frame != self.sensor_frame:
            problems.append(
                f"sensor frame {arm.sensor_frame!r}, calibrated with {self.sensor_frame!r}"
            )
        if self.urdf_sha256 is not None and arm.urdf_path is not None:
            if file_sha256(arm.urdf_path) != self.urdf_sha256:
                problems.append(
                    f"URDF {arm.urdf_path} is not the one calibrated with ({self.urdf}; SHA-256 "
                    "differs)"
                )
        if self.placement is not None and arm.sensor_frame == self.sensor_frame:
            joint, placement = sensor_placement(arm)
            if joint != self.parent_joint or not np.allclose(
                placement, self.placement, atol=_PLACEMENT_TOLERANCE
            ):
                problems.append(
                    f"sensor mounted at {joint} {np.round(placement, 6).tolist()}, calibrated at "
                    f"{self.parent_joint} "
                    f"{np.round(self.placement, 6).tolist()} [m, rad]"
                )
        return problems
