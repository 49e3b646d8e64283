"""Time columns of the CSVs: ``t`` [s], or one alias, converted by the unit its name gives.

Without ``t``, one column named ``time``, ``time_s``, ``t_s``, ``timestamp``,
``stamp`` or ``%time`` is read as seconds, and ``t_ms``/``time_ms``,
``t_us``/``time_us``, ``t_ns``/``time_ns`` are converted (a unit is applied
only where the column's name says it). An alias whose cells are not numbers (ISO dates, say) is not
a time here: it
is left alone with a warning, and so is one spanning more than a year (ROS
stamps in nanoseconds): only a column named ``t`` is refused for that. Two
numeric candidates are an error. Used by
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


def times_from_table(table: Table) -> np.ndarray | None:
    """The ``t`` column ``(N,)`` [s] (or its one numeric alias, converted), or None when the table
    has none.
    """
    if TIME_COLUMN in table.header:
        # ftkin's own column: a span beyond a year is refused by Samples, naming the likely unit
        return table.floats([TIME_COLUMN])[:, 0]
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
