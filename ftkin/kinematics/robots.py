"""Robot models by name: ``--robot NAME`` on the command line.

``ftkin_c4`` is the bundled six-axis arm (default, sensor frame ``ft_sensor``
already in its URDF); ``fr3`` the bundled Franka FR3 with its hand (sensor frame
``fr3_hand``). The other names load a URDF from the
``example-robot-data`` wheel (optional extra ``robots``) and add the sensor
frame ``ft_sensor`` at the robot's flange (``tool0`` for the UR arms,
``panda_link8`` for the Panda, ...), optionally offset by a translation [m] and
roll-pitch-yaw [rad] in the flange frame. Grippers' finger joints are locked so
``q`` holds only the arm joints.

The flange frame of each named robot is the frame its controller expresses a payload in
(:data:`FLANGE_FRAMES`; libfranka's ``F_x_Cload`` in ``<prefix>_link8``, UR's ``set_payload``
in ``tool0``). For an arm loaded from a URDF it is never guessed: the controller's own rule
(:data:`CONTROLLERS`) finds it, or the user names it (``--flange-frame``).

The wheel ships no Python loader: its files are found through the installed
distribution's file list (``share/example-robot-data/package.xml``), and the
``share`` folder is the package directory ``package://`` mesh URIs resolve
against.
"""

import functools
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, UrdfError
from ..validation import as_float_array
from .arm import Arm, SensorMount
from .ur_eseries import FLANGE_FRAME as UR_FLANGE_FRAME
from .ur_eseries import UR_DH, ur_arm

DEFAULT_ROBOT = "ftkin_c4"
BUNDLED_FLANGE_FRAME = "flange"
"""The bundled arm's flange frame (z out of the flange face)."""
SENSOR_FRAME = "ft_sensor"
_DISTRIBUTION = "example-robot-data"


@dataclass(frozen=True)
class Controller:
    """A robot controller's convention for the frame it takes a payload in.

    Attributes:
        name: ``"franka"`` or ``"ur"`` (the payload export formats name theirs).
        frame_pattern: A full-match regular expression of that frame's name in a URDF.
        description: The frame as the vendor documents it, for messages.
    """

    name: str
    frame_pattern: str
    description: str

    def frames_in(self, frame_names: Sequence[str]) -> list[str]:
        """The frames of ``frame_names`` that follow this controller's rule."""
        return [name for name in frame_names if re.fullmatch(self.frame_pattern, name)]


CONTROLLERS: dict[str, Controller] = {
    "franka": Controller(
        "franka",
        r"(?:.+_)?link8",
        "the flange <prefix>_link8 (libfranka F_x_Cload, franka_msgs SetLoad center_of_mass)",
    ),
    "ur": Controller("ur", r"(?:.+_)?tool0", "the tool flange tool0 (URScript set_payload)"),
}
"""Payload frame rules by controller family."""


@dataclass(frozen=True)
class RobotSpec:
    """Where an example-robot-data arm's URDF and flange are.

    Attributes:
        name: The ``--robot`` name.
        urdf: URDF path relative to ``share/example-robot-data/robots``.
        flange_frame: Frame the sensor is bolted to (z out of the flange), the frame the
            robot's controller takes a payload in.
        locked_joints: Joints fixed at a value [rad or m] (gripper fingers).
        description: One line for listings.
        controller: The controller family (a key of :data:`CONTROLLERS`), or None.
    """

    name: str
    urdf: str
    flange_frame: str
    locked_joints: dict[str, float] = field(default_factory=dict)
    description: str = ""
    controller: str | None = None


ROBOT_SPECS: dict[str, RobotSpec] = {
    spec.name: spec
    for spec in (
        RobotSpec(
            "ur3",
            "ur_description/urdf/ur3_robot.urdf",
            "tool0",
            description="Universal Robots UR3 (CB3)",
            controller="ur",
        ),
        RobotSpec(
            "ur5",
            "ur_description/urdf/ur5_robot.urdf",
            "tool0",
            description="Universal Robots UR5 (CB3)",
            controller="ur",
        ),
        RobotSpec(
            "ur10",
            "ur_description/urdf/ur10_robot.urdf",
            "tool0",
            description="Universal Robots UR10 (CB3)",
            controller="ur",
        ),
        RobotSpec(
            "panda",
            "panda_description/urdf/panda.urdf",
            "panda_link8",
            {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0},
            "Franka Emika Panda (7 joints; fingers locked)",
            "franka",
        ),
        RobotSpec(
            "xarm7", "xarm_description/urdf/xarm7.urdf", "link_eef", description="UFactory xArm7"
        ),
        RobotSpec(
            "z1",
            "z1_description/urdf/z1.urdf",
            "link06",
            {"jointGripper": 0.0},
            "Unitree Z1 (gripper locked)",
        ),
    )
}
"""The example-robot-data arms ftkin knows, by ``--robot`` name."""


