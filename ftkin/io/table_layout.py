"""How a timed samples table was recorded: a table of poses or a continuous recording.

A samples CSV with a time column and no ``pose`` column comes in two real shapes, told apart
from the data (never from the file name or a flag):

* **a pose table**: a script that moves the arm, lets it settle and records writes one row per
  pose (or a few rows per pose), the rows 0.5 s to minutes apart, the orientation changing by
  a degree or more between poses. Every row is kept; consecutive rows at one orientation are
  one pose. This is the shape a drift calibration needs: each pose has its time.
* **a continuous recording**: a logger streaming at a steady rate (10 Hz to kHz) while the arm
  moves between still phases. Its still segments are found by
  :func:`~ftkin.io.static_segments.find_static_segments` (speed, settling, minimum duration),
  each becomes one pose, and the rows in motion are left out.

What tells them apart is how the rows were taken, not how fast the orientation changes between
them (a slow sweep of 4.5° steps 10 s apart is a pose table, though its "speed" is tiny). The
test, on the orientation signal (joint positions, or the nine entries of ``R_BS``):

1. **the sampling**: the times are a recorder's when they are steady (:func:`uniformly_sampled`:
   most steps within half the median step of it, few long gaps) and the median step is at most
   :data:`MAX_RECORDER_STEP` (0.25 s, 4 Hz). A recorder samples a motion at 10 Hz or faster;
   a pose table's rows are a move and a settling apart (0.5 s or more), so consecutive rows
   cannot sample one motion;
2. two consecutive rows are **at one pose** when the change between them is at most
   ``pose_tolerance`` (a displacement, whatever the time between them: a repeated reading within
   noise); rows closer in time than :data:`MAX_RECORDER_STEP` must also both be still by the
   windowed speed (:func:`~ftkin.io.static_segments.joint_speed`), since a recorder at kHz sees
   a motion change by less than the tolerance from one row to the next;
3. no two consecutive rows at one pose (every row differs from the previous one by more than
   the tolerance): **one reading per pose**, unless the rows are a recorder's (step 1) and a
   smooth motion (consecutive changes alike, :func:`smooth_motion`): an excitation, which has no
   static pose at all and is refused;
4. steady times (whatever the step: a slow logger, or a stream whose times are not in seconds,
   which :func:`_refuse_turning_segments` then names), rows in runs at one pose with rows in
   motion between them, the runs at least :data:`MIN_RUN` rows long (median): a **continuous
   recording** (a pose table's repeated readings are taken in quick succession, its times
   not steady);
5. anything else: **readings grouped by pose** (each run of rows at one orientation is a pose,
   every row kept).

:class:`TableLayout` says which was chosen and why (:meth:`TableLayout.describe`:
"read as a pose table: 40 rows, one pose each, because ..."); ``ftkin calibrate`` prints it,
:func:`~ftkin.io.samples_csv.load_samples` logs it and returns it as ``LoadedSamples.layout``.
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
MAX_RECORDER_STEP = 0.25
"""Longest median time step [s] of a recorder's rows (4 Hz): a recorder samples a motion at
10 Hz or faster (ROS joint states, a robot's 1 kHz state, a sensor's 100 Hz to 7 kHz), while
the rows of a pose table are a move and a settling apart (0.5 s or more)."""

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
        time_step: Median time between consecutive rows [s], None when not measured.
    """

    kind: str
    reason: str
    rows: int
    poses: int
    pose_ids: np.ndarray | None = None
    search: SegmentSearch | None = None
    time_step: float | None = None

    @property
    def pose_table(self) -> bool:
        """Whether every row was kept as (part of) a pose: not a :data:`RECORDING`."""
        return self.kind != RECORDING

    def describe(self) -> str:
        """One line: what the table was read as, why, and what it gave."""
        if self.kind == RECORDING:
            kept = len(self.search.segments)
            return (
                f"read as a {RECORDING}: {self.reason}; {kept} still segment(s) → {kept} pose(s), "
                f"the rows in motion left out ({self.search.describe()}; --all-rows keeps every "
                "row as a pose)"
            )
        if self.kind == ONE_PER_POSE:
            return (
                f"read as a pose table: {self.rows} rows, one pose each ({ONE_PER_POSE}), "
                f"because {self.reason}"
            )
        if self.kind == GROUPED:
            return (
                f"read as a pose table: {self.rows} rows, {self.poses} pose(s) ({GROUPED}: "
                f"consecutive rows at one orientation are one pose), because {self.reason}"
            )
        return f"read as a pose table: {self.rows} rows, {self.poses} pose(s) by {self.reason}"


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


