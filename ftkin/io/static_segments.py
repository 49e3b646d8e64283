"""Find the stretches of a recording where the arm stands still.

A recording (a ROS 2 bag, or a samples CSV with a time column and no pose
column) holds joint positions or orientations over time while the arm moves
from pose to pose. Static calibration needs the readings taken while the arm
is still, after vibrations have died out. :func:`find_static_segments` finds
them from the positions alone (joint angles, or the entries of ``R_BS`` for a
recording of orientations); the bag reader and the samples CSV share it:

1. joint speed at each joint sample: ``max_j |q_j(t + w/2) - q_j(t - w/2)| / w``
   over a window ``w`` (``speed_window`` [s]; positions linearly interpolated),
   which is robust to encoder jitter at high sample rates;
2. still where that speed is below ``speed_threshold`` [rad/s or m/s];
3. each maximal still stretch loses its first ``settle_time`` [s]; what is
   left becomes a :class:`StaticSegment` when it lasts at least
   ``min_duration`` [s].
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_in_range, as_positive


@dataclass(frozen=True)
class SegmentParameters:
    """How still, for how long, and how much settling to skip.

    Attributes:
        speed_threshold: Largest joint speed counted as still [rad/s or m/s].
        min_duration: Shortest usable still time after settling [s].
        settle_time: Time skipped at the start of each still stretch [s]
            (vibrations and controller settling after a move).
        speed_window: Time span of the finite difference for the speed [s].
        pose_tolerance: Largest change between two consecutive rows of a timed table at one
            pose [rad or m, or of an ``R_BS`` entry], whatever the time between them (see
            :mod:`ftkin.io.table_layout`).
    """

    speed_threshold: float = 0.01
    min_duration: float = 1.0
    settle_time: float = 0.5
    speed_window: float = 0.1
    pose_tolerance: float = 2e-3

    def __post_init__(self):
        for name in ("speed_threshold", "min_duration", "speed_window", "pose_tolerance"):
            object.__setattr__(self, name, as_positive(getattr(self, name), name))
        settle = as_in_range(self.settle_time, "settle_time", 0.0, 1e6, "s")
        object.__setattr__(self, "settle_time", settle)


@dataclass(frozen=True)
class StaticSegment:
    """A time interval where the arm was still (settling already skipped).

    Attributes:
        start: First usable time [s] (same clock as the input times).
        end: Last still time [s].
    """

    start: float
    end: float

    @property
    def duration(self) -> float:
        """Length of the segment [s]."""
        return self.end - self.start


@dataclass(frozen=True)
class SegmentSearch:
    """Segments found plus what was seen, for messages when none qualify.

    Attributes:
        segments: The static segments, in time order.
        still_stretches: Durations of every still stretch before settling [s].
        parameters: The parameters used.
        speeds: ``(N,)`` speed at each sample [rad/s or m/s, or 1/s for ``R_BS`` entries].
        quantity: What the speed is of (``"joint speed"``, ``"orientation speed"``).
        times: ``(N,)`` the sample times [s] searched, or None.
    """

    segments: list[StaticSegment]
    still_stretches: list[float]
    parameters: SegmentParameters
    speeds: np.ndarray | None = None
    quantity: str = "joint speed"
    times: np.ndarray | None = None

    @property
    def unit(self) -> str:
        """The speed's unit: rad/s for joint speeds, 1/s for the rate of the ``R_BS`` entries."""
        return "1/s" if self.quantity == "orientation speed" else "rad/s"

    @property
    def still(self) -> np.ndarray:
        """``(N,)`` True where the sample counts as still."""
        return self.speeds < self.parameters.speed_threshold

    def motion(self) -> str:
        """How much of the recording moves: the share of samples in motion and the peak speed."""
        moving = int(np.count_nonzero(~self.still))
        return (
            f"{moving} of {len(self.speeds)} samples ({100 * moving / len(self.speeds):.0f} %) in "
            f"motion, {self.quantity} up to {self.speeds.max():.3g} {self.unit}"
        )

    def describe(self) -> str:
        """One line: how many stretches, the longest, and the parameters."""
        p = self.parameters
        longest = max(self.still_stretches, default=0.0)
        return (
            f"{len(self.segments)} static segment(s) from {len(self.still_stretches)} still "
            f"stretch(es) (longest {longest:.3g} s); "
            f"still = {self.quantity} < {p.speed_threshold:g} {self.unit}, "
            f"usable ≥ {p.min_duration:g} s after skipping {p.settle_time:g} s of settling"
        )


def joint_speed(times, joint_positions, window: float) -> np.ndarray:
    """``(N,)`` largest joint speed at each sample [rad/s], central difference over ``window``
    [s].
    """
    times = as_float_array(times, "times")
    q = as_float_array(joint_positions, "joint positions")
    if q.ndim != 2 or len(q) != len(times):
        raise InvalidInput(
            f"joint positions must be (N, nq) with N = {len(times)} times, got shape {q.shape}"
        )
    if len(times) < 2:
        return np.zeros(len(times))
    if np.any(np.diff(times) < 0):
        raise InvalidInput("times must be sorted (non-decreasing)")
    ahead = np.clip(times + window / 2, times[0], times[-1])
    behind = np.clip(times - window / 2, times[0], times[-1])
    change = [np.abs(np.interp(ahead, times, c) - np.interp(behind, times, c)) for c in q.T]
    return np.max(change, axis=0, initial=0.0) / np.maximum(ahead - behind, 1e-12)


def find_static_segments(
    times,
    joint_positions,
    parameters: SegmentParameters | None = None,
    quantity: str = "joint speed",
) -> SegmentSearch:
    """Static segments of a joint trajectory (or of any position signal).

    Args:
        times: ``(N,)`` sample times [s], sorted.
        joint_positions: ``(N, nq)`` joint positions [rad or m] (or the nine
            entries of ``R_BS`` per sample for a recording of orientations).
        parameters: Thresholds (default :class:`SegmentParameters`).
        quantity: What the speed is of, for messages.

    Returns:
        A :class:`SegmentSearch` (possibly with no segments; callers decide
        whether that is an error).
    """
    parameters = parameters or SegmentParameters()
    times = as_float_array(times, "times")
    speed = joint_speed(times, joint_positions, parameters.speed_window)
    still = speed < parameters.speed_threshold
    edges = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(np.int8), [0]])))
    segments, stretches = [], []
    for first, stop in zip(edges[::2], edges[1::2]):
        start_time, end_time = times[first], times[stop - 1]
        stretches.append(float(end_time - start_time))
        usable_start = start_time + parameters.settle_time
        if end_time - usable_start >= parameters.min_duration:
            segments.append(StaticSegment(float(usable_start), float(end_time)))
    return SegmentSearch(segments, stretches, parameters, speed, quantity, times)


def segment_index(times, segments: list[StaticSegment]) -> np.ndarray:
    """``(M,)`` index of the segment each time falls in, ``-1`` outside every segment.

    ``segments`` are disjoint and in time order (as :func:`find_static_segments` returns them).
    """
    times = as_float_array(times, "times")
    if not segments:
        return np.full(len(times), -1, dtype=np.int64)
    starts = np.array([segment.start for segment in segments])
    ends = np.array([segment.end for segment in segments])
    index = (
        np.searchsorted(starts, times, side="right") - 1
    )  # last segment starting at or before each time
    inside = (index >= 0) & (times <= ends[index])
    return np.where(inside, index, -1).astype(np.int64)
