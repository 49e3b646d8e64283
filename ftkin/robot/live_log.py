"""The record of a live run of compensated samples (``ftkin compensate --ur HOST --live``, or a
loop of one's own over :func:`~ftkin.robot.live_compensation.compensated_stream`).

:class:`SampleLog` writes each sample as it comes (``t`` [s, the sensor's stamp], the joints
[rad], ``fx..mz`` [N, N·m], sensor frame; never over an existing file). :func:`missed_packages`
counts the samples a stream skipped from the gaps in its stamps. :func:`settle` skips the samples
that queue up right after connecting, until the stamps step by one period.
"""

from __future__ import annotations

import math
import os
import time

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput

FLUSH_EVERY = 250
"""Log rows per flush (half a second at 500 Hz)."""
SETTLE_STEPS, SETTLE_LIMIT = 25, 0.5
""":func:`settle` returns after this many consecutive one-period steps of the stamps, or this
long [s]."""
SAME_PERIOD = 1.25
"""A step of the stamps up to this many times the shortest seen is one period (:func:`settle`)."""


class SampleLog:
    """A CSV of compensated samples, written as they come, flushed every :data:`FLUSH_EVERY` rows.

    Raises:
        InvalidInput: ``path`` exists (ftkin never overwrites a file).
    """

    def __init__(self, path, joint_names):
        try:
            self.stream = open(path, "x", encoding="utf-8", newline="")  # noqa: SIM115 (close())
        except FileExistsError:
            raise InvalidInput(
                f"{path} exists: ftkin never overwrites a file; choose another"
            ) from None
        self.stream.write(",".join(["t", *joint_names, *WRENCH_CHANNELS]) + "\n")
        self.rows: list[str] = []

    def add(self, stamp: float, q: np.ndarray, contact: np.ndarray) -> None:
        """One sample: its stamp [s], joint angles ``(nq,)`` [rad], contact wrench ``(6,)``."""
        self.rows.append(",".join(map(repr, [float(stamp), *q.tolist(), *contact.tolist()])))
        if len(self.rows) >= FLUSH_EVERY:
            self.flush()

    def flush(self) -> None:
        """Write the rows held and flush the file."""
        if self.rows:
            self.stream.write("\n".join(self.rows) + "\n")
            self.rows = []
        self.stream.flush()

    def close(self) -> None:
        """Write what is held, sync to disk and close."""
        self.flush()
        os.fsync(self.stream.fileno())
        self.stream.close()


def missed_packages(stamps) -> tuple[int, float]:
    """Samples missed between consecutive ``stamps`` [s], and the period [s] (the median step).

    A step of ``k`` periods (rounded: 1.49 periods is one, 1.51 two) misses ``k − 1`` samples.
    Fewer than two stamps: ``(0, nan)``; a median step that is not positive: nothing counted.
    """
    stamps = np.asarray(stamps, dtype=float).reshape(-1)
    if len(stamps) < 2:
        return 0, math.nan
    steps = np.diff(stamps)
    period = float(np.median(steps))
    if not period > 0.0:
        return 0, period
    return int(np.sum(np.maximum(np.round(steps / period) - 1.0, 0.0))), period


def settle(stream, steady: int = SETTLE_STEPS, limit: float = SETTLE_LIMIT) -> None:
    """Skip samples ``(stamp, ...)`` of ``stream`` until ``steady`` consecutive steps of the
    stamps are each within :data:`SAME_PERIOD` of the shortest step seen (one period), or
    ``limit`` [s] has passed: right after connecting, a receive thread works through what queued
    up meanwhile (ur_rtde's getters skip packages then)."""
    deadline, previous, shortest, run = time.monotonic() + limit, None, math.inf, 0
    for stamp, *_ in stream:
        if previous is not None:
            step = stamp - previous
            shortest = min(shortest, step)
            run = run + 1 if step <= SAME_PERIOD * shortest else 0
        previous = stamp
        if run >= steady or time.monotonic() > deadline:
            return
