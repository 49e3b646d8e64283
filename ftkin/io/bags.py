"""Calibration samples straight from a ROS 2 bag (optional extra ``bags``).

Reads a bag (a rosbag2 folder with sqlite3 or MCAP storage, or a bare
``.mcap`` file) with the pure-Python ``rosbags`` library, no ROS install:

* a ``sensor_msgs/msg/JointState`` topic and a ``geometry_msgs/msg/WrenchStamped``
  topic, named or auto-detected by message type;
* times from the messages' header stamps [s] (the bag's receive time when a
  topic's stamps are all zero);
* joint positions matched to the arm's joints **by name** (extra joints are
  ignored; each joint may come from different messages) and linearly
  interpolated to each wrench stamp; wrench samples outside the joint-state
  time range are dropped;
* static segments found from the joint trajectory
  (:mod:`ftkin.io.static_segments`), each becoming one pose id whose readings are
  the wrenches inside it.

Wrenches are the raw sensor readings ``[fx, fy, fz, mx, my, mz]`` [N, N·m] in
the sensor frame; the messages' ``frame_id`` is checked against the sensor
frame, and a base-frame wrench is converted on request (:mod:`ftkin.io.wrench_frames`).
"""

import logging
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..calibration.samples import Samples
from ..exceptions import InvalidSamples, MissingDependency
from ..progress import Progress
from .csv_table import Table, format_float
from .samples_csv import POSE_COLUMN, LoadedSamples
from .static_segments import SegmentParameters, find_static_segments, segment_index
from .table_layout import RECORDING, TableLayout
from .time_columns import TIME_COLUMN
from .wrench_frames import wrenches_in_sensor_frame

logger = logging.getLogger(__name__)

JOINT_STATE_TYPE = "sensor_msgs/msg/JointState"
WRENCH_TYPE = "geometry_msgs/msg/WrenchStamped"
BAG_SUFFIXES = (".mcap", ".db3")


def is_bag_path(path) -> bool:
    """True for a rosbag2 folder (with ``metadata.yaml``), a ``.mcap`` or a ``.db3`` file."""
    path = Path(path)
    return path.suffix.lower() in BAG_SUFFIXES or (
        path.is_dir() and (path / "metadata.yaml").is_file()
    )


@dataclass(frozen=True)
class BagRecording:
    """Wrench readings with joint positions interpolated to their stamps.

    Attributes:
        source: The bag path.
        joint_topic, wrench_topic: Topics read.
        wrench_frame_id: ``header.frame_id`` of the first wrench message.
        joint_names: The arm's joint names, in ``q`` order.
        joint_times: ``(K,)`` joint-state stamps [s].
        joint_trajectory: ``(K, nq)`` joint positions at those stamps [rad or m].
        times: ``(M,)`` wrench stamps [s] inside the joint-state time range.
        wrenches: ``(M, 6)`` raw readings [N, N·m], sensor frame.
        joint_positions: ``(M, nq)`` joint positions interpolated to ``times``.
        dropped: Wrench messages outside the joint-state time range.
    """

    source: str
    joint_topic: str
    wrench_topic: str
    wrench_frame_id: str
    joint_names: list[str]
    joint_times: np.ndarray
    joint_trajectory: np.ndarray
    times: np.ndarray
    wrenches: np.ndarray
    joint_positions: np.ndarray
    dropped: int


@dataclass(frozen=True)
class BagSamples(LoadedSamples):
    """:class:`~ftkin.io.samples_csv.LoadedSamples` from a bag, with what was found in it
    (``recording``).
    """

    recording: BagRecording | None = None  # the base's property (None for a CSV), as a field


def _rosbags():
    try:
        from rosbags.highlevel import AnyReader, AnyReaderError
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise MissingDependency("rosbags", "bags", "reading ROS 2 bags") from None
    return AnyReader, AnyReaderError, get_typestore(Stores.ROS2_HUMBLE)


def _topic_listing(connections) -> str:
    return ", ".join(sorted({f"{c.topic} ({c.msgtype})" for c in connections})) or "none"


