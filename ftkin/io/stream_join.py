"""Streams at different rates joined by time: several tables, each on its own clock rate, onto the
wrench's stamps.

A :class:`Stream` is one table: strictly increasing times [s] and named columns. Its role is read
from its columns (:func:`stream_roles`): the wrench ``fx..mz``, the IMU's accelerometer
``ax,ay,az`` and gyro ``wx,wy,wz``, an orientation ``qw,qx,qy,qz``, joints (any other numeric
column). :func:`join_streams` puts every column on the stamps of the stream holding the wrench
(the output rate is the wrench's):

* orientations are interpolated by slerp (shortest arc), everything else linearly; a ``pose``
  column is held from the previous sample (an id, not a quantity);
* only the time every stream covers is kept: rows of the wrench outside the overlap are dropped
  and :attr:`JoinedStreams.notes` says so; streams that do not overlap at all are refused;
* stamps that do not increase are refused, naming the file's line;
* a gap in a stream longer than ``max_gap`` (default :data:`GAP_PERIODS` of its median period)
  leaves the rows inside it without data: they are dropped (``gaps="drop"``) or kept and marked
  (``gaps="mark"``: :attr:`JoinedStreams.in_gap`), and the notes say which.
"""

import logging
from dataclasses import dataclass, field

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput, InvalidSamples
from ..validation import as_float_array

logger = logging.getLogger(__name__)

ACCEL_COLUMNS = ("ax", "ay", "az")
"""The accelerometer's specific force [m/s² or g], IMU frame."""
GYRO_COLUMNS = ("wx", "wy", "wz")
"""The gyro's angular velocity [rad/s], IMU frame."""
ORIENTATION_COLUMNS = ("qw", "qx", "qy", "qz")
"""A unit quaternion (slerp-interpolated)."""
HELD_COLUMNS = ("pose",)
"""Columns held from the previous sample instead of interpolated (ids)."""

ROLE_COLUMNS = {
    "wrench": WRENCH_CHANNELS,
    "accelerometer": ACCEL_COLUMNS,
    "gyro": GYRO_COLUMNS,
    "orientation": ORIENTATION_COLUMNS,
}
"""The columns that give a stream each role (all of them, or none)."""

GAP_POLICIES = ("drop", "mark")
GAP_PERIODS = 5.0
"""Default longest gap between two stamps of a stream, in its median periods."""


@dataclass(frozen=True)
class Stream:
    """One table on its own clock.

    Attributes:
        name: Where it came from (a file name), used in messages.
        times: ``(N,)`` stamps [s], strictly increasing.
        columns: Column name → ``(N,)`` values.
        lines: ``(N,)`` file line of each row (for messages), or None.
    """

    name: str
    times: np.ndarray
    columns: dict
    lines: np.ndarray | None = None

    def __post_init__(self):
        times = as_float_array(self.times, f"{self.name}: times [s]").reshape(-1)
        if len(times) < 2:
            raise InvalidSamples(f"{len(times)} row(s); a stream needs at least two", self.name)
        where = lambda i: None if self.lines is None else int(self.lines[i])  # noqa: E731
        if not np.all(np.isfinite(times)):
            i = int(np.argmin(np.isfinite(times)))
            raise InvalidSamples(f"time stamp {times[i]} is not finite", self.name, where(i))
        steps = np.diff(times)
        if np.any(steps <= 0.0):
            i = int(np.argmax(steps <= 0.0)) + 1
            raise InvalidSamples(
                f"time stamps do not increase: t = {times[i]:.9g} s after {times[i - 1]:.9g} s "
                "(rows out of order or repeated; sort the file or fix its clock)",
                self.name,
                where(i),
            )
        columns = {}
        for key, values in self.columns.items():
            array = as_float_array(values, f"{self.name}: column {key!r}").reshape(-1)
            if len(array) != len(times):
                raise InvalidSamples(
                    f"column {key!r} has {len(array)} values for {len(times)} stamps", self.name
                )
            array = array.copy()
            array.setflags(write=False)
            columns[str(key)] = array
        times = times.copy()
        times.setflags(write=False)
        object.__setattr__(self, "times", times)
        object.__setattr__(self, "columns", columns)
        stream_roles(columns, self.name)  # an incomplete set of a role's columns is refused here

    @property
    def roles(self) -> tuple[str, ...]:
        """What the columns give: ``wrench``, ``accelerometer``, ``gyro``, ``orientation``,
        ``joints`` (other columns)."""
        return stream_roles(self.columns, self.name)

    @property
    def period(self) -> float:
        """Median step between stamps [s]."""
        return float(np.median(np.diff(self.times)))


