"""How a file spells ftkin's columns: other names, units in the header, the time unit.

Real files come from other loggers: ATI's and Bota's tools write ``Fx,Fy,Fz,Tx,Ty,Tz``, a
script writes ``Fx (N)`` or ``t [us]``, a ROS bag export writes ``wrench.force.x``. Every table
reader of ftkin (samples, logs, moving recordings) passes what it read through
:func:`spelled_table` first, which gives the table in ftkin's names and SI units:

1. ``--column NAME=COLUMN`` (:attr:`ColumnSpelling.columns`) renames a file's column to
   ftkin's ``NAME`` (``fx``, ``t``, ``pose``, a joint name, ...);
2. a unit in the header, ``NAME (UNIT)`` or ``NAME [UNIT]``, converts the column to SI: forces
   in N, kN, lbf, klbf, kgf; torques in N·m (also ``Nm``, ``N-m``), N·mm, kN·m, lbf·in, lbf·ft,
   kgf·cm; times in s, ms, us (µs), ns. An unknown unit on a wrench or time column is refused;
   other columns keep their header as it is (carried along);
3. wrench columns in other spellings, when ftkin's own are absent: any case of ``fx..fz``,
   ``mx..mz`` and ``tx..tz`` (torques), and ROS-style ``force.x``/``torque.x`` with any prefix
   ending in ``.``, ``_`` or ``/``;
4. ``--time-unit s|ms|us|ns`` (:attr:`ColumnSpelling.time_unit`) converts the time column
   (``t``, or its one alias such as ``timestamp``) to seconds.

A time column whose values are plainly not seconds (beyond 1e11, the year 5000 in seconds since
1970: milliseconds or microseconds since the epoch) is refused by
:func:`~ftkin.io.time_columns.times_from_table`, naming ``--time-unit``.
"""

import logging
import re
from collections import Counter
from collections.abc import Mapping
from dataclasses import dataclass, replace

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput, InvalidSamples
from ..options import option
from .csv_table import Table, format_float, read_header

logger = logging.getLogger(__name__)

POUND_FORCE = 4.4482216152605
"""One pound-force in newtons (exact by definition: 0.45359237 kg × 9.80665 m/s²)."""
KILOGRAM_FORCE = 9.80665
"""One kilogram-force in newtons (exact)."""
INCH, FOOT = 0.0254, 0.3048
"""[m], exact."""

FORCE_UNITS = {
    "n": 1.0,
    "kn": 1e3,
    "lbf": POUND_FORCE,
    "klbf": 1e3 * POUND_FORCE,
    "kgf": KILOGRAM_FORCE,
}
"""Force units to newtons, by lower-case name."""
TORQUE_UNITS = {
    "nm": 1.0,
    "nmm": 1e-3,
    "knm": 1e3,
    "lbfin": POUND_FORCE * INCH,
    "inlbf": POUND_FORCE * INCH,
    "inlb": POUND_FORCE * INCH,
    "lbin": POUND_FORCE * INCH,
    "lbfft": POUND_FORCE * FOOT,
    "ftlbf": POUND_FORCE * FOOT,
    "ftlb": POUND_FORCE * FOOT,
    "lbft": POUND_FORCE * FOOT,
    "kgfcm": KILOGRAM_FORCE * 0.01,
}
"""Torque units to N·m, by lower-case name with separators (``·``, ``-``, ``.``, ``*``, space)
removed: ``N·m``, ``Nm``, ``N-m`` are one unit."""
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6, "μs": 1e-6, "ns": 1e-9}
"""Time units to seconds."""
TIME_UNIT_CHOICES = ("s", "ms", "us", "ns")

_HEADER_UNIT = re.compile(r"^(?P<name>.*?\S)\s*[\(\[](?P<unit>[^\)\]]*)[\)\]]\s*$")
_WRENCH_NAME = re.compile(
    r"^(?:(?:.*[./_])?(?P<long>force|torque)[._]|(?P<short>[fmt]))(?P<axis>[xyz])$",
    re.IGNORECASE,
)
_TIME_NAMES = {"t", "time", "time_s", "t_s", "timestamp", "stamp", "%time"}
_UNIT_SEPARATORS = re.compile(r"[\s·.*\-⋅]")


