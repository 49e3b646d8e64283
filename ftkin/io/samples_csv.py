"""Samples CSV: the columns of a calibration table and how they become :class:`Samples`.

A samples CSV has a header row (lines starting with ``#`` are comments), the
raw wrench columns ``fx,fy,fz,mx,my,mz`` [N, N·m], and the sensor orientation
in exactly one convention:

* joint columns: the URDF's joint names, or ``q1..qn`` in joint order [rad];
* ``alpha,beta,gamma``: the paper's commanded Euler angles [deg],
  ``R_BS = Rz(α) Ry(β) Rx(γ)``;
* ``qw,qx,qy,qz``: unit quaternion of the sensor frame in the base frame;
* ``r11,r12,...,r33``: the nine entries of ``R_BS``, row-major (``r12`` is row 1, column 2),
  orthonormal within 1e-3 (then re-orthonormalized).

Columns in other spellings (``Fx..Tz``, ``force.x``, units in the header such as ``Fx (lbf)``,
``--column NAME=COLUMN``, ``--time-unit``) are read through
:mod:`ftkin.io.column_spelling` first.

An optional integer ``pose`` column groups repeated readings of one pose; an
optional ``t`` column gives each reading's time [s] (a drifting bias is then
modelled, see :mod:`ftkin.calibration.drift`); without ``t``, one column named
``time``, ``time_s``, ``t_s``, ``timestamp``, ``stamp`` or ``%time`` is read as
it [s], and ``t_ms``/``time_ms``, ``t_us``/``time_us``, ``t_ns``/``time_ns``
are converted from the unit their name gives.
Other columns are carried along untouched (``ftkin compensate`` copies them).

A table with a time column and no ``pose`` column is read as a *pose table* or a
*continuous recording* from how its rows were taken (:mod:`ftkin.io.table_layout`: a
recorder's steady steps of at most 0.25 s, rows repeating an orientation within noise). A
pose table keeps every row, consecutive rows at one orientation being one pose. A continuous
recording (the arm moving between still phases) is cut into its still segments, found from
the orientation by the bag reader's algorithm (:mod:`ftkin.io.static_segments`), each one
pose, the moving rows left out. This happens when ``segments``
(:class:`~ftkin.io.static_segments.SegmentParameters`) is given: ``ftkin calibrate``,
``report``, ``extract`` and ``view`` give it unless ``--all-rows``. Without it (the library's
default: a log to compensate is read whole) every row is kept. A recording in motion with no
usable still segment is refused. ``LoadedSamples.layout`` says how the table was read.
"""

import logging
import re
from dataclasses import dataclass, replace

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..calibration.samples import Samples
from ..exceptions import InvalidSamples
from ..kinematics.joint_units import degrees_for_radians
from ..kinematics.rotations import (
    euler_zyx_deg_to_matrix,
    matrix_entries_to_matrix,
    quaternion_to_matrix,
)
from ..validation import MAX_ID, MAX_WRENCH, as_names
from .column_spelling import ColumnSpelling, spelled_table
from .csv_table import Table, missing_columns, read_table
from .recorded_robot import check_recorded_robot
from .static_segments import SegmentParameters, SegmentSearch, segment_index
from .table_layout import POSE_COLUMN_LAYOUT, RECORDING, TableLayout, table_layout
from .time_columns import times_from_table

logger = logging.getLogger(__name__)

EULER_COLUMNS = ("alpha", "beta", "gamma")
QUATERNION_COLUMNS = ("qw", "qx", "qy", "qz")
MATRIX_COLUMNS = tuple(f"r{row}{column}" for row in (1, 2, 3) for column in (1, 2, 3))
"""``r11, r12, ..., r33``: the entries of ``R_BS``, row-major (``r12``: row 1, column 2)."""
POSE_COLUMN = "pose"
_GENERIC_JOINT = re.compile(r"^q(\d+)$")
_ANGLE_COLUMNS = {
    "euler": (EULER_COLUMNS, "Euler angle"),
    "quaternion": (QUATERNION_COLUMNS, "quaternion"),
    "matrix": (MATRIX_COLUMNS, "rotation matrix"),
}
MAX_POSE_ID = MAX_ID
"""Largest pose id magnitude: every integer up to it is exact in a float64 cell."""


