"""Arguments and helpers several subcommands share."""

import argparse
import logging
from pathlib import Path

from .. import Arm, FrameNotFound, InvalidInput, load_samples
from ..kinematics import bundled_urdf_path
from ..kinematics.robots import (
    DEFAULT_ROBOT,
    ROBOT_SPECS,
    ROBOTS,
    load_robot,
    sensor_mount_from_offset,
)
from .arg_types import (
    add_options,
    bounded_int,
    non_negative_float,
    number_list,
    option,
    positive_float,
    refuse,
)
from .declared import add_declared, declared_values
from .shared_options import WRENCH_FRAME

logger = logging.getLogger("ftkin.cli")


def add_arm_arguments(parser: argparse.ArgumentParser) -> None:
    """``--urdf``, ``--sensor-frame``, ``--tool-frame`` (default: the bundled arm)."""
    group = parser.add_argument_group("robot model (for joint-angle columns)")
    add_options(
        group,
        option(
            "--robot",
            metavar="NAME",
            help=f"robot by name: {', '.join(ROBOTS)} (default: {DEFAULT_ROBOT}, the bundled arm)",
        ),
        option(
            "--urdf",
            metavar="PATH",
            help="URDF of the arm (default: the bundled six-axis arm; ftkin robot and record "
            "--franka: the bundled FR3)",
        ),
        option(
            "--sensor-frame",
            default=None,
            metavar="NAME",
            help="sensor frame name (default: ft_sensor; the bundled FR3's: fr3_hand)",
        ),
        option(
            "--tool-frame", default=None, metavar="NAME", help="tool / control-point frame name"
        ),
        option(
            "--sensor-offset",
            type=number_list,
            metavar="X Y Z [R P Y]",
            help="with --robot: sensor origin in the flange frame, X Y Z [m] and optionally ROLL "
            "PITCH YAW [rad] "
            "(with --urdf and --sensor-parent: the same, relative to that frame)",
        ),
        option(
            "--sensor-parent",
            metavar="FRAME",
            help="with --urdf: add the sensor frame at this existing frame (for URDFs without one)",
        ),
        option(
            "--package-dir",
            action="append",
            default=[],
            metavar="DIR",
            help="folder that package:// mesh URIs resolve against (collision checks, 3D view; "
            "repeatable)",
        ),
    )


def arm_from_args(args: argparse.Namespace) -> Arm | None:
    """The arm the arguments name, or None when none was named (bundled arm used on demand).

    Frame options are checked against the arm whichever way it is named: a
    ``--sensor-frame`` or ``--tool-frame`` that the model lacks is a
    :class:`~ftkin.exceptions.FrameNotFound` listing its frames.
    """
    urdf, robot = getattr(args, "urdf", None), getattr(args, "robot", None)
    offset = getattr(args, "sensor_offset", None)
    parent = getattr(args, "sensor_parent", None)
    sensor_frame = getattr(args, "sensor_frame", None)
    tool_frame = getattr(args, "tool_frame", None)
    package_dirs = list(getattr(args, "package_dir", None) or [])
    refuse(
        InvalidInput,
        *(
            (
                getattr(args, name, None) is not None and not str(getattr(args, name)).strip(),
                f"--{name.replace('_', '-')} is empty; give a name or leave the option out",
            )
            for name in ("urdf", "robot", "sensor_frame", "tool_frame", "sensor_parent")
        ),
        *(
            (not str(folder).strip(), "--package-dir is empty; give a folder or leave it out")
            for folder in package_dirs
        ),
        (urdf and robot, "give either --urdf or --robot, not both"),
        (
            offset is not None and len(offset) not in (3, 6),
            "--sensor-offset takes 3 numbers (X Y Z [m]) or 6 (and ROLL PITCH YAW [rad]), got "
            f"{len(offset or ())}",
        ),
        (
            urdf and parent is None and offset is not None,
            "--sensor-offset with --urdf needs --sensor-parent FRAME (the frame the sensor is "
            "bolted to)",
        ),
        (
            not urdf and parent is not None,
            "--sensor-parent is for --urdf; with --robot the sensor is mounted at the robot's "
            "flange",
        ),
        (
            robot and sensor_frame not in (None, "ft_sensor"),  # (--robot and --urdf: refused)
            "--sensor-frame is for --urdf; --robot names its sensor frame ft_sensor (move it "
            "with --sensor-offset)",
        ),
        (
            offset is not None and not (urdf or robot),
            "--sensor-offset needs --robot NAME (or --urdf with --sensor-parent)",
        ),
    )
    if urdf:
        mount = None if parent is None else sensor_mount_from_offset(parent, offset)
        return Arm.from_urdf(
            urdf,
            sensor_frame or "ft_sensor",
            tool_frame,
            sensor_mount=mount,
            package_dirs=package_dirs,
        )
    if robot:
        arm = load_robot(robot, offset, tool_frame)
        arm.package_dirs += package_dirs
        return arm
    if sensor_frame not in (None, "ft_sensor") or tool_frame is not None:
        return Arm.from_urdf(bundled_urdf_path(), sensor_frame or "ft_sensor", tool_frame or "tool")
    return None


