"""Robot models by name: ``--robot NAME`` on the command line.

``ftkin_c4`` is the bundled six-axis arm (default, sensor frame ``ft_sensor``
already in its URDF). The other names load a URDF from the
``example-robot-data`` wheel (optional extra ``robots``) and add the sensor
frame ``ft_sensor`` at the robot's flange (``tool0`` for the UR arms,
``panda_link8`` for the Panda, ...), optionally offset by a translation [m] and
roll-pitch-yaw [rad] in the flange frame. Grippers' finger joints are locked so
``q`` holds only the arm joints.

The wheel ships no Python loader: its files are found through the installed
distribution's file list (``share/example-robot-data/package.xml``), and the
``share`` folder is the package directory ``package://`` mesh URIs resolve
against.
"""

import functools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, UrdfError
from ..validation import as_float_array
from .arm import Arm, SensorMount
from .ur_eseries import UR_DH, load_ur

DEFAULT_ROBOT = "ftkin_c4"
BUNDLED_FLANGE_FRAME = "flange"
"""The bundled arm's flange frame (z out of the flange face)."""
SENSOR_FRAME = "ft_sensor"
_DISTRIBUTION = "example-robot-data"


@dataclass(frozen=True)
class RobotSpec:
    """Where an example-robot-data arm's URDF and flange are.

    Attributes:
        name: The ``--robot`` name.
        urdf: URDF path relative to ``share/example-robot-data/robots``.
        flange_frame: Frame the sensor is bolted to (z out of the flange).
        locked_joints: Joints fixed at a value [rad or m] (gripper fingers).
        description: One line for listings.
    """

    name: str
    urdf: str
    flange_frame: str
    locked_joints: dict[str, float] = field(default_factory=dict)
    description: str = ""


ROBOT_SPECS: dict[str, RobotSpec] = {
    spec.name: spec
    for spec in (
        RobotSpec(
            "ur3", "ur_description/urdf/ur3_robot.urdf", "tool0", description="Universal Robots UR3"
        ),
        RobotSpec(
            "ur5", "ur_description/urdf/ur5_robot.urdf", "tool0", description="Universal Robots UR5"
        ),
        RobotSpec(
            "ur10",
            "ur_description/urdf/ur10_robot.urdf",
            "tool0",
            description="Universal Robots UR10",
        ),
        RobotSpec(
            "panda",
            "panda_description/urdf/panda.urdf",
            "panda_link8",
            {"panda_finger_joint1": 0.0, "panda_finger_joint2": 0.0},
            "Franka Emika Panda (7 joints; fingers locked)",
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


ROBOTS: dict[str, Callable[..., Arm]] = {
    DEFAULT_ROBOT: _bundled,
    **{name: functools.partial(_load_spec, spec) for name, spec in ROBOT_SPECS.items()},
    # UR e-Series, UR20, UR30: built from UR's DH parameters (no URDF), flange tool0
    **{name: functools.partial(load_ur, name) for name in UR_DH},
}
"""Loaders by robot name; each takes an optional sensor offset and tool frame (see
:func:`load_robot`).
"""


def flange_frame_name(arm: Arm) -> str:
    """The arm's flange frame, from the robot table (:data:`ROBOT_SPECS`).

    A robot loaded by name: its spec's ``flange_frame``. An arm from a URDF: the first flange
    frame of the table (the bundled arm's ``flange`` first) that its model has, else the frame
    the sensor frame hangs from.
    """
    spec = ROBOT_SPECS.get(arm.robot_name or "")
    if spec is not None:
        return spec.flange_frame
    for name in (BUNDLED_FLANGE_FRAME, *(spec.flange_frame for spec in ROBOT_SPECS.values())):
        if arm.model.existFrame(name):
            return name
    return arm.model.frames[arm.model.frames[arm.sensor_frame_id].parentFrame].name


def load_robot(
    name: str,
    sensor_offset: Sequence[float] | SensorMount | None = None,
    tool_frame: str | None = None,
) -> Arm:
    """Load a robot by name (see :data:`ROBOTS`), sensor frame ``ft_sensor``.

    Args:
        name: ``ftkin_c4`` (bundled) or an example-robot-data arm (``ur5``, ``panda``, ...).
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