def recorder_sampled(times: np.ndarray) -> bool:
    """Whether the rows are a recorder's samples of one motion (module docstring, step 1): steady
    times (:func:`uniformly_sampled`) whose median step is at most :data:`MAX_RECORDER_STEP`."""
    return uniformly_sampled(times) and float(np.median(np.diff(times))) <= MAX_RECORDER_STEP


def consecutive_change(signal: np.ndarray) -> np.ndarray:
    """``(N-1,)`` largest change of any signal entry from each row to the next [rad, m, or of an
    ``R_BS`` entry]."""
    return np.max(np.abs(np.diff(signal, axis=0)), axis=1, initial=0.0)


def runs_at_one_pose(times, signal, parameters: SegmentParameters) -> np.ndarray:
    """``(N,)`` run number of each row: consecutive rows at one pose (see the module docstring,
    step 2) share it: their change at most ``pose_tolerance``, and, when closer in time than
    :data:`MAX_RECORDER_STEP`, both still by the windowed speed.
    """
    times = np.asarray(times, dtype=float)
    still = joint_speed(times, signal, parameters.speed_window) < parameters.speed_threshold
    apart = np.diff(times) > MAX_RECORDER_STEP  # no recorder between them: displacement only
    same = (consecutive_change(signal) <= parameters.pose_tolerance) & (
        apart | (still[1:] & still[:-1])
    )
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
    step = float(np.median(np.diff(times))) if rows > 1 else None
    recorder = steady and step <= MAX_RECORDER_STEP
    tolerance = parameters.pose_tolerance
    if lengths.max(initial=0) < 2:
        if recorder and smooth_motion(signal):
            _refuse_motion(times, signal, parameters, quantity, source)
        reason = f"no row repeats the previous row's orientation (within {tolerance:g}) and " + (
            f"their changes are unrelated (not a sampled motion), though {_sampling(times)}"
            if recorder
            else _sampling(times)
        )
        return TableLayout(ONE_PER_POSE, reason, rows, rows, np.arange(rows), None, step)
    grouped = lengths[lengths >= 2]
    moving = int(np.count_nonzero(lengths == 1))
    if steady and moving > 0 and np.median(grouped) >= MIN_RUN:
        search = find_static_segments(times, signal, parameters, quantity)
        if not search.segments:
            _refuse_no_segment(search, source)
        _refuse_turning_segments(times, signal, search, quantity, source)
        reason = (
            f"rows every {step:.3g} s, {len(grouped)} still run(s) of a median "
            f"{np.median(grouped):g} rows with {moving} row(s) in motion between them"
        )
        return TableLayout(RECORDING, reason, rows, len(search.segments), None, search, step)
    _, pose_ids = np.unique(runs, return_inverse=True)
    reason = (
        f"runs of rows repeat one orientation (within {tolerance:g}), a median "
        f"{np.median(grouped):g} rows each, "
        + (
            f"with {moving} row(s) changing between them"
            if moving
            else "with no row in motion between them"
        )
        + f", and {_sampling(times)}"
    )
    return TableLayout(GROUPED, reason, rows, len(lengths), pose_ids.astype(np.int64), None, step)


def _sampling(times: np.ndarray) -> str:
    """One clause: how the rows were taken (module docstring, step 1)."""
    if len(times) < 2:
        return "there is a single row"
    step = float(np.median(np.diff(times)))
    if not uniformly_sampled(times):
        return f"the times are not a recorder's steady steps (median step {step:.3g} s)"
    if step > MAX_RECORDER_STEP:
        return (
            f"the rows are {step:.3g} s apart, longer than a recorder's step "
            f"(at most {MAX_RECORDER_STEP:g} s)"
        )
    return f"the rows come every {step:.3g} s (a recorder's rate)"


def _refuse_motion(times, signal, parameters: SegmentParameters, quantity: str, source: str):
    """A recorder's rows that never repeat an orientation and change steadily: a motion with no
    still pose (an excitation), refused."""
    search = find_static_segments(times, signal, parameters, quantity)
    raise InvalidSamples(
        f"a continuous motion ({times[-1] - times[0]:.3g} s) with no usable still segment: "
        f"{search.motion()}; {_sampling(times)} and no row repeats the previous row's "
        f"orientation (within {parameters.pose_tolerance:g}; the smallest change is "
        f"{consecutive_change(signal).min():.3g}): the arm never holds a pose; fit every row "
        "as a pose with --all-rows, or use the motion with 'calibrate --dynamic'",
        source,
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
