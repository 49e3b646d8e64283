"""The samples CSV of a session on a robot, written as it goes: one flushed block per pose.

Columns: the arm's joint names [rad], ``fx,fy,fz,mx,my,mz`` [N, N·m], ``pose`` (the pose's index
in the session's plan) and ``t`` [s, the sensor's stamp]: the table ``ftkin calibrate`` reads
(:mod:`ftkin.io.samples_csv`), then any extra columns (``ax,ay,az,wx,wy,wz``: the IMU's, which
``ftkin record`` writes for a sensor that has one; with no joint columns, the table of a
calibration from the IMU, :mod:`ftkin.io.imu_columns`). Each pose's rows are written in one
call, flushed and synced before the arm moves on (Ctrl-C held off meanwhile:
:func:`interrupts_held`), so an interrupted session loses at most the pose it was on, and a
resumed one (:meth:`SamplesLog.recorded_poses`) knows which poses are done.
"""

from __future__ import annotations

import logging
import os
import signal
import threading
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput, InvalidSamples
from ..io.atomic import atomic_write_text
from ..io.csv_table import read_table
from ..io.samples_csv import POSE_COLUMN

logger = logging.getLogger(__name__)

TIME_COLUMN = "t"


@contextmanager
def interrupts_held():
    """Hold Ctrl-C (SIGINT) off while a block of rows is written, and raise it after: the file
    and the writer's count of what it holds agree (on the main thread; elsewhere, where Python
    delivers no signal, it does nothing)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    caught = []
    previous = signal.signal(signal.SIGINT, lambda number, frame: caught.append(number))
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
    if caught:
        raise KeyboardInterrupt


def append_comment(path, text: str) -> None:
    """Write ``text`` as one ``#`` line at the end of the samples file ``path`` (a note learnt from
    its poses, e.g. the arm they were recorded on: :mod:`ftkin.io.recorded_robot`), flushed and
    synced; readers skip it wherever it is, and a resumed log appends after it."""
    line = " ".join(str(text).split())  # one line, whatever it held
    with open(path, "a", encoding="utf-8", newline="") as stream:
        stream.write(f"# {line}\n")
        stream.flush()
        os.fsync(stream.fileno())


class SamplesLog:
    """Append-only samples CSV of a session.

    Args:
        path: The file.
        joint_names: The arm's joint names (the joint columns, in ``q`` order).
        resume: Continue an existing file (its columns must match); False refuses an existing
            file (ftkin never overwrites an input).
        comments: Lines written as ``#`` comments above the header of a new file.
        extra_columns: Names of more columns after ``t`` (e.g. the IMU's ``ax,ay,az``), one
            value each per reading.

    Raises:
        InvalidInput: the file exists and ``resume`` is False, or its columns differ, or its last
            line is incomplete.
    """

    def __init__(self, path, joint_names, *, resume: bool = False, comments=(), extra_columns=()):
        self.path = Path(path)
        self.extra_columns = list(extra_columns)
        self.header = [*joint_names, *WRENCH_CHANNELS, POSE_COLUMN, TIME_COLUMN, *extra_columns]
        self._nq = len(joint_names)
        self._recorded: dict[int, np.ndarray] = {}
        self._recorded_extra: dict[int, np.ndarray] = {}
        exists = self.path.exists() and self.path.stat().st_size > 0
        if exists and not resume:
            raise InvalidInput(
                f"{self.path} already exists: pass resume=True (--resume) to continue that "
                "session, or choose another samples file"
            )
        if exists:
            self._read_existing()
        else:
            lines = [f"# {line}" for line in comments] + [",".join(self.header)]
            self._write("\n".join(lines) + "\n", mode="x" if not self.path.exists() else "w")

    def _read_existing(self) -> None:
        with open(self.path, "rb") as stream:
            stream.seek(max(0, self.path.stat().st_size - 1))
            if stream.read(1) != b"\n":
                raise InvalidInput(
                    f"the last line of {self.path} is incomplete (the session was stopped while "
                    "writing it): delete that line, then resume"
                )
        lines = [
            line
            for line in self.path.read_text(encoding="utf-8").splitlines()
            if line.strip() and not line.lstrip().startswith("#")
        ]
        if lines == [",".join(self.header)]:  # stopped before its first pose: nothing to read
            return
        table = read_table(self.path)
        if table.header != self.header:
            raise InvalidSamples(
                f"its columns {table.header} are not this session's {self.header} (another arm?)",
                str(self.path),
            )
        if not table.rows:
            return
        q = table.floats(self.header[: self._nq])
        extra = table.floats(self.extra_columns)
        poses = table.floats([POSE_COLUMN])[:, 0].astype(int)
        for pose in np.unique(poses):
            self._recorded[int(pose)] = q[poses == pose].mean(axis=0)
            self._recorded_extra[int(pose)] = extra[poses == pose].mean(axis=0)

    def _write(self, text: str, mode: str = "a") -> None:
        with open(self.path, mode, encoding="utf-8", newline="") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())

    def recorded_poses(self) -> dict[int, np.ndarray]:
        """``{pose id: mean joint positions (nq,) [rad]}`` of the poses in the file."""
        return dict(self._recorded)

    def recorded_extra(self) -> dict[int, np.ndarray]:
        """``{pose id: mean of the extra columns (k,)}`` of the poses in the file."""
        return dict(self._recorded_extra)

    def append_pose(self, pose_id: int, joint_positions, wrenches, times, extra=None) -> None:
        """Write one pose's readings (one write, flushed and synced); ``extra``: ``(n, k)``
        values of the extra columns.

        Raises:
            InvalidInput: the pose is already in the file, or the arrays do not match.
        """
        pose_id = int(pose_id)
        if pose_id in self._recorded:
            raise InvalidInput(f"pose {pose_id} is already recorded in {self.path}")
        q = np.asarray(joint_positions, dtype=float)
        w = np.asarray(wrenches, dtype=float)
        t = np.asarray(times, dtype=float).reshape(-1)
        k = len(self.extra_columns)
        e = np.zeros((len(t), 0)) if extra is None and not k else np.asarray(extra, dtype=float)
        if q.shape != (len(t), self._nq) or w.shape != (len(t), 6) or e.shape != (len(t), k):
            raise InvalidInput(
                f"expected ({len(t)}, {self._nq}) joint positions, ({len(t)}, 6) wrenches and "
                f"({len(t)}, {k}) extra values, got {q.shape}, {w.shape} and {e.shape}"
            )
        lines = [
            ",".join([*map(repr, map(float, q[i])), *map(repr, map(float, w[i])), str(pose_id)])
            + f",{float(t[i])!r}"
            + "".join(f",{float(value)!r}" for value in e[i])
            for i in range(len(t))
        ]
        self._write("\n".join(lines) + "\n")
        self._recorded[pose_id] = q.mean(axis=0)
        self._recorded_extra[pose_id] = e.mean(axis=0)

    def remove_pose(self, pose_id: int, reason: str) -> None:
        """Take one pose's rows out of the file (rewritten atomically, a ``#`` line saying why):
        a pose that did not fit the others, to be measured again.

        Raises:
            InvalidInput: the pose is not in the file.
        """
        pose_id = int(pose_id)
        if pose_id not in self._recorded:
            raise InvalidInput(f"pose {pose_id} is not recorded in {self.path}")
        column = self.header.index(POSE_COLUMN)
        kept = []
        for line in self.path.read_text(encoding="utf-8").splitlines():
            cells = line.split(",")
            data = (
                line.strip() and not line.lstrip().startswith("#") and line != ",".join(self.header)
            )
            if data and len(cells) > column and cells[column].strip() == str(pose_id):
                continue
            kept.append(line)
        header = kept.index(",".join(self.header))
        kept.insert(header, f"# pose {pose_id} removed: {reason}")
        with interrupts_held():
            atomic_write_text(self.path, "\n".join(kept) + "\n")
            del self._recorded[pose_id], self._recorded_extra[pose_id]
