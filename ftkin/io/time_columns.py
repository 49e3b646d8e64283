"""Time columns of the CSVs: ``t`` [s], or one alias, converted by the unit its name gives.

Without ``t``, one column named ``time``, ``time_s``, ``t_s``, ``timestamp``,
``stamp`` or ``%time`` is read as seconds, and ``t_ms``/``time_ms``,
``t_us``/``time_us``, ``t_ns``/``time_ns`` are converted (a unit is applied
only where the column's name says it; ``--time-unit``, :class:`~ftkin.io.column_spelling.
ColumnSpelling`, gives the unit of any of them). An alias whose cells are not numbers (ISO dates,
say) is not a time here: it is left alone with a warning. A time column whose values are plainly
not seconds (beyond :data:`NOT_SECONDS`: epoch milliseconds, microseconds or nanoseconds) is
refused, naming ``--time-unit``. Two numeric candidates are an error. Used by
the samples CSV, the motion recordings, bag extraction and the viewer.
"""

import logging

import numpy as np

from ..calibration.samples import LONGEST_TIME_SPAN
from ..exceptions import InvalidSamples
from .csv_table import Table

logger = logging.getLogger(__name__)

TIME_COLUMN = "t"
"""ftkin's time column [s] (written by ``ftkin extract``)."""

TIME_ALIASES = {
    "time": 1.0,
    "time_s": 1.0,
    "t_s": 1.0,
    "timestamp": 1.0,
    "stamp": 1.0,
    "%time": 1.0,
    "t_ms": 1e-3,
    "time_ms": 1e-3,
    "t_us": 1e-6,
    "time_us": 1e-6,
    "t_ns": 1e-9,
    "time_ns": 1e-9,
}
"""Time columns read when ``t`` is absent, with the factor to seconds their name gives."""


def _numeric(table: Table, name: str) -> bool:
    """Whether the column's first cell is a number (an alias holding dates or text is not a time in
    seconds).
    """
    try:
        float(table.rows[0][table.column_index(name)])
    except (ValueError, IndexError):
        logger.warning(
            "%s: column %r is not numbers of seconds (%r); not read as the time: name a time "
            "column "
            "'t' [s] to model a drift",
            table.source,
            name,
            table.rows[0][table.column_index(name)][:40],
        )
        return False
    return True


NOT_SECONDS = 1e11
"""A time [s] beyond this (the year 5138 in seconds since 1970) is plainly not seconds: epoch
milliseconds are about 1.7e12, microseconds 1.7e15, nanoseconds 1.7e18."""


def refuse_times_not_seconds(table: Table, column: str, times: np.ndarray) -> None:
    """Refuse a time column whose values are plainly not seconds, naming ``--time-unit``."""
    largest = float(np.max(np.abs(times), initial=0.0))
    if largest <= NOT_SECONDS:
        return
    row = int(np.argmax(np.abs(times)))
    guess = next(
        (
            unit
            for unit, scale in (("ns", 1e18), ("us", 1e15), ("ms", 1e12))
            if largest >= scale / 10
        ),
        "ms",
    )
    raise InvalidSamples(
        f"column {column!r} holds {times[row]:.6g}: not seconds (as seconds since 1970 that "
        f"is {largest / 3.156e7:.3g} years); give its unit with --time-unit {guess} (Python: "
        f"ColumnSpelling(time_unit={guess!r})), e.g. for {guess} since the epoch",
        table.source,
        table.lines[row],
    )


def times_from_table(table: Table) -> np.ndarray | None:
    """The ``t`` column ``(N,)`` [s] (or its one numeric alias, converted), or None when the table
    has none.
    """
    if TIME_COLUMN in table.header:
        # ftkin's own column: a span beyond a year is refused by Samples, naming the likely unit
        times = table.floats([TIME_COLUMN])[:, 0]
        refuse_times_not_seconds(table, TIME_COLUMN, times)
        return times
    found = [
        name for name in table.header if name.lower() in TIME_ALIASES and _numeric(table, name)
    ]
    if not found:
        return None
    if len(found) > 1:
        raise InvalidSamples(
            f"several time columns {found}: name the one to use 't' (seconds)", table.source
        )
    name, factor = found[0], TIME_ALIASES[found[0].lower()]
    times = table.floats([name])[:, 0] * factor
    if factor == 1.0:
        refuse_times_not_seconds(table, name, times)
    span = float(np.ptp(times))
    if span > LONGEST_TIME_SPAN:
        logger.warning(
            "%s: column %r spans %.4g s, more than a year: not read as the time (nanoseconds? "
            "write a "
            "column t = %s / 1e9 in seconds to model a drift)",
            table.source,
            name,
            span,
            name,
        )
        return None
    logger.info(
        "reading column %r as the time t%s",
        name,
        "" if factor == 1.0 else f" (× {factor:g} to seconds)",
    )
    return times