def _pick_topic(connections, topic, msgtype, flag, source):
    if topic is not None:
        chosen = [c for c in connections if c.topic == topic]
        if not chosen:
            raise InvalidSamples(
                f"no topic {topic!r} in the bag; topics found: {_topic_listing(connections)}",
                source,
            )
        if chosen[0].msgtype != msgtype:
            raise InvalidSamples(
                f"topic {topic!r} carries {chosen[0].msgtype}, expected {msgtype}", source
            )
        return chosen
    topics = sorted({c.topic for c in connections if c.msgtype == msgtype})
    if not topics:
        raise InvalidSamples(
            f"no {msgtype} topic in the bag; topics found: {_topic_listing(connections)}", source
        )
    if len(topics) > 1:
        raise InvalidSamples(f"several {msgtype} topics: {topics}; choose one with {flag}", source)
    return [c for c in connections if c.topic == topics[0]]


def _stamps(header_times: np.ndarray, log_times: np.ndarray, topic: str) -> np.ndarray:
    """The header stamps [s], or the bag's receive times [ns → s] when the stamps are all zero."""
    if len(header_times) and not np.any(header_times):
        logger.warning("%s: all header stamps are zero; using the bag's receive times", topic)
        return log_times * 1e-9
    return header_times


class _Messages:
    """The two topics' messages as they are read: stamps, wrench rows, joint series by name."""

    def __init__(self, source: str):
        self.source = source
        self.joint_stamps: list[tuple[float, int]] = []  # (header stamp [s], receive time [ns])
        self.wrench_rows: list[tuple] = []  # (fx, fy, fz, mx, my, mz, header stamp, receive time)
        self.frame_id = ""
        self.series: dict[str, tuple[list[int], list[float]]] = {}  # name -> (messages, values)

    def add(self, connection, log_time: int, message) -> None:
        """One deserialized message of either topic."""
        stamp = message.header.stamp.sec + message.header.stamp.nanosec * 1e-9
        if connection.msgtype == WRENCH_TYPE:
            force, torque = message.wrench.force, message.wrench.torque
            self.wrench_rows.append(
                (force.x, force.y, force.z, torque.x, torque.y, torque.z, stamp, log_time)
            )
            self.frame_id = self.frame_id or message.header.frame_id
            return
        if len(message.position) != len(message.name):
            raise InvalidSamples(
                f"{connection.topic}: a JointState has {len(message.name)} names but "
                f"{len(message.position)} positions",
                self.source,
            )
        for name, value in zip(message.name, message.position):
            indices, positions = self.series.setdefault(name, ([], []))
            indices.append(len(self.joint_stamps))
            positions.append(float(value))
        self.joint_stamps.append((stamp, log_time))

    def joint_trajectory(self, topic: str, names: list[str]):
        """``(joint_times (K,), trajectory (K, nq))``: every joint interpolated to every stamp."""
        joint_stamps = np.asarray(self.joint_stamps, dtype=float)
        message_times = _stamps(joint_stamps[:, 0], joint_stamps[:, 1], topic)
        series = {
            name: (message_times[self.series[name][0]], self.series[name][1]) for name in names
        }
        joint_times = np.unique(np.concatenate([stamps for stamps, _ in series.values()]))
        trajectory = np.empty((len(joint_times), len(names)))
        for column, (stamps, values) in enumerate(series.values()):
            order = np.argsort(stamps, kind="stable")
            trajectory[:, column] = np.interp(joint_times, stamps[order], np.asarray(values)[order])
        return joint_times, trajectory


