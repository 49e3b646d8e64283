"""How the sensor frame of a calibration was obtained, so that it can be rebuilt and checked.

A :class:`KinematicsRecord` is written into the calibration file: the
``--robot`` name and ``--sensor-offset``, or the ``--urdf`` path with
``--sensor-parent`` and its offset, plus the kinematics themselves: the chain from the base to
the sensor frame (:func:`kinematic_chain`: each joint's screw axis and the sensor frame's
placement at zero joint angles, the product-of-exponentials form, which fixes the sensor pose
for every ``q``). ``compensate``, ``view`` and ``report`` rebuild the arm from it
(:meth:`KinematicsRecord.build_arm`), and
:class:`~ftkin.control.compensation.Compensator` refuses an arm that differs
(:meth:`KinematicsRecord.mismatches`). Arms are compared by their kinematics, within
:data:`KINEMATICS_TOLERANCE`, never by the URDF's bytes: two files describing the same chain
(another copy, other mesh paths, rounding in the last digits) are the same arm, and a
difference is named (which joint, by how much).
"""

import hashlib
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..validation import as_vector

_PLACEMENT_TOLERANCE = 1e-9  # m and rad: a record without a chain (made by hand)
KINEMATICS_TOLERANCE = 1e-5
"""Largest difference between two arms' chains [m and rad] taken as the same kinematics (a joint
axis's direction [rad] and position [m], the sensor frame's orientation [rad] and position [m] at
zero joint angles). Far above the rounding of a URDF written with six decimals (5e-7) or of a
model built from DH parameters, far below what a calibration resolves: 1e-5 rad turns a 10 N
weight by 0.1 mN, 10 µm moves a centre of mass by as much."""
_MOST_REPORTED = 3  # joint differences named in one message (then "and N more")


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


def kinematic_chain(arm) -> tuple[np.ndarray, np.ndarray]:
    """The chain from the base to the sensor frame, at zero joint angles (base frame).

    Returns ``(screw_axes, sensor_home)``: ``(nq, 6)`` the screw axis ``[ω, v]`` of each joint
    in ``q`` order (``ω`` the unit axis of a revolute joint, ``v`` the velocity [m/s per unit
    rate] of the point at the base origin; ``ω = 0`` and ``v`` the unit direction of a prismatic
    joint; a row of zeros for a joint that does not move the sensor), and ``(6,)`` the sensor
    frame's placement ``[x, y, z, roll, pitch, yaw]`` [m, rad]. Together they fix the sensor pose
    for every ``q`` (``T(q) = exp(S₁q₁)…exp(Sₙqₙ)·M``), however the URDF splits the chain into
    links and fixed joints.
    """
    model, frame = arm.model, arm.sensor_frame_id
    data = model.createData()
    jacobian = pin.computeFrameJacobian(
        model, data, np.zeros(model.nq), frame, pin.ReferenceFrame.WORLD
    )  # rows [v; ω], columns the joints' screw axes in the base frame
    placement = pin.updateFramePlacement(model, data, frame)
    screw_axes = np.hstack([jacobian[3:].T, jacobian[:3].T])
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    return screw_axes, np.concatenate([placement.translation, rpy])


def _joint_difference(recorded: np.ndarray, given: np.ndarray) -> tuple[str, float, float] | None:
    """How one joint's screw axis differs from the recorded one: ``(what, turned [rad], moved
    [m])``, or None within :data:`KINEMATICS_TOLERANCE`."""
    kinds = []
    for axis in (recorded, given):
        if np.linalg.norm(axis[:3]) > 0.5:
            kinds.append("revolute")
        elif np.linalg.norm(axis[3:]) > 0.5:
            kinds.append("prismatic")
        else:
            kinds.append("not moving the sensor")
    if kinds[0] != kinds[1]:
        return f"{kinds[1]}, calibrated {kinds[0]}", np.nan, np.nan
    if kinds[0] == "not moving the sensor":
        return None
    revolute = kinds[0] == "revolute"
    directions = [axis[:3] if revolute else axis[3:] for axis in (recorded, given)]
    directions = [d / np.linalg.norm(d) for d in directions]
    turned = float(np.arctan2(np.linalg.norm(np.cross(*directions)), np.dot(*directions)))
    # a revolute axis's point nearest the base origin is ω × v; a prismatic joint has no place
    points = [np.cross(d, axis[3:]) for d, axis in zip(directions, (recorded, given))]
    moved = float(np.linalg.norm(points[1] - points[0])) if revolute else 0.0
    if turned <= KINEMATICS_TOLERANCE and moved <= KINEMATICS_TOLERANCE:
        return None
    return ("axis" if revolute else "direction"), turned, moved