@functools.lru_cache(maxsize=1)
def example_robot_data_share() -> Path:
    """The ``share`` folder of the installed example-robot-data (cached).

    Raises:
        MissingDependency: example-robot-data is not installed.
    """
    import importlib.metadata  # here, not at import: it pulls in the email package (~0.05 s)

    try:
        distribution = importlib.metadata.distribution(_DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        raise MissingDependency(_DISTRIBUTION, "robots", "loading a robot by name") from None
    for entry in distribution.files or ():
        if str(entry).replace("\\", "/").endswith("share/example-robot-data/package.xml"):
            package_xml = Path(distribution.locate_file(entry))
            if package_xml.is_file():
                return package_xml.parent.parent
    raise MissingDependency(
        _DISTRIBUTION, "robots", "loading a robot by name (its files were not found; reinstall it)"
    )


def sensor_mount_from_offset(parent_frame: str, sensor_offset=None) -> SensorMount:
    """A :class:`SensorMount` at ``parent_frame`` from ``[x, y, z]`` [m] or ``[x, y, z, roll, pitch,
    yaw]`` [m, rad].
    """
    if sensor_offset is None:
        return SensorMount(parent_frame)
    if isinstance(sensor_offset, SensorMount):
        return sensor_offset
    values = as_float_array(sensor_offset, "sensor offset").ravel()
    if values.shape not in ((3,), (6,)) or not np.all(np.isfinite(values)):
        raise InvalidInput(
            "sensor offset must be 3 numbers (x y z [m]) or 6 (x y z [m] roll pitch yaw [rad]), "
            f"got {sensor_offset!r}"
        )
    if np.any(np.abs(values[:3]) > 10.0):
        raise InvalidInput(
            "sensor offset x y z must be within 10 m of the parent frame, got "
            f"{values[:3].tolist()} [m]"
        )
    rpy = values[3:] if len(values) == 6 else np.zeros(3)
    if np.any(np.abs(rpy) > 2.0 * np.pi):
        raise InvalidInput(
            f"sensor offset roll pitch yaw {rpy.tolist()} are beyond 2π: angles are in radians "
            "(these look like degrees)"
        )
    return SensorMount(parent_frame, tuple(values[:3]), tuple(rpy))


def _bundled(sensor_offset=None, tool_frame: str | None = None) -> Arm:
    if sensor_offset is not None:
        raise InvalidInput(
            "the bundled arm already has its ft_sensor frame; --sensor-offset is for robots "
            "without one"
        )
    return Arm.default(tool_frame or "tool")


def _load_spec(spec: RobotSpec, sensor_offset=None, tool_frame: str | None = None) -> Arm:
    share = example_robot_data_share()
    path = share / "example-robot-data" / "robots" / spec.urdf
    if not path.is_file():
        raise UrdfError(
            str(path), [f"robot {spec.name!r}: this example-robot-data has no such file"]
        )
    return Arm.from_urdf(
        path,
        SENSOR_FRAME,
        tool_frame,
        sensor_mount=sensor_mount_from_offset(spec.flange_frame, sensor_offset),
        package_dirs=[str(share)],
        locked_joints=spec.locked_joints or None,
    )


def _load_ur(name: str, sensor_offset=None, tool_frame: str | None = None) -> Arm:
    """The ``--robot`` loader of a UR arm: :func:`~ftkin.kinematics.ur_eseries.ur_arm` with the
    sensor offset of :func:`sensor_mount_from_offset` on ``tool0``.
    """
    return ur_arm(name, sensor_mount_from_offset(UR_FLANGE_FRAME, sensor_offset), tool_frame)


def _fr3(sensor_offset=None, tool_frame: str | None = None) -> Arm:
    from .fr3 import FR3_TOOL_FRAME, fr3_arm

    if sensor_offset is not None:
        raise InvalidInput(
            "the bundled FR3 has its sensor frame fr3_hand (the hand's mounting face); "
            "--sensor-offset is for robots without one"
        )
    return fr3_arm(tool_frame or FR3_TOOL_FRAME)


ROBOTS: dict[str, Callable[..., Arm]] = {
    DEFAULT_ROBOT: _bundled,
    "fr3": _fr3,
    **{name: functools.partial(_load_spec, spec) for name, spec in ROBOT_SPECS.items()},
    # UR e-Series, UR20, UR30: built from UR's DH parameters (no URDF), flange tool0
    **{name: functools.partial(_load_ur, name) for name in UR_DH},
}
"""Loaders by robot name; each takes an optional sensor offset and tool frame (see
:func:`load_robot`).
"""

FLANGE_FRAMES: dict[str, tuple[str, str | None]] = {
    DEFAULT_ROBOT: (BUNDLED_FLANGE_FRAME, None),
    "fr3": ("fr3_link8", "franka"),
    **{name: (spec.flange_frame, spec.controller) for name, spec in ROBOT_SPECS.items()},
    **{name: (UR_FLANGE_FRAME, "ur") for name in UR_DH},
}
"""``{robot name: (flange frame, controller family)}`` for every name of :data:`ROBOTS`."""


def register_robot(
    name: str, load: Callable[..., Arm], flange_frame: str, controller: str | None = None
) -> None:
    """Add a robot by name: its loader ``load(sensor_offset, tool_frame) -> Arm``, its flange
    frame (where the controller takes a payload) and controller family.
    """
    if controller is not None and controller not in CONTROLLERS:
        raise InvalidInput(f"controller must be one of {sorted(CONTROLLERS)}, got {controller!r}")
    ROBOTS[name] = load
    FLANGE_FRAMES[name] = (flange_frame, controller)


def flange_frame_name(arm: Arm, controller: str | None = None) -> str:
    """The frame the arm's controller takes a payload in (the flange): never guessed.

    * a robot loaded by name: the robot table's (:data:`FLANGE_FRAMES`); with ``controller``,
      a robot of another controller family is refused;
    * an arm from a URDF, with ``controller``: the one frame of the model that follows that
      controller's rule (:data:`CONTROLLERS`: ``<prefix>_link8`` for a Franka, ``tool0`` for a
      UR);
    * anything else is refused.

    Raises:
        InvalidInput: the frame is not known; the message names ``--flange-frame`` (Python:
            ``flange_frame=``).
    """
    name_it = "give it: --flange-frame NAME (Python: flange_frame=NAME)"
    rule = CONTROLLERS.get(controller) if controller is not None else None
    known = FLANGE_FRAMES.get(arm.robot_name or "")
    if known is not None:
        frame, family = known
        if rule is not None and family != controller:
            raise InvalidInput(
                f"a {controller} payload is expressed in {rule.description}, but this arm is "
                f"{arm.robot_name!r}"
                + (f" (a {family} robot)" if family else "")
                + f", whose flange is {frame!r}; export the payload format of its own "
                f"controller, or {name_it}"
            )
        return frame
    if rule is None:
        raise InvalidInput(
            f"the flange frame of this arm ({arm.urdf_path or 'a model'}) is not known: it is "
            "where the robot's controller takes the payload; " + name_it
        )
    found = rule.frames_in(arm.frame_names)
    if len(found) == 1:
        return found[0]
    raise InvalidInput(
        f"a {controller} payload is expressed in {rule.description}; this arm's model has "
        + (f"several such frames ({', '.join(found)})" if found else "no such frame")
        + f"; {name_it}"
    )


def load_robot(
    name: str,
    sensor_offset: Sequence[float] | SensorMount | None = None,
    tool_frame: str | None = None,
) -> Arm:
    """Load a robot by name (see :data:`ROBOTS`), sensor frame ``ft_sensor``.

    Args:
        name: ``ftkin_c4`` (bundled), ``fr3`` (bundled, sensor frame ``fr3_hand``) or an
            example-robot-data arm (``ur5``, ``panda``, ...).
        sensor_offset: Sensor origin and orientation in the flange frame:
            ``[x, y, z]`` [m] or ``[x, y, z, roll, pitch, yaw]`` [m, rad]
            (URDF rpy, ``R = Rz(yaw) Ry(pitch) Rx(roll)``); default: at the
            flange with its axes.
        tool_frame: Tool (control point) frame of the model, or None
            (the bundled arm: its ``tool`` frame).

    Raises:
        InvalidInput: unknown name (the message lists the known ones) or a bad offset.
        FrameNotFound: ``tool_frame`` is not a frame of the model.
        MissingDependency: example-robot-data is not installed (extra ``robots``).
    """
    if name not in ROBOTS:
        raise InvalidInput(f"unknown robot {name!r}; known robots: {', '.join(sorted(ROBOTS))}")
    arm = ROBOTS[name](sensor_offset, tool_frame)
    arm.robot_name = name
    return arm
