"""The IMU columns of a CSV, and files joined by time into IMU samples.

Columns: the wrench ``fx,fy,fz,mx,my,mz`` [N, N·m] (or the ROS spellings the samples CSV takes),
the accelerometer's specific force ``ax,ay,az`` [m/s²; ``accel_unit="g"`` for g] and the gyro's
``wx,wy,wz`` [rad/s], both in the IMU frame; an optional ``pose`` column (static poses) and a
time column ``t`` [s] (``time_unit`` for ms, µs or ns; or one alias naming its unit, see
:mod:`ftkin.io.time_columns`). Each file's role is read from its columns
(:func:`~ftkin.io.stream_join.stream_roles`), so the files may come in any order: one table with
everything, or a wrench log, an IMU log and an orientation log at their own rates
(:func:`~ftkin.io.stream_join.join_streams`). With an orientation ``qw,qx,qy,qz`` (or, given the
arm, its joint columns) the samples are fused: an orientation and the IMU
(:class:`~ftkin.calibration.fused_samples.FusedSamples`).
"""

import logging
from dataclasses import replace

import numpy as np

from ..calibration.fused_samples import FusedSamples
from ..calibration.imu_samples import ImuSamples, accel_unit_factor, check_specific_force_unit
from ..calibration.model import STANDARD_GRAVITY, WRENCH_CHANNELS
from ..calibration.samples import Samples
from ..exceptions import InvalidInput, InvalidSamples
from .column_spelling import ColumnSpelling, spelled_table
from .csv_table import read_header, read_table
from .static_segments import SegmentParameters, segment_index
from .stream_join import (
    ACCEL_COLUMNS,
    GYRO_COLUMNS,
    ORIENTATION_COLUMNS,
    JoinedStreams,
    Stream,
    join_streams,
)
from .time_columns import TIME_ALIASES, TIME_COLUMN, times_from_table

logger = logging.getLogger(__name__)


def _numeric(table, name: str) -> bool:
    try:
        float(table.rows[0][table.column_index(name)])
    except (ValueError, IndexError):
        return False
    return True


def read_stream(
    path,
    *,
    time_unit: str | None = None,
    accel_unit: str = "m/s^2",
    g: float = STANDARD_GRAVITY,
    allow_no_time: bool = False,
    spelling: ColumnSpelling | None = None,
) -> Stream:
    """One CSV as a :class:`~ftkin.io.stream_join.Stream`: its time [s] and numeric columns, the
    accelerometer converted to m/s² and checked (its median norm must be about ``g``).

    ``allow_no_time``: a table without a time column is read in row order (a single table of
    static poses), its stream's times the row numbers. Columns in other spellings and units in
    the header are read through :func:`~ftkin.io.column_spelling.spelled_table` (``time_unit``
    is its :attr:`~ftkin.io.column_spelling.ColumnSpelling.time_unit`; ``spelling``, when given,
    is the whole spelling, its own time unit included).

    Raises:
        InvalidSamples: no time column, a cell that is not a number, stamps that do not
            increase (with the line), an accelerometer in another unit than ``accel_unit``.
        InvalidInput: an unknown ``time_unit`` or ``accel_unit``.
    """
    factor = accel_unit_factor(accel_unit, g)
    spelling = spelling if spelling is not None else ColumnSpelling(time_unit=time_unit)
    table = spelled_table(read_table(path), spelling)
    times = times_from_table(table)
    if times is None:
        if not allow_no_time:
            raise InvalidSamples(
                "no time column: streams are joined on a column 't' (seconds, or time_unit)",
                table.source,
            )
        times = np.arange(len(table.rows), dtype=float)  # row order: one table, nothing to join
    timing = {TIME_COLUMN, *(name for name in table.header if name.lower() in TIME_ALIASES)}
    names = [name for name in table.header if name not in timing and _numeric(table, name)]
    values = table.floats(names) if names else np.zeros((len(table.rows), 0))
    columns = {name: values[:, i] for i, name in enumerate(names)}
    if all(name in columns for name in ACCEL_COLUMNS):
        accel = np.stack([columns[name] for name in ACCEL_COLUMNS], axis=1) * factor
        check_specific_force_unit(accel, g, accel_unit, table.source)
        for i, name in enumerate(ACCEL_COLUMNS):
            columns[name] = accel[:, i]
    return Stream(table.source, times, columns, np.asarray(table.lines))


def imu_samples_from_joined(joined: JoinedStreams, g: float = STANDARD_GRAVITY) -> ImuSamples:
    """:class:`ImuSamples` of joined streams (the wrench, the accelerometer, the gyro if any)."""
    for role in ("wrench", "accelerometer"):
        if not joined.has(role):
            raise InvalidSamples(
                f"no {role} columns among the files ({', '.join(joined.columns)}): a calibration "
                f"from the IMU needs {', '.join(WRENCH_CHANNELS)} and {', '.join(ACCEL_COLUMNS)}"
            )
    pose = joined.columns.get("pose")
    return ImuSamples(
        joined.array(ACCEL_COLUMNS),
        joined.array(WRENCH_CHANNELS),
        None if pose is None else pose,
        joined.array(GYRO_COLUMNS) if joined.has("gyro") else None,
        joined.times,
        g,
    )