def _how_far(turned: float, moved: float) -> str:
    """``"turned 2.5°"``, ``"moved 3 mm"`` or both: the parts beyond the tolerance."""
    parts = [f"turned {np.rad2deg(turned):.3g}°"] if turned > KINEMATICS_TOLERANCE else []
    if moved > KINEMATICS_TOLERANCE:
        parts.append(f"moved {moved * 1e3:.3g} mm")
    return " and ".join(parts)


def chain_differences(recorded_axes, recorded_home, recorded_joints, arm) -> list[str]:
    """How ``arm``'s chain (:func:`kinematic_chain`) differs from a recorded one, joint by joint
    and at the sensor frame (empty within :data:`KINEMATICS_TOLERANCE`)."""
    axes, home = kinematic_chain(arm)
    recorded_axes = np.asarray(recorded_axes, dtype=float).reshape(-1, 6)
    names = list(recorded_joints or [f"joint {i + 1}" for i in range(len(recorded_axes))])
    if len(axes) != len(recorded_axes):
        return [
            f"{len(axes)} joints ({', '.join(arm.joint_names)}), calibrated with "
            f"{len(recorded_axes)} ({', '.join(names)})"
        ]
    problems = []
    for i, (was, now) in enumerate(zip(recorded_axes, axes)):
        found = _joint_difference(was, now)
        if found is None:
            continue
        what, turned, moved = found
        label = f"joint {i + 1} ({arm.joint_names[i]})"
        if np.isnan(turned):
            problems.append(f"{label} is {what}")
        else:
            problems.append(
                f"{label}: its {what} is {_how_far(turned, moved)} from the calibration's "
                f"({names[i]})"
            )
    if len(problems) > _MOST_REPORTED:
        problems = problems[:_MOST_REPORTED] + [
            f"and {len(problems) - _MOST_REPORTED} more joints differ"
        ]
    recorded_home = np.asarray(recorded_home, dtype=float)
    rotation = pin.rpy.rpyToMatrix(*recorded_home[3:]).T @ pin.rpy.rpyToMatrix(*home[3:])
    turned = float(np.linalg.norm(pin.log3(rotation)))
    moved = float(np.linalg.norm(home[:3] - recorded_home[:3]))
    if turned > KINEMATICS_TOLERANCE or moved > KINEMATICS_TOLERANCE:
        problems.append(
            f"at zero joint angles the sensor frame {arm.sensor_frame!r} is "
            f"{_how_far(turned, moved)} from the calibration's (at "
            f"{(np.round(home[:3], 6) + 0.0).tolist()} m, calibrated at "
            f"{(np.round(recorded_home[:3], 6) + 0.0).tolist()} m, base frame)"
        )
    return problems