def _column_pairs(value) -> dict[str, str]:
    """``{ftkin name: file column}`` from a mapping or ``NAME=COLUMN`` strings."""
    if value is None:
        return {}
    if isinstance(value, Mapping):
        pairs = list(value.items())
    elif isinstance(value, str):
        raise InvalidInput(f"columns must be NAME=COLUMN pairs in a list, got the text {value!r}")
    else:
        pairs = []
        for item in value:
            name, equals, column = str(item).partition("=")
            if not equals or not name.strip() or not column.strip():
                raise InvalidInput(
                    f"--column takes NAME=COLUMN (ftkin's name = the file's column, e.g. "
                    f"fx=Force_X), got {item!r}"
                )
            pairs.append((name.strip(), column.strip()))
    out: dict[str, str] = {}
    for name, column in pairs:
        if not isinstance(name, str) or not isinstance(column, str):
            raise InvalidInput(f"column names must be text, got {name!r}={column!r}")
        if name in out:
            raise InvalidInput(f"--column {name}= is given twice ({out[name]!r}, {column!r})")
        out[name] = column
    sources = Counter(out.values())
    twice = [column for column, count in sources.items() if count > 1]
    if twice:
        raise InvalidInput(f"--column maps the file's column {twice[0]!r} to two names")
    return out


def _column_pair_text(text: str) -> str:
    """argparse type of one ``--column NAME=COLUMN``."""
    import argparse

    try:
        _column_pairs([text])
    except InvalidInput as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


@dataclass(frozen=True)
class ColumnSpelling:
    """How a file names and scales ftkin's columns (see the module docstring).

    Attributes:
        columns: ``{ftkin name: the file's column}`` (or ``NAME=COLUMN`` strings).
        time_unit: Unit of the time column (``s``, ``ms``, ``us``, ``ns``), or None (seconds,
            or the unit its name or header gives).
    """

    columns: Mapping[str, str] = option(
        help="read the file's COLUMN as ftkin's NAME (fx..mz, t, pose, a joint name, qw..qz, "
        "r11..r33, ...); repeatable",
        flag="--column",
        metavar="NAME=COLUMN",
        action="append",
        parse=_column_pair_text,
        default_factory=dict,
        cli_default=[],
    )
    time_unit: str | None = option(
        None,
        help="unit of the time column (t, or its one alias such as timestamp); a t column "
        "holding epoch milliseconds or microseconds needs it",
        choices=TIME_UNIT_CHOICES,
    )

    def __post_init__(self):
        object.__setattr__(self, "columns", _column_pairs(self.columns))
        if self.time_unit is not None and self.time_unit not in TIME_UNIT_CHOICES:
            raise InvalidInput(
                f"time_unit must be one of {', '.join(TIME_UNIT_CHOICES)}, got {self.time_unit!r}"
            )


def _unit_key(unit: str) -> str:
    return _UNIT_SEPARATORS.sub("", unit.strip().lower())


def wrench_name(column: str) -> str | None:
    """ftkin's wrench channel a column name spells (``Fx``, ``tx``, ``force.x`` → ``fx``/``mx``),
    or None."""
    match = _WRENCH_NAME.match(column)
    if match is None:
        return None
    kind = (match["long"] or match["short"]).lower()
    return ("f" if kind in ("force", "f") else "m") + match["axis"].lower()


def _unit_factor(table: Table, column: str, name: str, unit: str) -> float | None:
    """The factor to SI of ``unit`` on the column ``name`` (None: not a column ftkin reads)."""
    key = _unit_key(unit)
    if name in WRENCH_CHANNELS[:3]:
        units, what = FORCE_UNITS, "force"
    elif name in WRENCH_CHANNELS[3:]:
        units, what = TORQUE_UNITS, "torque"
    elif name.lower() in _TIME_NAMES:
        units, what = {_unit_key(k): v for k, v in TIME_UNITS.items()}, "time"
    else:
        return None
    if key not in units:
        shown = {"force": "N, kN, lbf, klbf, kgf", "torque": "N·m, N·mm, kN·m, lbf·in, lbf·ft, "}
        shown["torque"] += "kgf·cm"
        shown["time"] = "s, ms, us, ns"
        raise InvalidSamples(
            f"column {column!r}: unknown {what} unit {unit!r}; expected one of {shown[what]}",
            table.source,
            table.header_line,
        )
    return units[key]


def _scaled(table: Table, name: str, factor: float) -> Table:
    """The column ``name`` multiplied by ``factor`` (cells rewritten: values are SI from here)."""
    if factor == 1.0:
        return table
    index = table.column_index(name)
    values = table.floats([name])[:, 0] * factor
    rows = [
        [*row[:index], format_float(value), *row[index + 1 :]]
        for row, value in zip(table.rows, values)
    ]
    return replace(table, rows=rows)