def detect_orientation(table: Table, joint_names=None) -> tuple[str, list[str]]:
    """Which orientation convention the table uses: ``("joints"|"euler"|"quaternion", columns)``.

    Raises:
        InvalidSamples: none found, several mixed, or an incomplete set.
    """
    joint_names = None if joint_names is None else as_names(joint_names, "joint_names")
    header = table.header
    angles = {
        kind: [name for name in names if name in header]
        for kind, (names, _) in _ANGLE_COLUMNS.items()
    }
    generic = sorted(
        (name for name in header if _GENERIC_JOINT.match(name)), key=lambda n: int(n[1:])
    )
    named = [name for name in (joint_names or []) if name in header]
    if any(angles.values()):  # joint columns of any arm would be mixed in
        named = named or [name for name in header if "joint" in name.lower()]
    if named and generic and set(named) != set(generic):  # an arm whose joints are q1..qn
        raise InvalidSamples(
            f"both URDF joint-name columns {named} and generic columns {generic}; use one",
            table.source,
        )
    found = {kind: columns for kind, columns in angles.items() if columns}
    if named or generic:
        found["joints"] = named or generic
    if len(found) > 1:
        raise InvalidSamples(
            "mixed orientation conventions: "
            + "; ".join(f"{kind} columns {columns}" for kind, columns in found.items())
            + "; give exactly one of joint angles, alpha/beta/gamma or qw/qx/qy/qz",
            table.source,
        )
    if not found:
        _no_orientation(table, joint_names)
    kind = next(iter(found))
    if kind in _ANGLE_COLUMNS:
        columns, what = _ANGLE_COLUMNS[kind]
        missing_columns(table, columns, what)
        return kind, list(columns)
    if named:
        missing_columns(table, joint_names, "joint")
        return kind, list(joint_names)
    expected = [f"q{i + 1}" for i in range(len(joint_names or ()))]
    if joint_names is not None and generic != expected:
        raise InvalidSamples(
            f"joint columns {generic} do not match the arm's {len(joint_names)} joints; "
            f"expected {expected} or the URDF names {list(joint_names)}",
            table.source,
        )
    return kind, generic


def _no_orientation(table: Table, joint_names) -> None:
    """The :class:`InvalidSamples` for a table without orientation columns (hints at wrong arms)."""
    joints = (
        f"the arm's joint names {list(joint_names)} or q1..q{len(joint_names)}"
        if joint_names
        else "joint columns"
    )
    unknown = [name for name in table.header if "joint" in name.lower()]
    hint = (
        f"; columns {unknown} look like joint names but are not this arm's (wrong --urdf/--robot?)"
        if unknown
        else ""
    )
    raise InvalidSamples(
        f"no orientation columns: expected {joints} [rad], or alpha,beta,gamma [deg], or "
        f"qw,qx,qy,qz, or r11..r33 (R_BS row-major){hint}; the header has {table.header}",
        table.source,
        table.header_line,
    )


def check_radians(table: Table, columns, values: np.ndarray, arm=None) -> None:
    """Refuse joint angles that can only be degrees, with their line: the rule of
    :func:`~ftkin.kinematics.joint_units.degrees_for_radians` (``|q| > 2π``, or with ``arm``
    far outside its limits that degrees fit), which ``Samples.from_joint_positions`` applies too.
    """
    found = degrees_for_radians(arm, values, columns, "joint column")
    if found is not None:
        row, _, message = found
        raise InvalidSamples(message, table.source, table.lines[row])


def _refuse_beyond(table: Table, values: np.ndarray, limit: float, describe) -> None:
    """:class:`InvalidSamples` at the first cell of ``values`` ``(N, k)`` beyond ``±limit``:
    ``describe(row, column)``, its line.
    """
    bad = np.argwhere(np.abs(values) > limit)
    if bad.size:
        row, column = bad[0]
        raise InvalidSamples(describe(row, column), table.source, table.lines[row])


@dataclass(frozen=True)
class TableOrientations:
    """Sensor orientations read from a table's orientation columns.

    Attributes:
        rotations: ``(N, 3, 3)`` ``R_BS``, one per row.
        kind: ``"joints"``, ``"euler"`` or ``"quaternion"``.
        columns: The columns they came from.
        joint_positions: ``(N, nq)`` [rad] for joint columns, else None.
        arm: The arm used for joint columns, else None.
    """

    rotations: np.ndarray
    kind: str
    columns: list[str]
    joint_positions: np.ndarray | None = None
    arm: object = None