@dataclass(frozen=True)
class KinematicsRecord:
    """The kinematics a calibration was made with.

    Attributes:
        sensor_frame: Name of the sensor frame.
        robot: ``--robot`` name, or None for a URDF given by path.
        urdf: Path of the URDF (absolute).
        urdf_sha256: SHA-256 of the URDF's bytes (provenance: arms are compared by
            ``screw_axes`` and ``sensor_home``, not by bytes).
        sensor_parent: Frame the sensor frame was added at (``--sensor-parent`` or the robot's
        flange), or None
            when the URDF has the sensor frame.
        sensor_offset: ``[x, y, z, roll, pitch, yaw]`` [m, rad] of the sensor on ``sensor_parent``,
        or None.
        parent_joint: Joint the sensor frame moves with.
        placement: ``[x, y, z, roll, pitch, yaw]`` [m, rad] of the sensor frame on ``parent_joint``.
        tool_frame: The tool (control point) frame, or None.
        joints: Names of the joints in ``q`` order, or None.
        screw_axes: ``(nq, 6)`` screw axes ``[ω, v]`` of the joints at zero joint angles, base
            frame (:func:`kinematic_chain`), or None (a record made by hand: then the sensor
            frame's name and placement on its parent joint are compared).
        sensor_home: ``[x, y, z, roll, pitch, yaw]`` [m, rad] of the sensor frame in the base
            frame at zero joint angles, or None.
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
    joints: tuple[str, ...] | None = None
    screw_axes: tuple[tuple[float, ...], ...] | None = None
    sensor_home: tuple[float, ...] | None = None

    @classmethod
    def from_arm(cls, arm) -> "KinematicsRecord":
        """The record of an :class:`~ftkin.kinematics.arm.Arm` (its robot name and mount when it has
        them, and its chain).
        """
        mount = arm.sensor_mount
        joint, placement = sensor_placement(arm)
        screw_axes, sensor_home = kinematic_chain(arm)
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
            joints=tuple(arm.joint_names),
            screw_axes=tuple(tuple(float(v) for v in row) for row in screw_axes),
            sensor_home=tuple(float(v) for v in sensor_home),
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
            "joints": list(self.joints) if self.joints is not None else None,
            "screw_axes": [list(row) for row in self.screw_axes]
            if self.screw_axes is not None
            else None,
            "sensor_home": list(self.sensor_home) if self.sensor_home is not None else None,
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
            if key in ("sensor_offset", "placement", "sensor_home"):
                if not isinstance(value, list) or len(value) != 6:
                    raise InvalidInput(
                        f"{key} must be 6 numbers [x, y, z, roll, pitch, yaw] or null, got "
                        f"{value!r}"
                    )
                values[key] = tuple(as_vector(value, 6, key).tolist())
            elif key == "screw_axes":
                if not isinstance(value, list) or not all(
                    isinstance(row, list) and len(row) == 6 for row in value
                ):
                    raise InvalidInput(
                        f"screw_axes must be a list of [wx, wy, wz, vx, vy, vz] (one per joint) "
                        f"or null, got {value!r}"
                    )
                values[key] = tuple(
                    tuple(as_vector(row, 6, f"screw_axes[{i}]").tolist())
                    for i, row in enumerate(value)
                )
            elif key == "joints":
                if not isinstance(value, list) or not all(isinstance(n, str) for n in value):
                    raise InvalidInput(
                        f"joints must be a list of joint names or null, got {value!r}"
                    )
                values[key] = tuple(value)
            elif not isinstance(value, str):
                raise InvalidInput(f"{key} must be a string or null, got {value!r}")
        if (values["screw_axes"] is None) != (values["sensor_home"] is None):
            raise InvalidInput("screw_axes and sensor_home come together (both or neither)")
        if values["joints"] is not None and values["screw_axes"] is not None:
            if len(values["joints"]) != len(values["screw_axes"]):
                raise InvalidInput(
                    f"{len(values['joints'])} joints but {len(values['screw_axes'])} screw_axes; "
                    "expected one each"
                )
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
            InvalidInput: the recorded URDF is gone, or its kinematics were changed since
                (:meth:`mismatches` says how).
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
                f"the calibration's URDF {self.urdf} is not there any more: give the arm "
                "(ftkin: --urdf PATH and the mount options; Python: arm=Arm.from_urdf(PATH, ...))"
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
        """How ``arm`` differs from this record (empty when it is the same kinematics).

        With the recorded chain (``screw_axes``, ``sensor_home``), the arm's chain from the base
        to its sensor frame is compared within :data:`KINEMATICS_TOLERANCE`, whatever the URDF's
        file, names or link structure; each difference names the joint (or the sensor frame)
        and by how much. A record without a chain compares the sensor frame's name and its
        placement on the parent joint.
        """
        if self.screw_axes is not None and self.sensor_home is not None:
            return chain_differences(self.screw_axes, self.sensor_home, self.joints, arm)
        problems = []
        if arm.sensor_frame != self.sensor_frame:
            problems.append(
                f"sensor frame {arm.sensor_frame!r}, calibrated with {self.sensor_frame!r}"
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
