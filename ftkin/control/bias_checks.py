"""The bias a reading at its time had, and checks of a bias against its calibration: one rule
for the API and the CLI.

Two mistakes look right in the numbers and are warned of (through :mod:`logging`), by
:meth:`~ftkin.control.compensation.Compensator.rezero` and
:meth:`~ftkin.control.compensation.Compensator.bias_at` (so by ``compensate_batch`` and
``compensate_samples`` with times, and the viewer's readings) as by ``ftkin rezero``,
``ftkin compensate`` and ``ftkin view``:

* **a re-zero that moved the force bias by more than the tool's weight** (and at least
  :data:`REZERO_WARNING_FORCE`): a contact at the pose, or a sensor tared in its driver since the
  calibration; a thermal drift is smaller. A re-zero of a drifting calibration is also said: rows
  of a log timed inside its recording keep the bias the recording saw.
* **a log whose times look like another clock** than a drifting calibration's recording: rows
  inside the recording of a calibration re-zeroed since (they take the recording's bias, not the
  re-zeroed one), or times more than :data:`EARLY_SPANS` recording spans before its start (another
  clock or another unit: every row takes the last bias).

The check functions return the texts (empty when all is well); :func:`bias_at_times` and
:meth:`~ftkin.control.compensation.Compensator.rezero` log them.
"""

import logging
from dataclasses import dataclass

import numpy as np

from ..calibration.drift import BiasDrift
from ..calibration.result import CalibrationResult

logger = logging.getLogger(__name__)

REZERO_WARNING_FORCE = 2.0
"""A re-zero that moves the force bias by more than the tool's weight and this [N] is warned of
(a contact at the pose, or a sensor tared in its driver: a thermal drift is smaller)."""
EARLY_SPANS = 10.0
"""A log whose first time is more than this many recording spans before a drifting calibration's
recording started is taken to be on another clock (or in another unit) and warned of."""
MOVED_BIAS = 1e-9
"""How far [N or N·m] the bias applied outside a drifting calibration's recording may be from the
trajectory's end before rows inside the recording are said to use another bias (the two are equal
until a re-zero, a tracker or ``set_bias`` moves it)."""


def seconds_text(value: float) -> str:
    """A time [s] as text: to the millisecond when it is a clock's (since the epoch), so that two
    stamps of one run read apart (the form :mod:`ftkin.io.stream_join` prints times in; io is a
    sibling stage, not importable from here)."""
    return f"{value:.3f}" if abs(value) >= 1e5 else f"{value:.6g}"


def drifting(drift: BiasDrift | None) -> bool:
    """Whether ``drift`` is a bias trajectory (not None, not the constant model ``"none"``)."""
    return drift is not None and drift.model != "none"


def recording_span(drift: BiasDrift) -> tuple[float, float]:
    """First and last time [s] of the recording a drift trajectory covers (its
    ``recorded_span``, else its pose times): the span :meth:`BiasDrift.covers` tests."""
    span = drift.recorded_span if drift.recorded_span is not None else drift.times[[0, -1]]
    return float(span[0]), float(span[1])


@dataclass(frozen=True)
class LogTimesCheck:
    """How the rows of a log at ``times`` meet a drifting calibration's recording.

    Attributes:
        rows: Number of rows.
        inside: Rows inside the recording: they use the trajectory's bias at their time.
        warnings: Texts of the clock warnings (empty: none).
    """

    rows: int
    inside: int
    warnings: tuple[str, ...]

    @property
    def outside(self) -> int:
        """Rows outside the recording: they use the current bias (the calibration's last, or
        re-zeroed since)."""
        return self.rows - self.inside


def check_log_times(drift: BiasDrift | None, times, bias) -> LogTimesCheck:
    """Whether a log's ``times`` ``(N,)`` [s] and a drifting calibration's recording look like
    one clock, given the ``bias`` ``(6,)`` [N, N·m] applied outside the recording.

    Without a drift trajectory every row is outside and nothing is said.
    """
    times = np.asarray(times, dtype=float).reshape(-1)
    if not drifting(drift) or not len(times):
        return LogTimesCheck(len(times), 0, ())
    inside = int(np.count_nonzero(drift.covers(times)))
    start, end = recording_span(drift)
    where = f"the calibration's recording ({seconds_text(start)}–{seconds_text(end)} s)"
    moved = float(np.max(np.abs(np.asarray(bias, dtype=float) - drift.end_bias)))
    texts = []
    if inside and moved > MOVED_BIAS:
        texts.append(
            f"{inside} rows fall inside {where} and used the bias it saw, not the bias re-zeroed "
            f"since (it moved by up to {moved:.4g}): if the log is of a later session on another "
            f"clock, shift its times past {seconds_text(end)} s or drop its t column"
        )
    first = float(np.min(times))
    if first < start - EARLY_SPANS * max(end - start, 1e-9):
        texts.append(
            f"the log's times ({seconds_text(first)}–{seconds_text(float(np.max(times)))} s) are "
            f"long before {where}: on another clock or in another unit (--time-unit)? its rows "
            "used the last bias"
        )
    return LogTimesCheck(len(times), inside, tuple(texts))


def bias_at_times(drift: BiasDrift | None, bias, times: np.ndarray) -> np.ndarray:
    """The bias ``(N, 6)`` [N, N·m] readings at ``times`` ``(N,)`` [s] (finite, checked by the
    caller) had: inside a drifting calibration's recording its trajectory, elsewhere (or without
    a trajectory) ``bias`` ``(6,)``, the bias applied now. Logs the clock warnings of
    :func:`check_log_times`. The one rule of
    :meth:`~ftkin.control.compensation.Compensator.bias_at` and of the viewer's readings.
    """
    out = np.tile(np.asarray(bias, dtype=float), (len(times), 1))
    if drifting(drift):
        inside = drift.covers(times)
        out[inside] = drift.bias_at(times[inside])
        for text in check_log_times(drift, times, bias).warnings:
            logger.warning("%s", text)
    return out


def rezero_warnings(calibration, previous_bias, bias) -> tuple[str, ...]:
    """What to say of a re-zero of ``calibration`` from ``previous_bias`` to ``bias`` ``(6,)``
    [N, N·m]: a force bias moved by more than ``max(tool weight, REZERO_WARNING_FORCE)``, and a
    drift trajectory the re-zero leaves in place."""
    texts = []
    moved = float(
        np.linalg.norm(np.asarray(bias, float)[:3] - np.asarray(previous_bias, float)[:3])
    )
    weight = float(calibration.tool_weight)
    if moved > max(weight, REZERO_WARNING_FORCE):
        texts.append(
            f"the bias moved by {moved:.4g} N, more than the tool's weight ({weight:.4g} N): was "
            "the tool touching something, or the sensor tared in its driver since the "
            "calibration? Re-zero at a contact-free pose"
        )
    drift = calibration.drift if isinstance(calibration, CalibrationResult) else None
    if drifting(drift):
        start, end = recording_span(drift)
        texts.append(
            f"this calibration has a drift trajectory ({drift.model}) over {start:.6g}–{end:.6g} "
            "s: rows of a log timed inside it keep the bias the recording saw; the re-zeroed bias "
            "applies after it"
        )
    return tuple(texts)