def stream_roles(columns, name: str = "<stream>") -> tuple[str, ...]:
    """The roles of a stream's columns (see :data:`ROLE_COLUMNS`); other columns are joints.

    Raises:
        InvalidSamples: a role's columns present only in part (``ax, ay`` without ``az``).
    """
    roles = []
    for role, names in ROLE_COLUMNS.items():
        present = [column for column in names if column in columns]
        if present and len(present) < len(names):
            missing = [column for column in names if column not in columns]
            raise InvalidSamples(
                f"{role} columns {present} without {missing}: give all of {', '.join(names)}",
                name,
            )
        if present:
            roles.append(role)
    claimed = {column for names in ROLE_COLUMNS.values() for column in names}
    if any(column not in claimed and column not in HELD_COLUMNS for column in columns):
        roles.append("joints")
    return tuple(roles)


@dataclass(frozen=True)
class JoinedStreams:
    """Every stream's columns on the wrench's stamps.

    Attributes:
        times: ``(M,)`` output stamps [s] (the wrench's, inside the overlap).
        columns: Column name → ``(M,)`` values.
        in_gap: ``(M,)`` True where a stream had a gap longer than the limit (only with
            ``gaps="mark"``; dropped rows are gone).
        overlap: ``(start, end)`` [s] that every stream covers.
        sources: Column name → the stream it came from.
        notes: What was dropped or marked, one sentence each (also logged).
    """

    times: np.ndarray
    columns: dict
    in_gap: np.ndarray
    overlap: tuple[float, float]
    sources: dict
    notes: tuple[str, ...] = field(default=())

    def __len__(self) -> int:
        return len(self.times)

    def has(self, role: str) -> bool:
        """Whether the joined columns give ``role`` (see :data:`ROLE_COLUMNS`)."""
        return all(name in self.columns for name in ROLE_COLUMNS[role])

    def array(self, names) -> np.ndarray:
        """The named columns as ``(M, k)``.

        Raises:
            InvalidInput: a column no stream had.
        """
        missing = [name for name in names if name not in self.columns]
        if missing:
            raise InvalidInput(
                f"no stream has the column(s) {', '.join(missing)}; columns: "
                f"{', '.join(self.columns)}"
            )
        return np.stack([self.columns[name] for name in names], axis=1)