def orientations_from_table(table: Table, arm=None) -> TableOrientations:
    """The sensor orientation of every row, in whichever convention the table uses.

    Joint columns go through ``arm``'s forward kinematics (the bundled arm when
    ``arm`` is None); Euler angles [deg] and quaternions need no arm.

    Raises:
        InvalidSamples: no, mixed or incomplete orientation columns, non-numbers,
            joint angles in degrees, non-unit quaternions (with file and line).
    """
    from ..kinematics.arm import Arm

    angles = EULER_COLUMNS + QUATERNION_COLUMNS + MATRIX_COLUMNS
    if arm is None and not any(name in table.header for name in angles):
        arm = Arm.default()
    # with Euler or quaternion columns (no arm), any joint column is refused as mixed in
    kind, columns = detect_orientation(table, arm.joint_names if arm is not None else None)
    values = table.floats(columns)
    convert = {
        "euler": euler_zyx_deg_to_matrix,
        "quaternion": quaternion_to_matrix,
        "matrix": matrix_entries_to_matrix,
    }.get(kind)
    try:
        if convert is not None:
            return TableOrientations(convert(values).reshape(-1, 3, 3), kind, columns)
        check_radians(table, columns, values, arm)  # its line; the limits warned by Samples
        return TableOrientations(arm.rotation_sensor_to_base(values), kind, columns, values, arm)
    except InvalidSamples:
        raise
    except ValueError as error:  # InvalidInput from the converters: their index becomes the line
        row = None if convert is None else _first_refused_row(convert, values)
        if row is None:
            raise InvalidSamples(str(error), table.source) from None
        message = re.sub(rf" #{row}\b", "", str(error))  # "#2" (0-based) beside "line 4" misleads
        raise InvalidSamples(message, table.source, table.lines[row]) from None


def _first_refused_row(convert, values: np.ndarray) -> int | None:
    """The first row of ``values`` that ``convert`` refuses, or None (only on the error path: one
    row at a time)."""
    for row, value in enumerate(values):
        try:
            convert(value)
        except ValueError:
            return row
    return None


def configurations_from_table(table, arm) -> np.ndarray:
    """Joint angles ``(P, nq)`` [rad] of a poses table (``ftkin plan`` output), one per pose.

    Rows sharing a ``pose`` id are one pose (its first row is taken).
    """
    table = spelled_table(table)
    kind, columns = detect_orientation(table, arm.joint_names)
    if kind != "joints" or len(columns) != arm.nq:
        raise InvalidSamples(
            f"expected {arm.nq} joint columns ({', '.join(arm.joint_names)} or "
            f"q1..q{arm.nq}) [rad], found {kind} columns {columns}",
            table.source,
        )
    values = table.floats(columns)
    check_radians(table, columns, values, arm)
    if "pose" not in table.header:
        return values
    _, first = np.unique(table.floats(["pose"])[:, 0], return_index=True)
    return values[np.sort(first)]


def pose_ids_from_table(table: Table) -> np.ndarray | None:
    """The integer ``pose`` column ``(N,)``, or None when the table has none."""
    if POSE_COLUMN not in table.header:
        return None
    pose_ids = table.floats([POSE_COLUMN])
    _refuse_beyond(
        table,
        pose_ids,
        MAX_POSE_ID,
        lambda row, _: (
            f"pose id {table.rows[row][table.column_index(POSE_COLUMN)].strip()!r} is too large; "
            "expected an integer of magnitude at most 2**53"
        ),
    )
    _refuse_beyond(  # a fractional part
        table,
        pose_ids - np.round(pose_ids),
        0.0,
        lambda row, _: f"pose id {float(pose_ids[row, 0])!r} is not an integer",
    )
    return pose_ids[:, 0].astype(np.int64)


def check_wrench_magnitude(table: Table, wrenches: np.ndarray) -> None:
    """Refuse readings beyond ±:data:`MAX_WRENCH` (they would overflow the fit, not inform it)."""
    _refuse_beyond(
        table,
        wrenches,
        MAX_WRENCH,
        lambda row, column: (
            f"column {WRENCH_CHANNELS[column]!r} holds {wrenches[row, column]:g}, beyond "
            f"±{MAX_WRENCH:g}: expected "
            "N (fx, fy, fz) and N·m "
            "(mx, my, mz), not raw counts"
        ),
    )


@dataclass(frozen=True)
class LoadedSamples:
    """Samples read from a CSV, with the table they came from.

    ``layout`` says how a timed table was read (:class:`~ftkin.io.table_layout.TableLayout`:
    its pose column, one reading per pose, readings grouped by pose, or a continuous recording
    whose still segments are the poses; ``table`` then has a ``pose`` column), None when the
    table has no times or every row was kept as read. ``search`` holds the still segments of a
    continuous recording. A bag's reader returns the specialization
    :class:`~ftkin.io.bags.BagSamples`, which adds :attr:`recording`.
    """

    samples: Samples
    table: Table
    orientation: str
    orientation_columns: list[str]
    layout: "TableLayout | None" = None

    @property
    def recording(self):
        """What a bag held (:class:`~ftkin.io.bags.BagRecording`): None here, for a CSV; a
        :class:`~ftkin.io.bags.BagSamples` carries it (this module does not know the bag reader,
        which imports it).
        """
        return None

    @property
    def search(self) -> SegmentSearch | None:
        """The still segments of a continuous recording, else None."""
        return None if self.layout is None else self.layout.search