def fused_samples_from_joined(
    imu: ImuSamples, joined: JoinedStreams, arm=None, rows=None
) -> FusedSamples:
    """:class:`~ftkin.calibration.fused_samples.FusedSamples` of joined streams that also hold an
    orientation (``qw,qx,qy,qz`` of the sensor in the base, slerped) or, with ``arm``, its joint
    angles (the arm's joint names or ``q1..qn`` [rad], interpolated linearly).

    ``imu`` holds the join's rows ``rows`` (indices; None: all of them), e.g. the still ones.

    Raises:
        InvalidSamples: both an orientation and the arm's joints, the arm's joints missing, or
            joint angles beyond ±2π (degrees).
    """
    names = [] if arm is None else _joint_columns(joined, arm)
    if joined.has("orientation") and names:
        raise InvalidSamples(
            f"both an orientation (qw,qx,qy,qz) and joint columns {names}: the orientation is "
            "ambiguous; drop one (or do not pass the arm)"
        )
    rows = slice(None) if rows is None else rows
    times, pose = imu.times, imu.pose_ids
    if names:
        joints = joined.array(names)[rows]
        if np.any(np.abs(joints) > 2.0 * np.pi + 0.01):
            raise InvalidSamples(
                f"joint columns {names} reach {float(np.max(np.abs(joints))):g}, outside ±2π: "
                "joint angles must be in radians (these look like degrees)"
            )
        samples = Samples.from_joint_positions(arm, joints, imu.wrenches, pose, times=times)
    else:
        quaternions = joined.array(ORIENTATION_COLUMNS)[rows]
        samples = Samples.from_quaternions(quaternions, imu.wrenches, pose, times=times)
    return FusedSamples(
        samples, imu.specific_force, imu.angular_velocity, imu.g, imu.accel_count_factor
    )


def _joint_columns(joined: JoinedStreams, arm) -> list[str]:
    """The arm's joint columns among the joined ones: its joint names, else ``q1..qn``."""
    for names in (list(arm.joint_names), [f"q{i + 1}" for i in range(arm.nq)]):
        if all(name in joined.columns for name in names):
            return names
    raise InvalidSamples(
        f"no joint columns for the arm among the files ({', '.join(joined.columns)}): expected "
        f"{', '.join(arm.joint_names)} or q1..q{arm.nq} [rad]"
    )


def load_imu_samples(
    *paths,
    time_unit: str | None = None,
    accel_unit: str = "m/s^2",
    g: float = STANDARD_GRAVITY,
    max_gap: float | None = None,
    gaps: str = "drop",
    spelling: ColumnSpelling | None = None,
    segments: SegmentParameters | None = None,
    arm=None,
) -> tuple[ImuSamples | FusedSamples, JoinedStreams]:
    """Read one or more CSVs (any order) and join them on time into :class:`ImuSamples`, or into
    :class:`~ftkin.calibration.fused_samples.FusedSamples` when the files also give an
    orientation (``qw,qx,qy,qz``) or, with ``arm``, its joint angles: ``ftkin.calibrate`` then
    fits both and checks the mount (:mod:`ftkin.calibration.fused_fit`).

    ``segments``: for a static calibration, how a timed table without a ``pose`` column is read
    (:mod:`ftkin.io.table_layout`, on the direction of the specific force, the IMU's own
    orientation signal): a continuous recording keeps only its still segments, one pose each;
    readings one or a few per pose get their pose ids. None (a dynamic calibration, a log to
    compensate) keeps every reading.

    Returns the samples and the join (its :attr:`~ftkin.io.stream_join.JoinedStreams.notes` say
    what was dropped or marked).
    """
    if not paths:
        raise InvalidInput("load_imu_samples needs at least one file")
    single = len(paths) == 1
    streams = [
        read_stream(
            p,
            time_unit=time_unit,
            accel_unit=accel_unit,
            g=g,
            allow_no_time=single,
            spelling=spelling,
        )
        for p in paths
    ]
    joined = join_streams(streams, max_gap=max_gap, gaps=gaps)
    samples, rows = imu_samples_from_joined(joined, g), None
    if segments is not None and "pose" not in joined.columns and _has_time(paths[0]) | (not single):
        samples = _still_poses(samples, segments, str(paths[0]))
        rows = np.searchsorted(joined.times, samples.times)  # the rows kept (stamps increase)
    if single and not _has_time(paths[0]):
        samples = ImuSamples(
            samples.specific_force,
            samples.wrenches,
            samples.pose_ids,
            samples.angular_velocity,
            None,
            samples.g,
        )
    factor = accel_count_factor(streams)
    if factor < 1.0:
        samples = replace(samples, accel_count_factor=factor)
    if joined.has("orientation") or arm is not None:
        return fused_samples_from_joined(samples, joined, arm, rows), joined
    return samples, joined