def slerp(times: np.ndarray, quaternions: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(M, 4)`` ``[w, x, y, z]`` at ``at`` by slerp between the samples
    ``(N, 4)`` at ``times`` (shortest arc; ``at`` within ``[times[0], times[-1]]``)."""
    unit = quaternions / np.linalg.norm(quaternions, axis=1)[:, None]
    index = np.clip(np.searchsorted(times, at, side="right") - 1, 0, len(times) - 2)
    fraction = (at - times[index]) / (times[index + 1] - times[index])
    first, second = unit[index], unit[index + 1]
    dot = np.einsum("ij,ij->i", first, second)
    second = np.where(dot[:, None] < 0.0, -second, second)  # q and −q: the same rotation
    dot = np.abs(dot)
    angle = np.arccos(np.clip(dot, -1.0, 1.0))
    small = angle < 1e-6
    sine = np.where(small, 1.0, np.sin(angle))
    weight0 = np.where(small, 1.0 - fraction, np.sin((1.0 - fraction) * angle) / sine)
    weight1 = np.where(small, fraction, np.sin(fraction * angle) / sine)
    out = weight0[:, None] * first + weight1[:, None] * second
    return out / np.linalg.norm(out, axis=1)[:, None]


def seconds_text(value: float) -> str:
    """A time stamp [s] as text: to the millisecond when it is a clock's (since the epoch), so
    that two stamps of one run read apart."""
    return f"{value:.3f}" if abs(value) >= 1e5 else f"{value:.6g}"


def _span(stream: Stream) -> str:
    return f"{stream.name} {seconds_text(stream.times[0])}–{seconds_text(stream.times[-1])} s"


def _gaps(stream: Stream, limit: float, at: np.ndarray) -> tuple[np.ndarray, list[str]]:
    """Which of ``at`` fall in a gap of ``stream`` longer than ``limit`` [s], and the gaps."""
    steps = np.diff(stream.times)
    starts = np.flatnonzero(steps > limit)
    inside = np.zeros(len(at), dtype=bool)
    described = []
    for k in starts:
        begin, end = stream.times[k], stream.times[k + 1]
        hit = (at > begin) & (at < end)
        inside |= hit
        line = "" if stream.lines is None else f" (after line {int(stream.lines[k])})"
        described.append(
            f"{seconds_text(begin)}–{seconds_text(end)} s{line}: {int(hit.sum())} rows"
        )
    return inside, described


def join_streams(
    streams, *, max_gap: float | None = None, gaps: str = "drop", reference: str | None = None
) -> JoinedStreams:
    """Join streams on time, at the rate of the one holding the wrench.

    Args:
        streams: :class:`Stream` objects (any order).
        max_gap: Longest step [s] between two stamps of a stream before the rows in between have
            no data; default :data:`GAP_PERIODS` of each stream's median period.
        gaps: ``"drop"`` (default) the rows inside a gap, or ``"mark"`` them (:attr:`in_gap`).
        reference: The name of the stream whose stamps the output takes (default: the one with
            the wrench columns).

    Raises:
        InvalidSamples: no stream or several with the wrench, a column in two streams, streams
            that do not overlap in time.
        InvalidInput: a bad ``max_gap`` or ``gaps``.
    """
    streams = list(streams)
    if not streams or not all(isinstance(s, Stream) for s in streams):
        raise InvalidInput("join_streams takes one or more ftkin Stream objects")
    if gaps not in GAP_POLICIES:
        raise InvalidInput(f"gaps must be one of {', '.join(GAP_POLICIES)}, got {gaps!r}")
    if max_gap is not None and not (np.isfinite(max_gap) and max_gap > 0.0):
        raise InvalidInput(f"max_gap must be a positive number of seconds, got {max_gap!r}")
    if reference is None:
        holders = [s for s in streams if "wrench" in s.roles]
        if len(holders) != 1:
            found = ", ".join(s.name for s in holders) or "none"
            raise InvalidSamples(
                f"exactly one stream must hold the wrench (fx..mz) to set the output rate; found "
                f"{found}"
            )
        base = holders[0]
    else:
        named = [s for s in streams if s.name == reference]
        if len(named) != 1:
            raise InvalidInput(f"no single stream named {reference!r}")
        base = named[0]
    sources: dict[str, str] = {}
    for stream in streams:
        for name in stream.columns:
            if name in sources:
                raise InvalidSamples(
                    f"column {name!r} is in both {sources[name]} and {stream.name}: which one is "
                    "meant is ambiguous; rename or drop one"
                )
            sources[name] = stream.name
    start = max(s.times[0] for s in streams)
    end = min(s.times[-1] for s in streams)
    keep = (base.times >= start) & (base.times <= end)
    at = base.times[keep]
    if not start < end or len(at) < 2:
        raise InvalidSamples(
            "the streams do not overlap in time"
            + (f" (in fewer than two rows of {base.name})" if start < end else "")
            + ": "
            + "; ".join(_span(s) for s in streams)
            + ": are they from one run, on one clock and in one time unit?"
        )
    notes = []
    if not keep.all():
        before, after = int(np.sum(base.times < start)), int(np.sum(base.times > end))
        notes.append(
            f"the output covers the overlap {seconds_text(start)}–{seconds_text(end)} s of "
            + "; ".join(_span(s) for s in streams)
            + f": {before} rows of {base.name} before it and {after} after it dropped"
        )
    columns = {name: values[keep] for name, values in base.columns.items()}
    in_gap = np.zeros(len(at), dtype=bool)
    for stream in streams:
        if stream is base:
            continue
        limit = GAP_PERIODS * stream.period if max_gap is None else float(max_gap)
        hit, described = _gaps(stream, limit, at)
        if described:
            action = "dropped" if gaps == "drop" else "marked (in_gap)"
            notes.append(
                f"{stream.name} has {len(described)} gap(s) longer than {limit:.6g} s; the rows "
                f"inside are {action}: " + "; ".join(described)
            )
        in_gap |= hit
        for name, values in stream.columns.items():
            if name in HELD_COLUMNS:
                index = np.searchsorted(stream.times, at, side="right") - 1
                columns[name] = values[np.clip(index, 0, len(values) - 1)]
            elif name not in ORIENTATION_COLUMNS:
                columns[name] = np.interp(at, stream.times, values)
        if "orientation" in stream.roles:
            quaternions = np.stack([stream.columns[n] for n in ORIENTATION_COLUMNS], axis=1)
            joined = slerp(stream.times, quaternions, at)
            for i, name in enumerate(ORIENTATION_COLUMNS):
                columns[name] = joined[:, i]
    if gaps == "drop" and in_gap.any():
        kept = ~in_gap
        at, in_gap = at[kept], in_gap[kept]
        columns = {name: values[kept] for name, values in columns.items()}
    if len(at) == 0:
        raise InvalidSamples(
            "no row is left after joining: " + " ".join(notes) if notes else "no row in common"
        )
    for note in notes:
        logger.warning("%s", note)
    for values in columns.values():
        values.setflags(write=False)
    return JoinedStreams(at, columns, in_gap, (float(start), float(end)), sources, tuple(notes))
