"""The IMU columns of a CSV, and files joined by time into IMU samples.

Columns: the wrench ``fx,fy,fz,mx,my,mz`` [N, N·m] (or the ROS spellings the samples CSV takes),
the accelerometer's specific force ``ax,ay,az`` [m/s²; ``accel_unit="g"`` for g] and the gyro's
``wx,wy,wz`` [rad/s], both in the IMU frame; an optional ``pose`` column (static poses) and a
time column ``t`` [s] (``time_unit`` for ms, µs or ns; or one alias naming its unit, see
:mod:`ftkin.io.time_columns`). Each file's role is read from its columns
(:func:`~ftkin.io.stream_join.stream_roles`), so the files may come in any order: one table with
everything, or a wrench log, an IMU log and an orientation log at their own rates
(:func:`~ftkin.io.stream_join.join_streams`).
"""

import numpy as np

from ..calibration.imu_samples import ImuSamples, accel_unit_factor, check_specific_force_unit
from ..calibration.model import STANDARD_GRAVITY, WRENCH_CHANNELS
from ..exceptions import InvalidInput, InvalidSamples
from .column_spelling import ColumnSpelling, spelled_table
from .csv_table import read_table
from .stream_join import ACCEL_COLUMNS, GYRO_COLUMNS, JoinedStreams, Stream, join_streams
from .time_columns import TIME_ALIASES, TIME_COLUMN, times_from_table


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
) -> Stream:
    """One CSV as a :class:`~ftkin.io.stream_join.Stream`: its time [s] and numeric columns, the
    accelerometer converted to m/s² and checked (its median norm must be about ``g``).

    ``allow_no_time``: a table without a time column is read in row order (a single table of
    static poses), its stream's times the row numbers. Columns in other spellings and units in
    the header are read through :func:`~ftkin.io.column_spelling.spelled_table` (``time_unit``
    is its :attr:`~ftkin.io.column_spelling.ColumnSpelling.time_unit`).

    Raises:
        InvalidSamples: no time column, a cell that is not a number, stamps that do not
            increase (with the line), an accelerometer in another unit than ``accel_unit``.
        InvalidInput: an unknown ``time_unit`` or ``accel_unit``.
    """
    factor = accel_unit_factor(accel_unit, g)
    table = spelled_table(read_table(path), ColumnSpelling(time_unit=time_unit))
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


def load_imu_samples(
    *paths,
    time_unit: str | None = None,
    accel_unit: str = "m/s^2",
    g: float = STANDARD_GRAVITY,
    max_gap: float | None = None,
    gaps: str = "drop",
) -> tuple[ImuSamples, JoinedStreams]:
    """Read one or more CSVs (any order) and join them on time into :class:`ImuSamples`.

    Returns the samples and the join (its :attr:`~ftkin.io.stream_join.JoinedStreams.notes` say
    what was dropped or marked).
    """
    if not paths:
        raise InvalidInput("load_imu_samples needs at least one file")
    single = len(paths) == 1
    streams = [
        read_stream(p, time_unit=time_unit, accel_unit=accel_unit, g=g, allow_no_time=single)
        for p in paths
    ]
    joined = join_streams(streams, max_gap=max_gap, gaps=gaps)
    samples = imu_samples_from_joined(joined, g)
    if single and not _has_time(paths[0]):
        samples = ImuSamples(
            samples.specific_force,
            samples.wrenches,
            samples.pose_ids,
            samples.angular_velocity,
            None,
            samples.g,
        )
    return samples, joined


def _has_time(path) -> bool:
    header = read_table(path).header
    return TIME_COLUMN in header or any(name.lower() in TIME_ALIASES for name in header)
