"""Moving recordings: time, joint positions and raw wrenches, from a CSV or a ROS 2 bag.

A motion CSV has a time column ``t`` [s] (uniformly sampled), the joint
columns of the samples CSV (the URDF's joint names or ``q1..qn`` [rad]) and
the wrench columns ``fx..mz`` [N, N·m] (see :mod:`ftkin.io.samples_csv`).
Other columns are carried along. A bag is read with
:func:`ftkin.io.bags.read_bag` (joint positions interpolated to the wrench
stamps) and resampled to a uniform grid at the wrench rate when its stamps
jitter.

:meth:`MotionRecording.motion_samples` differentiates the joint positions with
the zero-phase Savitzky–Golay filter, which assumes a uniform grid: a CSV must
be sampled uniformly (steps within 5 % of the median, else an error asks to
resample it), a bag is resampled linearly whenever its steps vary by more than
0.1 % (wrench stamps jitter on a real system). The filter (:mod:`ftkin.calibration.derivatives`)
and runs the kinematics: :class:`~ftkin.calibration.regressor.MotionSamples` out.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..calibration.derivatives import DEFAULT_POLYORDER, joint_derivatives
from ..calibration.model import WRENCH_CHANNELS
from ..calibration.regressor import MotionSamples
from ..exceptions import InvalidInput, InvalidSamples
from .csv_table import Table, missing_columns, read_table
from .samples_csv import check_radians, detect_orientation
from .time_columns import TIME_COLUMN, time_column, times_from_table

JITTER_TOLERANCE = 1e-3
"""Largest deviation of a bag's time step from the median step [fraction] accepted without resampling."""


@dataclass(frozen=True)
class MotionRecording:
    """Uniformly sampled joint positions and raw readings.

    Attributes:
        source: File or bag the data came from.
        times: ``(N,)`` [s], uniform.
        joint_positions: ``(N, nq)`` [rad], in the arm's joint order.
        wrenches: ``(N, 6)`` raw readings, sensor frame [N, N·m].
        table: The CSV table (for copying other columns), or None for a bag.
    """

    source: str
    times: np.ndarray
    joint_positions: np.ndarray
    wrenches: np.ndarray
    table: Table | None = None

    def motion_samples(self, arm, window: int | None = None, polyorder: int = DEFAULT_POLYORDER) -> MotionSamples:
        """Zero-phase ``q, dq, ddq`` and the sensor frame's motion (:class:`MotionSamples`).

        Raises:
            InvalidSamples: the times are not uniform or too few for the window.
        """
        try:
            q, dq, ddq = joint_derivatives(self.times, self.joint_positions, window, polyorder)
        except InvalidInput as error:
            raise InvalidSamples(str(error), self.source) from None
        return MotionSamples.from_joint_trajectory(arm, q, dq, ddq, self.wrenches, self.times)


def is_motion_table(table: Table, arm) -> bool:
    """True when the table has a ``t`` column and joint columns (a moving recording)."""
    try:
        if time_column(table) is None:
            return False
        kind, _ = detect_orientation(table, arm.joint_names)
    except InvalidSamples:
        return False
    return kind == "joints"


def motion_from_table(table: Table, arm) -> MotionRecording:
    """A :class:`MotionRecording` from a parsed motion CSV.

    Raises:
        InvalidSamples: missing ``t``, joint or wrench columns, joint angles in
            degrees, or times not increasing (with file and line).
    """
    if time_column(table) is None:
        missing_columns(table, (TIME_COLUMN,), "time")
    missing_columns(table, WRENCH_CHANNELS, "wrench")
    kind, columns = detect_orientation(table, arm.joint_names)
    if kind != "joints":
        raise InvalidSamples(
            f"a moving recording needs joint columns (the arm's {arm.joint_names} or q1..q{arm.nq}), found {kind} columns",
            table.source,
        )
    joints = table.floats(columns)
    check_radians(table, columns, joints)
    times = times_from_table(table)
    steps = np.diff(times)
    if np.any(steps <= 0):
        row = int(np.flatnonzero(steps <= 0)[0]) + 1
        message = f"time {times[row]!r} s does not increase; expected strictly increasing stamps"
        raise InvalidSamples(message, table.source, table.lines[row])
    return MotionRecording(table.source, times, joints, table.floats(WRENCH_CHANNELS), table)


def load_motion_csv(path, arm) -> MotionRecording:
    """Read a motion CSV (see the module docstring)."""
    return motion_from_table(read_table(path), arm)


def uniform(times: np.ndarray, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """Resample ``arrays`` ``(N, k)`` onto a uniform grid at the median step when the stamps jitter (linear)."""
    steps = np.diff(times)
    period = float(np.median(steps))
    if np.max(np.abs(steps - period)) <= JITTER_TOLERANCE * period:
        return (times, *arrays)
    grid = times[0] + period * np.arange(int(np.floor((times[-1] - times[0]) / period)) + 1)
    return (grid, *(np.column_stack([np.interp(grid, times, column) for column in array.T]) for array in arrays))


def load_motion_bag(path, arm, joint_topic: str | None = None, wrench_topic: str | None = None) -> MotionRecording:
    """Read a moving recording from a ROS 2 bag (extra ``bags``), resampled to a uniform grid if needed."""
    from .bags import read_bag

    recording = read_bag(path, arm, joint_topic, wrench_topic)
    times, joints, wrenches = uniform(recording.times, recording.joint_positions, recording.wrenches)
    return MotionRecording(recording.source, times, joints, wrenches)