def declared_wrench_units(header, spelling: ColumnSpelling | None = None) -> dict[str, str]:
    """``{wrench channel: unit as written}`` for the wrench columns whose header names a unit
    (``mx [N·m]``, ``Fx (lbf)``), read from a header as the file has it (before
    :func:`spelled_table`). What a file declares wins over what the data look like: the doctor
    doubts a declared unit aloud, it does not override it.
    """
    spelling = spelling or ColumnSpelling()
    out: dict[str, str] = {}
    for column in header:
        match = _HEADER_UNIT.match(column)
        if match is None or column in spelling.columns.values():
            continue
        bare = match["name"].strip()
        name = bare if bare in WRENCH_CHANNELS else wrench_name(bare)
        if name in WRENCH_CHANNELS:
            out[name] = match["unit"].strip()
    return out


def spelled_header(path, spelling: ColumnSpelling | None = None) -> list[str]:
    """The header a file has in ftkin's names (:func:`spelled_table`'s), read without its rows
    (:func:`~ftkin.io.csv_table.read_header`)."""
    header = read_header(path)
    return spelled_table(Table(str(path), header, [], [], 1), spelling).header


def spelled_table(table: Table, spelling: ColumnSpelling | None = None) -> Table:
    """``table`` in ftkin's names and SI units (see the module docstring for the steps).

    Raises:
        InvalidSamples: a ``--column`` naming a column the file lacks or a name the file
            already has, an unknown unit on a wrench or time column, two columns spelling one
            channel, or a time unit that contradicts the column's name.
    """
    spelling = spelling or ColumnSpelling()
    header = list(table.header)
    for name, column in spelling.columns.items():
        if column not in header:
            raise InvalidSamples(
                f"--column {name}={column}: the file has no column {column!r}; its header has "
                f"{header[:30]}",
                table.source,
                table.header_line,
            )
        if name in header:
            raise InvalidSamples(
                f"--column {name}={column}: the file already has a column {name!r}; rename one",
                table.source,
                table.header_line,
            )
        header[header.index(column)] = name
    factors: dict[str, float] = {}
    for i, column in enumerate(header):
        match = _HEADER_UNIT.match(column)
        if match is None or column in spelling.columns:
            continue
        bare = match["name"].strip()
        name = bare if bare in WRENCH_CHANNELS else (wrench_name(bare) or bare)
        factor = _unit_factor(table, column, name, match["unit"])
        if factor is not None:
            header[i], factors[name] = name, factor
    spelled = {column: wrench_name(column) for column in header if column not in WRENCH_CHANNELS}
    spelled = {column: name for column, name in spelled.items() if name is not None}
    counts = Counter(spelled.values())
    for column, name in spelled.items():
        if name in header:  # ftkin's own name wins ("tx,ty,tz" may be a translation), said
            logger.warning(
                "%s: column %r could spell the wrench channel %r, which the file has under its "
                "own name: %r is used, %r carried along (rename one to use the other)",
                table.source,
                column,
                name,
                name,
                column,
            )
            continue
        if counts[name] > 1:
            same = [c for c, n in spelled.items() if n == name]
            raise InvalidSamples(
                f"columns {same} all spell the wrench channel {name!r}; keep one, or name it "
                f"with --column {name}=COLUMN",
                table.source,
                table.header_line,
            )
        header[header.index(column)] = name
    duplicates = [name for name, count in Counter(header).items() if count > 1]
    if duplicates:
        raise InvalidSamples(
            f"column {duplicates[0]!r} appears twice after reading the header's units and names",
            table.source,
            table.header_line,
        )
    table = replace(table, header=header)
    if spelling.time_unit is not None:
        table = _time_in_seconds(table, spelling.time_unit, factors)
    for name, factor in factors.items():
        table = _scaled(table, name, factor)
    return table


def _time_in_seconds(table: Table, unit: str, factors: dict) -> Table:
    """The time column renamed ``t``, its factor to seconds ``--time-unit``'s in ``factors``
    (checked against the unit its name or header gives)."""
    from .time_columns import TIME_ALIASES

    present = [name for name in table.header if name == "t" or name.lower() in TIME_ALIASES]
    if len(present) != 1:
        raise InvalidSamples(
            f"--time-unit {unit}: "
            + (f"several time columns {present}" if present else "the file has no time column")
            + " (t, time, timestamp, ...); name the one with --column t=COLUMN",
            table.source,
            table.header_line,
        )
    column = present[0]
    unitless = {"t", "time", "timestamp", "stamp", "%time"}
    explicit = column in factors or column.lower() not in unitless
    said = factors.pop(column, 1.0 if column == "t" else TIME_ALIASES[column.lower()])
    if explicit and said != TIME_UNITS[unit]:
        raise InvalidSamples(
            f"--time-unit {unit} contradicts the time column {column!r}, whose name or header "
            "gives another unit; leave --time-unit out or rename the column",
            table.source,
            table.header_line,
        )
    factors["t"] = TIME_UNITS[unit]
    return replace(table, header=["t" if name == column else name for name in table.header])
