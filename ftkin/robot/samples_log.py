"""The samples CSV of a session on a robot, written as it goes: one flushed block per pose.

Columns: the arm's joint names [rad], ``fx,fy,fz,mx,my,mz`` [N, N·m], ``pose`` (the pose's index
in the session's plan) and ``t`` [s, the sensor's stamp]: the table ``ftkin calibrate`` reads
(:mod:`ftkin.io.samples_csv`). Each pose's rows are written in one call, flushed and synced
before the arm moves on, so an interrupted session loses at most the pose it was on, and a
resumed one (:meth:`SamplesLog.recorded_poses`) knows which poses are done.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput, InvalidSamples
from ..io.csv_table import read_table
from ..io.samples_csv import POSE_COLUMN

logger = logging.getLogger(__name__)

TIME_COLUMN = "t"


class SamplesLog:
    """Append-only samples CSV of a session.

    Args:
        path: The file.
        joint_names: The arm's joint names (the joint columns, in ``q`` order).
        resume: Continue an existing file (its columns must match); False refuses an existing
            file (ftkin never overwrites an input).
        comments: Lines written as ``#`` comments above the header of a new file.

    Raises:
        InvalidInput: the file exists and ``resume`` is False, or its columns differ, or its last
            line is incomplete.
    """

    def __init__(self, path, joint_names, *, resume: bool = False, comments=()):
        self.path = Path(path)
        self.header = [*joint_names, *WRENCH_CHANNELS, POSE_COLUMN, TIME_COLUMN]
        self._nq = len(joint_names)
        self._recorded: dict[int, np.ndarray] = {}
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
        table = read_table(self.path)
        if table.header != self.header:
            raise InvalidSamples(
                f"its columns {table.header} are not this session's {self.header} (another arm?)",
                str(self.path),
            )
        if not table.rows:
            return
        q = table.floats(self.header[: self._nq])
        poses = table.floats([POSE_COLUMN])[:, 0].astype(int)
        for pose in np.unique(poses):
            self._recorded[int(pose)] = q[poses == pose].mean(axis=0)

    def _write(self, text: str, mode: str = "a") -> None:
        with open(self.path, mode, encoding="utf-8", newline="") as stream:
            stream.write(text)
            stream.flush()
            os.fsync(stream.fileno())

    def recorded_poses(self) -> dict[int, np.ndarray]:
        """``{pose id: mean joint positions (nq,) [rad]}`` of the poses in the file."""
        return dict(self._recorded)

    def append_pose(self, pose_id: int, joint_positions, wrenches, times) -> None:
        """Write one pose's readings (one write, flushed and synced).

        Raises:
            InvalidInput: the pose is already in the file, or the arrays do not match.
        """
        pose_id = int(pose_id)
        if pose_id in self._recorded:
            raise InvalidInput(f"pose {pose_id} is already recorded in {self.path}")
        q = np.asarray(joint_positions, dtype=float)
        w = np.asarray(wrenches, dtype=float)
        t = np.asarray(times, dtype=float).reshape(-1)
        if q.shape != (len(t), self._nq) or w.shape != (len(t), 6):
            raise InvalidInput(
                f"expected ({len(t)}, {self._nq}) joint positions and ({len(t)}, 6) wrenches, got "
                f"{q.shape} and {w.shape}"
            )
        lines = [
            ",".join([*map(repr, map(float, q[i])), *map(repr, map(float, w[i])), str(pose_id)])
            + f",{float(t[i])!r}"
            for i in range(len(t))
        ]
        self._write("\n".join(lines) + "\n")
        self._recorded[pose_id] = q.mean(axis=0)
