"""Several files as one table: each file's role read from its columns, joined on time.

``ftkin calibrate`` and ``ftkin compensate`` take any number of CSVs (``FILE [FILE ...]``, in any
order): a wrench log, an IMU log, an orientation or joint log, each on its own clock. Each file is
read through its spelling (:mod:`ftkin.io.column_spelling`), its role named by its columns
(:func:`~ftkin.io.stream_join.stream_roles`: wrench ``fx..mz``, accelerometer ``ax,ay,az``, gyro
``wx,wy,wz``, orientation ``qw..qz``, anything else joints), and the files are joined on their time
column at the wrench's rate (:func:`~ftkin.io.stream_join.join_streams`: slerp for orientations,
linear for the rest; the overlap only; gaps dropped or marked). The result is a :class:`Table` in
ftkin's columns, which the samples and log readers take as a file of their own.

:class:`StreamReading` holds the options (declared once: ``--accel-unit``, ``--max-gap``,
``--gaps``); :func:`imu_only` tells whether the files are a calibration from the IMU (an
accelerometer and no orientation).
"""

from dataclasses import dataclass

import numpy as np

from ..calibration.model import STANDARD_GRAVITY
from ..exceptions import InvalidInput, InvalidSamples
from ..options import number, option
from .column_spelling import ColumnSpelling, spelled_header
from .csv_table import Table, format_float
from .imu_columns import read_stream
from .stream_join import ACCEL_COLUMNS, GAP_POLICIES, JoinedStreams, join_streams
from .time_columns import TIME_COLUMN

ACCEL_UNITS = ("m/s^2", "g")


@dataclass(frozen=True)
class StreamReading:
    """How IMU columns and files on their own clocks are read.

    Attributes:
        accel_unit: Unit of ``ax,ay,az``: ``"m/s^2"`` or ``"g"`` (checked against the data: the
            median norm of the specific force at rest must be about g).
        max_gap: Longest step between two stamps of a file before the rows in between have no data
            [s]; None: five of its median periods.
        gaps: ``"drop"`` the rows inside a gap, or ``"mark"`` them (a column ``in_gap``).
    """

    accel_unit: str = option(
        "m/s^2",
        "unit of the accelerometer columns ax,ay,az (specific force, IMU frame; at rest it reads "
        "+g upward): m/s^2 or g",
        choices=ACCEL_UNITS,
    )
    max_gap: float | None = option(
        None,
        "longest step between two stamps of a file before the rows in between have no data "
        "(default: five of its median periods)",
        unit="s",
        parse=number(0.0, above=True),
        metavar="S",
    )
    gaps: str = option(
        "drop",
        "rows where a file has a gap longer than --max-gap: drop them, or mark them (a column "
        "in_gap)",
        choices=GAP_POLICIES,
    )

    def __post_init__(self):
        if self.accel_unit not in ACCEL_UNITS:
            raise InvalidInput(
                f"accel_unit must be one of {', '.join(ACCEL_UNITS)}, got {self.accel_unit!r}"
            )
        if self.gaps not in GAP_POLICIES:
            raise InvalidInput(f"gaps must be one of {', '.join(GAP_POLICIES)}, got {self.gaps!r}")
        if self.max_gap is not None and not (np.isfinite(self.max_gap) and self.max_gap > 0):
            raise InvalidInput(f"max_gap must be a positive number of seconds, got {self.max_gap}")


def imu_only(paths, spelling: ColumnSpelling | None = None, joint_names=()) -> bool:
    """Whether the files hold an accelerometer and no orientation at all: no Euler, quaternion or
    rotation-matrix column, no ``q1..qn`` and none of ``joint_names`` (the arm's): a calibration
    from the IMU alone."""
    import re

    from .samples_csv import EULER_COLUMNS, MATRIX_COLUMNS, QUATERNION_COLUMNS

    headers = [spelled_header(path, spelling) for path in paths]
    columns = {name for header in headers for name in header}
    accel = any(all(name in header for name in ACCEL_COLUMNS) for header in headers)
    oriented = columns & set(
        EULER_COLUMNS + QUATERNION_COLUMNS + MATRIX_COLUMNS + tuple(joint_names)
    )
    generic = any(re.fullmatch(r"q\d+", name) for name in columns)
    return accel and not oriented and not generic


JOINED_ACCEL_UNIT = "m/s^2"
"""The unit of ``ax,ay,az`` in a :func:`joined_table` (whatever the files' own)."""


def joined_table(
    paths,
    *,
    spelling: ColumnSpelling | None = None,
    reading: StreamReading | None = None,
    g: float = STANDARD_GRAVITY,
) -> tuple[Table, JoinedStreams]:
    """The files joined on time as one :class:`Table` (``t`` first, then every file's columns;
    ``in_gap`` when gaps are marked), and the join (its ``notes`` say what was dropped).

    The table's values are in SI: ``t`` in seconds and the accelerometer ``ax,ay,az`` in m/s²
    (:data:`JOINED_ACCEL_UNIT`), converted from ``reading``'s units and checked against ``g``, so
    a reader of the table must not convert them again.

    Raises:
        InvalidSamples: no file holds the wrench or several do, a column in two files, files that
            do not overlap in time, stamps that do not increase (with the file and line).
    """
    reading = reading or StreamReading()
    if len(paths) < 2:
        raise InvalidInput("joined_table joins two or more files; read one file as it is")
    streams = [
        read_stream(path, accel_unit=reading.accel_unit, g=g, spelling=spelling) for path in paths
    ]
    joined = join_streams(streams, max_gap=reading.max_gap, gaps=reading.gaps)
    names = list(joined.columns)
    header = [TIME_COLUMN, *names] + (["in_gap"] if reading.gaps == "mark" else [])
    values = [joined.times, *(np.asarray(joined.columns[name], dtype=float) for name in names)]
    rows = [[format_float(value) for value in row] for row in zip(*values)]
    if reading.gaps == "mark":
        rows = [[*row, str(int(flag))] for row, flag in zip(rows, joined.in_gap)]
    if not rows:
        raise InvalidSamples("the files share no time: nothing to join", str(paths[0]))
    source = " + ".join(str(path) for path in paths)
    table = Table(source, header, rows, list(range(2, len(rows) + 2)), 1, JOINED_ACCEL_UNIT)
    return table, joined
