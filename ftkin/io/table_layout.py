"""How a timed samples table was recorded: a table of poses or a continuous recording.

A samples CSV with a time column and no ``pose`` column comes in two real shapes, told apart
from the data (never from the file name or a flag):

* **a table of poses**: a script that records at each pose writes one row per pose (or a few
  rows per pose), the rows seconds or minutes apart. Every row is kept; consecutive rows at one
  orientation are one pose. This is the shape a drift calibration needs: each pose has its time.
* **a continuous recording**: a logger streaming at a steady rate (10 Hz, 1 kHz) while the arm
  moves between still phases. Its still segments are found by
  :func:`~ftkin.io.static_segments.find_static_segments` (speed, settling, minimum duration),
  each becomes one pose, and the rows in motion are left out.

The test, on the orientation signal (joint positions, or the nine entries of ``R_BS``):

1. two consecutive rows are **at one pose** when the change between them is at most
   ``pose_tolerance`` (a displacement, whatever the time between them) and both rows are
   still by the windowed speed (:func:`~ftkin.io.static_segments.joint_speed`): rows a minute
   apart that differ by 0.3 rad are two poses, however slow the implied speed;
2. no two consecutive rows at one pose: **one reading per pose**, unless the rows are a
   steadily sampled smooth motion (consecutive changes alike: an excitation), which has no
   static pose at all and is refused;
3. runs of rows at one pose, with rows in motion between them, at a steady sample rate, the
   runs at least :data:`MIN_RUN` rows long (median): a **continuous recording**;
4. anything else: **readings grouped by pose** (each run of rows at one orientation is a pose,
   every row kept).

:class:`TableLayout` says which was chosen and why; ``ftkin calibrate`` prints it.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidSamples
from .static_segments import SegmentParameters, SegmentSearch, find_static_segments, joint_speed

MAX_GAP = 20.0
"""Longest time step of a continuous recording, in median steps."""
MAX_STILL_TRAVEL = 0.05
"""Largest change of the orientation signal [rad, or the entries of ``R_BS``] within one still
segment (about 3°): more is a motion that the speed did not see."""
MAX_GAPS = 5
"""Most steps longer than :data:`MAX_GAP` median steps in a continuous recording."""
MIN_RUN = 3
"""Shortest median run of rows at one pose in a continuous recording (a recorder samples each
still phase many times)."""

POSE_COLUMN_LAYOUT = "pose column"
ONE_PER_POSE = "one reading per pose"
GROUPED = "readings grouped by pose"
RECORDING = "continuous recording"


@dataclass(frozen=True)
class TableLayout:
    """How a timed table was read.

    Attributes:
        kind: :data:`POSE_COLUMN_LAYOUT`, :data:`ONE_PER_POSE`, :data:`GROUPED` or
            :data:`RECORDING`.
        reason: Why, from the data (one clause).
        rows: Rows in the table.
        poses: Poses the rows make.
        pose_ids: ``(rows,)`` pose of each row for :data:`GROUPED` and :data:`ONE_PER_POSE`
            (None otherwise: the pose column's, or the segments').
        search: The still segments of a :data:`RECORDING`, else None.
    """

    kind: str
    reason: str
    rows: int
    poses: int
    pose_ids: np.ndarray | None = None
    search: SegmentSearch | None = None

    def describe(self) -> str:
        """One line: what the table was read as, why, and what it gave."""
        if self.kind == RECORDING:
            kept = len(self.search.segments)
            return (
                f"read as a {RECORDING}: {self.reason}; {kept} still segment(s) → {kept} pose(s), "
                f"the rows in motion left out ({self.search.describe()}; --all-rows keeps every "
                "row as a pose)"
            )
        return f"{self.rows} rows read as {self.kind} ({self.reason}): {self.poses} pose(s)"


def uniformly_sampled(times: np.ndarray) -> bool:
    """Whether reading times are a recorder's: 80 % of the steps within half the median step of
    it, every step positive, and steps longer than :data:`MAX_GAP` median steps rare (at most
    :data:`MAX_GAPS`, and under 1 % of the steps: a recorder that paused, or rows dropped in a
    gap of one of several joined streams)."""
    steps = np.diff(times)
    if len(steps) < 2 or np.any(steps <= 0):
        return False
    median = np.median(steps)
    gaps = int(np.count_nonzero(steps > MAX_GAP * median))
    return bool(
        gaps <= min(MAX_GAPS, 0.01 * len(steps))
        and np.mean(np.abs(steps - median) <= 0.5 * median) >= 0.8
    )


def smooth_motion(signal: np.ndarray) -> bool:
    """Whether consecutive rows change alike (a sampled motion, not independent poses): the
    median second difference of the signal under half the median first difference (independent
    poses give about √2 times it)."""
    steps = np.diff(signal, axis=0)
    if len(steps) < 2:
        return False
    first = np.median(np.linalg.norm(steps, axis=1))
    return bool(first > 0 and np.median(np.linalg.norm(np.diff(steps, axis=0), axis=1)) < first / 2)


def runs_at_one_pose(times, signal, parameters: SegmentParameters) -> np.ndarray:
    """``(N,)`` run number of each row: consecutive rows at one pose (see the module docstring,
    step 1) share it.
    """
    change = np.max(np.abs(np.diff(signal, axis=0)), axis=1, initial=0.0)
    still = joint_speed(times, signal, parameters.speed_window) < parameters.speed_threshold
    same = (change <= parameters.pose_tolerance) & still[1:] & still[:-1]
    return np.concatenate([[0], np.cumsum(~same)])


def table_layout(
    times, signal, parameters: SegmentParameters, quantity: str = "joint speed", source: str = ""
) -> TableLayout:
    """Read a timed table without a pose column (see the module docstring).

    Args:
        times: ``(N,)`` row times [s], sorted.
        signal: ``(N, k)`` orientation signal (joint positions [rad or m], or ``R_BS`` entries).
        parameters: Stillness and pose tolerance.
        quantity: What the signal's speed is (``"joint speed"``, ``"orientation speed"``).
        source: The file, for messages.

    Raises:
        InvalidSamples: a smooth motion with no static pose, or a recording whose still phases
            are all too short.
    """
    times = np.asarray(times, dtype=float)
    signal = np.asarray(signal, dtype=float).reshape(len(times), -1)
    rows = len(times)
    runs = runs_at_one_pose(times, signal, parameters)
    lengths = np.bincount(runs)
    steady = uniformly_sampled(times)
    if lengths.max(initial=0) < 2:
        if steady and smooth_motion(signal):
            _refuse_no_segment(find_static_segments(times, signal, parameters, quantity), source)
        return TableLayout(
            ONE_PER_POSE,
            "no two consecutive rows at one orientation",
            rows,
            rows,
            np.arange(rows),
        )
    grouped = lengths[lengths >= 2]
    moving = int(np.count_nonzero(lengths == 1))
    if steady and moving > 0 and np.median(grouped) >= MIN_RUN:
        search = find_static_segments(times, signal, parameters, quantity)
        if not search.segments:
            _refuse_no_segment(search, source)
        _refuse_turning_segments(times, signal, search, quantity, source)
        step = float(np.median(np.diff(times)))
        reason = (
            f"rows every {step:.3g} s, {len(grouped)} still run(s) of a median "
            f"{np.median(grouped):g} rows with {moving} row(s) in motion between them"
        )
        return TableLayout(RECORDING, reason, rows, len(search.segments), None, search)
    _, pose_ids = np.unique(runs, return_inverse=True)
    return TableLayout(
        GROUPED,
        f"consecutive rows at one orientation (within {parameters.pose_tolerance:g}) are one pose"
        + ("" if steady else "; the times are not a recorder's steady steps"),
        rows,
        len(lengths),
        pose_ids.astype(np.int64),
    )


def _refuse_turning_segments(times, signal, search: SegmentSearch, quantity: str, source: str):
    """Refuse a still segment whose signal moves by more than :data:`MAX_STILL_TRAVEL` within it:
    still by its speed only because the times are not in seconds (milliseconds read as seconds
    make every motion 1000 times slower)."""
    from .static_segments import segment_index

    index = segment_index(times, search.segments)
    for k, segment in enumerate(search.segments):
        inside = signal[index == k]
        travel = float(np.max(np.ptp(inside, axis=0))) if len(inside) else 0.0
        if travel > MAX_STILL_TRAVEL:
            raise InvalidSamples(
                f"still segment {k} ({segment.start:.6g}–{segment.end:.6g} s) is still by its "
                f"{quantity} but moves by {travel:.3g} within it: are the times in seconds "
                "(--time-unit ms|us|ns, or a unit in the column name)? Or lower the stillness "
                "threshold (--speed-threshold)",
                source,
            )


def _refuse_no_segment(search: SegmentSearch, source: str) -> None:
    """A steadily sampled recording with no usable still segment: refused, naming the motion."""
    times = search.times
    raise InvalidSamples(
        f"a continuous recording ({times[-1] - times[0]:.3g} s) with no usable still segment: "
        f"{search.motion()}; {search.describe()}; lower --min-static-duration/--settle-time or "
        "raise --speed-threshold, fit every row as a pose with --all-rows, or use the motion "
        "with 'calibrate --dynamic'",
        source,
    )
