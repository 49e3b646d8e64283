"""Is a log to compensate in its calibration's conventions and units? Refuse a mistake, warn of a
doubt: the decision ``ftkin compensate`` makes, for any caller with a log table.

:func:`~ftkin.io.table_readings.log_convention_report` reads the log under the common mistakes
(readings negated, another axis convention, forces in lbf, torques in N·mm or lbf·in) and judges
each reading's compensated wrench in the calibration's noise.
"""

import logging

from ..exceptions import ConventionMistake
from .csv_table import Table
from .table_readings import log_convention_report

logger = logging.getLogger(__name__)


def check_log_conventions(table: Table, arm, calibration, *, advice: str = "") -> None:
    """Raise when ``table`` fits ``calibration`` only in another convention or unit, warn
    (logging) when that is likely but not certain; nothing when the log reads as given (a log
    with contacts is not questioned: no other reading removes a contact).

    Args:
        table: The log (its ``source`` names it in the message).
        arm: The arm its joint columns are read with (None: the bundled arm).
        calibration: The calibration it is compensated with (its noise judges the readings; one
            without diagnostics is not checked).
        advice: Appended to the refusal's text (``ftkin compensate``: how to compensate the log
            as given).

    Raises:
        ConventionMistake: the log fits under another reading (its ``reading`` and ``fix``).
    """
    report = log_convention_report(table, arm, calibration)
    if report is None:
        return
    verdict, reason, reading = report
    if verdict == "mistake":
        raise ConventionMistake(reason + advice, table.source, reading.name, reading.fix)
    logger.warning("%s: %s", table.source, reason)