def add_column_arguments(parser: argparse.ArgumentParser) -> None:
    """``--column NAME=COLUMN`` and ``--time-unit``: how a file spells ftkin's columns
    (:class:`~ftkin.io.column_spelling.ColumnSpelling`)."""
    from ..io.column_spelling import ColumnSpelling

    add_declared(
        parser,
        ColumnSpelling,
        group="columns in other spellings (Fx..Tz, force.x and units in the header such as "
        "'Fx (lbf)' are read without options)",
    )


def column_spelling_from_args(args: argparse.Namespace):
    """The :class:`~ftkin.io.column_spelling.ColumnSpelling` of :func:`add_column_arguments`."""
    from ..io.column_spelling import ColumnSpelling

    return ColumnSpelling(**declared_values(ColumnSpelling, args))


def add_stream_arguments(parser: argparse.ArgumentParser) -> None:
    """``--accel-unit``, ``--max-gap``, ``--gaps``: IMU columns and files joined on time
    (:class:`~ftkin.io.joined_files.StreamReading`)."""
    from ..io.joined_files import StreamReading

    add_declared(
        parser,
        StreamReading,
        group="IMU columns (ax,ay,az [m/s²], wx,wy,wz [rad/s]) and several files joined on time",
    )


def stream_reading_from_args(args: argparse.Namespace):
    """The :class:`~ftkin.io.joined_files.StreamReading` of :func:`add_stream_arguments`."""
    from ..io.joined_files import StreamReading

    return StreamReading(**declared_values(StreamReading, args))


def input_paths(value) -> list[str]:
    """The files of a ``FILE [FILE ...]`` positional (one name or a list)."""
    return [value] if isinstance(value, str) else list(value)