def read_layout(table: Table, orientations: TableOrientations, times, parameters):
    """How a timed table without a pose column was recorded (:mod:`ftkin.io.table_layout`), and
    the rows to use: ``(table, orientations, times, layout)``, the table with a ``pose`` column
    (a continuous recording keeps only its still segments' rows).

    Raises:
        InvalidSamples: a motion with no static pose, or no usable still segment.
    """
    positions = orientations.joint_positions
    signal = orientations.rotations.reshape(-1, 9) if positions is None else positions
    quantity = "orientation speed" if positions is None else "joint speed"
    if len(times) < 2 or np.any(np.diff(times) < 0):
        return table, orientations, times, None  # the drift fit refuses unsorted times
    layout = table_layout(times, signal, parameters, quantity, table.source)
    if layout.kind != RECORDING:
        rows = [[*row, str(int(pose))] for row, pose in zip(table.rows, layout.pose_ids)]
        table = replace(table, header=[*table.header, POSE_COLUMN], rows=rows)
        logger.info("%s: %s", table.source, layout.describe())
        return table, orientations, times, layout
    index = segment_index(times, layout.search.segments)
    keep = np.flatnonzero(index >= 0)
    rows = [[*table.rows[i], str(int(index[i]))] for i in keep]
    lines = [table.lines[i] for i in keep]
    table = replace(table, header=[*table.header, POSE_COLUMN], rows=rows, lines=lines)
    orientations = replace(
        orientations,
        rotations=orientations.rotations[keep],
        joint_positions=None if positions is None else positions[keep],
    )
    logger.info("%s: %s", table.source, layout.describe())
    return table, orientations, times[keep], layout


def samples_from_table(
    table: Table,
    arm=None,
    segments: SegmentParameters | None = None,
    spelling: ColumnSpelling | None = None,
) -> LoadedSamples:
    """Build :class:`Samples` from a table; ``arm`` is needed for joint columns.

    When the table has joint columns and ``arm`` is None, the bundled arm is used. A table whose
    comments name the arm it was recorded on is refused with another ``--robot``
    (:func:`~ftkin.io.recorded_robot.check_recorded_robot`).
    The table's columns are read through ``spelling`` first (:func:`~ftkin.io.column_spelling.
    spelled_table`: other names, units in the header, the time unit).
    ``segments``: how still segments of a continuous recording are found (see
    the module docstring); None (the default) keeps every row.
    """
    table = spelled_table(table, spelling)
    missing_columns(table, WRENCH_CHANNELS, "wrench")
    check_recorded_robot(table, arm)  # a recording that names its arm is read with that arm
    orientations = orientations_from_table(table, arm)
    times = times_from_table(table)
    layout = None
    if segments is not None and times is not None and POSE_COLUMN not in table.header:
        table, orientations, times, layout = read_layout(table, orientations, times, segments)
    wrenches = table.floats(WRENCH_CHANNELS)
    check_wrench_magnitude(table, wrenches)
    pose_ids = pose_ids_from_table(table)
    if orientations.arm is None:
        samples = Samples(
            wrenches, orientations.rotations, pose_ids, times=times, orientation=orientations.kind
        )
    else:
        samples = Samples.from_joint_positions(
            orientations.arm,
            orientations.joint_positions,
            wrenches,
            pose_ids,
            orientations.rotations,
            times,
        )
    if layout is None and times is not None and POSE_COLUMN in table.header:
        poses = len(np.unique(pose_ids))
        layout = TableLayout(POSE_COLUMN_LAYOUT, "its pose column", len(pose_ids), poses)
    return LoadedSamples(samples, table, orientations.kind, orientations.columns, layout)


def load_samples(
    path,
    arm=None,
    segments: SegmentParameters | None = None,
    spelling: ColumnSpelling | None = None,
) -> LoadedSamples:
    """Read a samples CSV (see the module docstring for its columns and ``segments``;
    ``spelling``: :class:`~ftkin.io.column_spelling.ColumnSpelling`, other names and units)."""
    return samples_from_table(read_table(path), arm, segments, spelling)