def _read_messages(path: Path, source: str, joint_topic, wrench_topic, progress):
    """The joint and wrench connections chosen and their messages (:class:`_Messages`)."""
    any_reader, reader_error, typestore = _rosbags()

    messages = _Messages(source)
    try:
        with any_reader([path], default_typestore=typestore) as reader:
            joints = _pick_topic(
                reader.connections, joint_topic, JOINT_STATE_TYPE, "--joint-topic", source
            )
            wrench = _pick_topic(
                reader.connections, wrench_topic, WRENCH_TYPE, "--wrench-topic", source
            )
            total = sum(c.msgcount for c in joints + wrench)
            with Progress(total, "reading bag", enabled=progress) as bar:
                for connection, log_time, raw in reader.messages(connections=joints + wrench):
                    messages.add(connection, log_time, reader.deserialize(raw, connection.msgtype))
                    bar.advance()
    except reader_error as error:
        raise InvalidSamples(f"cannot read the bag: {error}", source) from None
    except InvalidSamples:
        raise
    except FileNotFoundError as error:  # a bag's .db3 given without its metadata.yaml beside it
        raise InvalidSamples(
            f"cannot read the bag: {error} (a ROS 2 .db3 bag is read from its folder, with its "
            "metadata.yaml: give the folder)",
            source,
        ) from None
    except Exception as error:  # a corrupt bag: rosbags raises struct, decode, index, memory errors
        raise InvalidSamples(
            f"cannot read the bag (corrupt or truncated?): {type(error).__name__}: {error}", source
        ) from None
    return joints[0].topic, wrench[0].topic, messages


def read_bag(
    path,
    arm,
    joint_topic: str | None = None,
    wrench_topic: str | None = None,
    progress: bool | None = None,
) -> BagRecording:
    """Read the joint and wrench topics of a bag and align them in time.

    Args:
        path: rosbag2 folder, ``.mcap`` file, or a ``.db3`` file (its folder is read).
        arm: The :class:`~ftkin.kinematics.arm.Arm` whose joints to extract, by name.
        joint_topic, wrench_topic: Topic names; None to pick the only topic of
            the right type.
        progress: Progress bar on stderr (default: when it is a terminal).

    Raises:
        InvalidSamples: unreadable bag, missing or ambiguous topic, joint
            names not matching the arm (lists found vs expected), or no
            wrench inside the joint-state time range.
        MissingDependency: ``rosbags`` is not installed.
    """
    path = Path(path)
    source = str(path)
    if not path.exists():
        raise InvalidSamples("file not found", source)
    folder = path.parent if path.suffix.lower() == ".db3" else path
    joint_topic, wrench_topic, messages = _read_messages(
        folder, source, joint_topic, wrench_topic, progress
    )
    expected = list(arm.joint_names)
    missing = [name for name in expected if name not in messages.series]
    if missing:
        raise InvalidSamples(
            f"joint names on {joint_topic} do not match the arm: missing {missing}; "
            f"the bag has {sorted(messages.series)}; the arm ({arm!r}) expects {expected}",
            source,
        )
    if not messages.wrench_rows:
        raise InvalidSamples(f"no messages on {wrench_topic}", source)
    joint_times, trajectory = messages.joint_trajectory(joint_topic, expected)
    rows = np.asarray(messages.wrench_rows, dtype=float)
    times = _stamps(rows[:, 6], rows[:, 7], wrench_topic)
    order = np.argsort(times, kind="stable")
    times, wrenches = times[order], rows[order, :6]
    inside = (times >= joint_times[0]) & (times <= joint_times[-1])
    if not np.any(inside):
        raise InvalidSamples(
            f"no {wrench_topic} stamp falls inside the {joint_topic} time range "
            f"[{joint_times[0]:.3f}, {joint_times[-1]:.3f}] s (wrench stamps [{times[0]:.3f}, "
            f"{times[-1]:.3f}] s)",
            source,
        )
    times, wrenches = times[inside], wrenches[inside]
    positions = np.column_stack(
        [np.interp(times, joint_times, trajectory[:, j]) for j in range(len(expected))]
    )
    return BagRecording(
        source,
        joint_topic,
        wrench_topic,
        messages.frame_id,
        expected,
        joint_times,
        trajectory,
        times,
        wrenches,
        positions,
        int(np.count_nonzero(~inside)),
    )