def add_samples_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments about how a samples file or a ROS 2 bag is read."""
    add_arm_arguments(parser)
    add_column_arguments(parser)
    add_stream_arguments(parser)
    from ..io.static_segments import SegmentParameters

    defaults = SegmentParameters()
    add_options(
        parser.add_argument_group(
            "ROS 2 bags (a rosbag2 folder, .mcap or .db3 instead of a CSV; needs ftkin[bags]) and "
            "continuous recordings (a CSV with a time column and no pose column)"
        ),
        option(
            "--all-rows", action="store_true", help="every reading its own pose: no still segments"
        ),
        option(
            "--joint-topic",
            metavar="TOPIC",
            help="sensor_msgs/JointState topic (default: the only one)",
        ),
        option(
            "--wrench-topic",
            metavar="TOPIC",
            help="geometry_msgs/WrenchStamped topic (default: the only one)",
        ),
        WRENCH_FRAME,
        option(
            "--speed-threshold",
            type=positive_float,
            default=defaults.speed_threshold,
            metavar="RAD_S",
            help="static when every joint (every R_BS entry of a CSV without joint columns) is "
            "slower than this [rad/s] (default: %(default)s)",
        ),
        option(
            "--min-static-duration",
            type=positive_float,
            default=defaults.min_duration,
            metavar="S",
            help="shortest usable static segment after settling [s] (default: %(default)s)",
        ),
        option(
            "--settle-time",
            type=non_negative_float,
            default=defaults.settle_time,
            metavar="S",
            help="time skipped at the start of each static segment [s] (default: %(default)s)",
        ),
        option(
            "--speed-window",
            type=positive_float,
            default=defaults.speed_window,
            metavar="S",
            help="time span of the joint-speed finite difference [s] (default: %(default)s)",
        ),
    )


# Option rows (arg_types.option) shared by several commands: --allow-other-arm for the commands
# that apply a calibration with the arm it records, --sg-window for the zero-phase derivatives of a
# moving recording.
ALLOW_OTHER_ARM = option(
    "--allow-other-arm",
    action="store_true",
    help="accept robot options that differ from the arm recorded in the calibration "
    "(deliberate reuse)",
)

SG_WINDOW = option(
    "--sg-window",
    type=bounded_int(3, 100_001, "samples"),
    default=None,
    metavar="SAMPLES",
    help="odd Savitzky–Golay window for joint velocities and accelerations (default: about 51 ms)",
)


def arm_for_calibration(args: argparse.Namespace, calibration) -> Arm | None:
    """The arm to read joint angles with when applying ``calibration``.

    The options given win; without any, the arm recorded in the calibration
    file (robot or URDF, sensor parent and offset) is rebuilt, so a log is
    compensated with the kinematics it was calibrated with; older files give
    their URDF and sensor frame. Returns None when nothing is named or
    recorded (the bundled arm is then used on demand).
    """
    if (arm := arm_from_args(args)) is not None:
        return arm
    if calibration.kinematics is not None:
        # the calibration says how its sensor frame was obtained: no options to repeat
        return calibration.kinematics.build_arm(list(getattr(args, "package_dir", None) or []))
    if not calibration.urdf:
        return None
    recorded = Path(calibration.urdf)
    if not recorded.is_file() or recorded.resolve() == bundled_urdf_path().resolve():
        return None
    try:
        return Arm.from_urdf(recorded, calibration.sensor_frame or "ft_sensor")
    except FrameNotFound:
        names = [
            name for name, spec in ROBOT_SPECS.items() if recorded.as_posix().endswith(spec.urdf)
        ]
        hint = (
            f"--robot {names[0]} (and the --sensor-offset used, if any)"
            if names
            else "--urdf with --sensor-parent"
        )
        raise InvalidInput(
            f"the calibration was made with {recorded} and a sensor frame "
            f"{calibration.sensor_frame!r} that the URDF "
            "does not contain (it was added when calibrating): give the same robot options as for "
            f"the calibration: {hint}"
        ) from None


def arm_of_calibration(args: argparse.Namespace, calibration) -> Arm | None:
    """The arm of :func:`arm_for_calibration`, or the bundled arm when the calibration was made
    on it; None when the calibration records no arm (made from orientation columns or the IMU)
    and no robot option names one. The library then refuses what needs the arm (joint angles or a
    flange of another arm would give a wrong result in silence), naming ``arm=`` and the flags:
    :class:`~ftkin.control.compensation.Compensator`, :func:`~ftkin.io.export.export_request`.
    """
    arm = arm_for_calibration(args, calibration)
    if arm is not None:
        return arm
    if calibration.urdf and Path(calibration.urdf).resolve() == bundled_urdf_path().resolve():
        return Arm.default()
    return None


def segment_parameters_from_args(args: argparse.Namespace):
    """The :class:`~ftkin.io.static_segments.SegmentParameters` of :func:`add_samples_arguments`
    (how still segments of a recording are found), or None with ``--all-rows``."""
    from ..io.static_segments import SegmentParameters

    if args.all_rows:
        return None
    return SegmentParameters(
        speed_threshold=args.speed_threshold,
        min_duration=args.min_static_duration,
        settle_time=args.settle_time,
        speed_window=args.speed_window,
    )


def load_samples_from_args(
    path,
    args: argparse.Namespace,
    *,
    static_only: bool = True,
    arm: Arm | None = None,
    g: float | None = None,
):
    """Read a samples CSV or a ROS 2 bag named on the command line (``path``: one file, or several
    CSVs joined on time, :mod:`ftkin.io.joined_files`).

    Returns a :class:`~ftkin.io.samples_csv.LoadedSamples` (a :class:`~ftkin.io.bags.BagSamples`
    for a bag). ``static_only`` (off with ``--all-rows``) applies to bags and continuous
    recordings: True keeps the readings of the static segments (calibration), False every
    reading (compensation). ``arm`` overrides the arm the options name (see
    :func:`arm_for_calibration`). ``g`` [m/s²] is what an accelerometer among joined files is
    checked against (``--g``, or the calibration's; default standard gravity).
    """
    from ..io.bags import bag_samples, is_bag_path
    from ..io.static_segments import SegmentParameters

    arm = arm_from_args(args) if arm is None else arm
    static_only = static_only and not args.all_rows
    parameters = segment_parameters_from_args(args) or SegmentParameters()
    segments = parameters if static_only else None
    paths = input_paths(path)
    if len(paths) > 1:  # several files, each on its own clock: joined on time, then one table
        from ..calibration.model import STANDARD_GRAVITY
        from ..io.joined_files import joined_table
        from ..io.samples_csv import samples_from_table

        table, joined = joined_table(
            paths,
            spelling=column_spelling_from_args(args),
            reading=stream_reading_from_args(args),
            g=STANDARD_GRAVITY if g is None else g,
        )
        print(f"joined {len(paths)} files on time: {len(table.rows)} rows at the wrench's stamps")
        loaded, path = samples_from_table(table, arm, segments), table.source
    elif not is_bag_path(path := paths[0]):
        loaded = load_samples(path, arm, segments, column_spelling_from_args(args))
    else:
        loaded = bag_samples(
            path,
            arm,
            joint_topic=args.joint_topic,
            wrench_topic=args.wrench_topic,
            parameters=parameters,
            static_only=static_only,
            wrench_frame=args.wrench_frame or "sensor",
        )
    if loaded.layout is not None:  # how the table was read: poses, or a recording's segments
        print(f"{path}: {loaded.layout.describe()}")
    elif loaded.search is not None:  # a bag's still segments
        print(f"{path}: {loaded.search.describe()}")
    return loaded