def accel_count_factor(streams) -> float:
    """Independent accelerometer readings per joined row (``ImuSamples.accel_count_factor``):
    1 when the accelerometer is in the wrench's file; else the ratio of the wrench's rate to the
    IMU's when the IMU is slower (its readings interpolated onto the wrench's stamps), times
    2/3, the variance a linear interpolation leaves of independent noise (the spread it shows)."""
    wrench = next((s for s in streams if all(n in s.columns for n in WRENCH_CHANNELS)), None)
    accel = next((s for s in streams if all(n in s.columns for n in ACCEL_COLUMNS)), None)
    if wrench is None or accel is None or wrench is accel:
        return 1.0
    ratio = wrench.period / accel.period
    return 1.0 if ratio >= 1.0 else ratio * 2.0 / 3.0


def _still_poses(samples: ImuSamples, segments: SegmentParameters, source: str) -> ImuSamples:
    """The static poses of timed IMU readings: the layout of the table read from the direction
    of the specific force (a still sensor keeps it; a turning one moves it)."""
    from .table_layout import RECORDING, table_layout

    force = samples.specific_force
    direction = force / np.linalg.norm(force, axis=1, keepdims=True)
    # an accelerometer is noisy (a joint encoder is not): the direction averaged over the speed
    # window, so that consecutive readings of a still sensor agree within the pose tolerance
    step = float(np.median(np.diff(samples.times))) if len(samples) > 1 else 1.0
    width = max(1, int(round(segments.speed_window / step)) if step > 0 else 1)
    if width > 1:
        kernel = np.ones(width) / width
        padded = np.pad(direction, ((width // 2, width - 1 - width // 2), (0, 0)), mode="edge")
        direction = np.stack([np.convolve(c, kernel, mode="valid") for c in padded.T], axis=1)
        # and the stillness threshold above the noise left: 8 × the speed of the stillest fifth
        from dataclasses import replace

        from .static_segments import joint_speed

        speed = joint_speed(samples.times, direction, segments.speed_window)
        floor = 8.0 * float(np.percentile(speed, 20))
        if floor > segments.speed_threshold:
            segments = replace(segments, speed_threshold=floor)
    layout = table_layout(
        samples.times, direction, segments, "specific-force direction speed", source
    )
    logger.info("%s: %s", source, layout.describe())
    if layout.kind != RECORDING:
        keep, pose_ids = np.arange(len(samples)), layout.pose_ids
    else:
        index = segment_index(samples.times, layout.search.segments)
        keep = np.flatnonzero(index >= 0)
        pose_ids = index[keep]
    gyro = samples.angular_velocity
    return ImuSamples(
        samples.specific_force[keep],
        samples.wrenches[keep],
        pose_ids,
        None if gyro is None else gyro[keep],
        samples.times[keep],
        samples.g,
    )


def _has_time(path) -> bool:
    header = read_header(path)
    return TIME_COLUMN in header or any(name.lower() in TIME_ALIASES for name in header)


def with_imu_columns(
    loaded, *, accel_unit: str = "m/s^2", g: float = STANDARD_GRAVITY
) -> Samples | FusedSamples:
    """The samples of a CSV read with an orientation (:func:`~ftkin.io.samples_csv.load_samples`),
    with the table's IMU too when it has ``ax,ay,az`` (and ``wx,wy,wz``):
    :class:`~ftkin.calibration.fused_samples.FusedSamples`, whose calibration fits the orientation
    and the IMU together and checks the mount (:mod:`ftkin.calibration.fused_fit`). A table
    without them, and a bag, give ``loaded.samples`` as read.

    The one rule of ``ftkin calibrate FILE``, ``ftkin record`` and ``ftkin robot calibrate``: a
    file with IMU columns is calibrated the same way whoever wrote it.

    Args:
        loaded: A :class:`~ftkin.io.samples_csv.LoadedSamples`.
        accel_unit: The unit of ``ax,ay,az``: ``"m/s^2"`` or ``"g"`` (a table that states its
            own, a join's, keeps it).
        g: Gravity [m/s²].
    """
    table = loaded.table
    if loaded.recording is not None or not all(name in table.header for name in ACCEL_COLUMNS):
        return loaded.samples
    gyro = table.floats(GYRO_COLUMNS) if all(n in table.header for n in GYRO_COLUMNS) else None
    unit = table.accel_unit or accel_unit  # a join's table is converted already
    return FusedSamples.from_arrays(
        loaded.samples, table.floats(ACCEL_COLUMNS), accel_unit=unit, angular_velocity=gyro, g=g
    )