def _table(source: str, columns: list[tuple[str, np.ndarray]]) -> Table:
    """A :class:`Table` of text cells (integers as integers, floats round-tripping exactly).

    ``columns`` is a list, not a dict: a joint named like another column (``t``, ``fx``) must
    show as a duplicate header, which the readers refuse, not replace that column silently.
    """
    cells = [
        [str(int(v)) for v in column]
        if np.issubdtype(column.dtype, np.integer)
        else [format_float(v) for v in column]
        for _, column in columns
    ]
    rows = [list(row) for row in zip(*cells)]
    return Table(source, [name for name, _ in columns], rows, list(range(1, len(rows) + 1)))


def bag_samples(
    path,
    arm=None,
    *,
    joint_topic: str | None = None,
    wrench_topic: str | None = None,
    parameters: SegmentParameters | None = None,
    static_only: bool = True,
    progress: bool | None = None,
    wrench_frame: str = "sensor",
) -> BagSamples:
    """Calibration (or compensation) samples from a bag.

    Args:
        path, joint_topic, wrench_topic, progress: See :func:`read_bag`.
        arm: The arm (default: the bundled one).
        parameters: Static-segment thresholds (see :class:`SegmentParameters`).
        static_only: True: only readings inside static segments, pose id =
            segment number (for calibration). False: every reading, one pose
            each, no segment search (for compensation).
        wrench_frame: ``"sensor"`` or ``"base"`` (see
            :func:`~ftkin.io.wrench_frames.wrenches_in_sensor_frame`).

    Returns:
        :class:`BagSamples` whose ``table`` has columns ``t`` [s], ``pose``
        (static only), the arm's joint names [rad] and ``fx..mz``.

    Raises:
        InvalidSamples: see :func:`read_bag`; also no static segment found
            (the message says what was seen and which thresholds were used).
    """
    if arm is None:
        from ..kinematics.arm import Arm

        arm = Arm.default()
    recording = read_bag(path, arm, joint_topic, wrench_topic, progress)
    times, positions = recording.times, recording.joint_positions
    wrenches = wrenches_in_sensor_frame(
        recording.wrenches,
        arm.rotation_sensor_to_base(positions),
        recording.wrench_frame_id,
        arm,
        wrench_frame,
        recording.source,
    )
    search, pose_ids = None, None
    if static_only:
        search = find_static_segments(recording.joint_times, recording.joint_trajectory, parameters)
        index = segment_index(times, search.segments)
        keep = index >= 0
        if not np.any(keep):
            duration = recording.joint_times[-1] - recording.joint_times[0]
            raise InvalidSamples(
                f"no static segments with wrench readings in {duration:.3g} s of "
                f"{recording.joint_topic}: "
                f"{search.describe()}; lower --min-static-duration/--settle-time or raise "
                "--speed-threshold",
                recording.source,
            )
        used = np.unique(index[keep])
        if len(used) < len(search.segments):
            logger.warning(
                "%d static segment(s) hold no wrench reading", len(search.segments) - len(used)
            )
        times, wrenches, positions = times[keep], wrenches[keep], positions[keep]
        pose_ids = np.searchsorted(used, index[keep])
    logger.info(
        "%s: %d readings%s",
        recording.source,
        len(times),
        f", {search.describe()}" if search is not None else "",
    )
    columns = [
        (TIME_COLUMN, times),
        *([] if pose_ids is None else [(POSE_COLUMN, pose_ids)]),
        *zip(recording.joint_names, positions.T),
        *zip(WRENCH_CHANNELS, wrenches.T),
    ]
    table = _table(recording.source, columns)
    samples = Samples.from_joint_positions(arm, positions, wrenches, pose_ids, times=times)
    layout = None
    if search is not None:
        layout = TableLayout(
            RECORDING,
            f"the joint states of a bag ({len(recording.joint_times)} messages)",
            len(recording.joint_times),
            len(search.segments),
            None,
            search,
        )
    return BagSamples(
        samples, table, "joints", list(recording.joint_names), layout, recording=recording
    )
