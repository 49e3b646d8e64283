"""Moving recordings: time, joint positions and raw wrenches, from a CSV or a ROS 2 bag.

A motion CSV has a time column ``t`` [s] (uniformly sampled), the joint
columns of the samples CSV (the URDF's joint names or ``q1..qn`` [rad]) and
the wrench columns ``fx..mz`` [N, N·m] (see :mod:`ftkin.io.samples_csv`),
and optionally the joint velocities and accelerations the recording already
has (a simulator's): ``dq1..dqn`` and ``ddq1..ddqn`` [rad/s, rad/s²], or
``<joint>_vel`` and ``<joint>_acc`` (what ``ftkin plan --excitation`` writes), or
``<joint>_velocity`` and ``<joint>_acceleration``; given, they are used as they
are instead of differentiating the positions, once checked against the
positions' time derivatives (:func:`given_derivatives`). Other columns are
carried along. A bag is read with
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

import logging
from dataclasses import dataclass

import numpy as np

from ..calibration.derivatives import DEFAULT_POLYORDER, joint_derivatives
from ..calibration.model import WRENCH_CHANNELS
from ..calibration.regressor import MotionSamples
from ..exceptions import InvalidInput, InvalidSamples
from .column_spelling import ColumnSpelling, spelled_table
from .csv_table import Table, missing_columns, read_table
from .samples_csv import check_radians, check_wrench_magnitude, detect_orientation
from .time_columns import TIME_COLUMN, times_from_table

logger = logging.getLogger(__name__)

JITTER_TOLERANCE = 1e-3
"""Largest deviation of a bag's time step from the median step [fraction] accepted without
resampling.
"""


@dataclass(frozen=True)
class MotionRecording:
    """Uniformly sampled joint positions and raw readings.

    Attributes:
        source: File or bag the data came from.
        times: ``(N,)`` [s], uniform.
        joint_positions: ``(N, nq)`` [rad], in the arm's joint order.
        wrenches: ``(N, 6)`` raw readings, sensor frame [N, N·m].
        table: The CSV table (for copying other columns), or None for a bag.
        joint_velocities: ``(N, nq)`` [rad/s] given by the recording, or None.
        joint_accelerations: ``(N, nq)`` [rad/s²] given by the recording, or None.
    """

    source: str
    times: np.ndarray
    joint_positions: np.ndarray
    wrenches: np.ndarray
    table: Table | None = None
    joint_velocities: np.ndarray | None = None
    joint_accelerations: np.ndarray | None = None

    def motion_samples(
        self, arm, window: int | None = None, polyorder: int = DEFAULT_POLYORDER
    ) -> MotionSamples:
        """Zero-phase ``q, dq, ddq`` and the sensor frame's motion (:class:`MotionSamples`).

        With velocities and accelerations given by the recording, those are
        used with the positions as they are (``window`` and ``polyorder`` do
        not apply).

        Raises:
            InvalidSamples: the times are not uniform or too few for the window.
        """
        q, dq, ddq = self.joint_positions, self.joint_velocities, self.joint_accelerations
        if dq is None or ddq is None:
            try:
                q, dq, ddq = joint_derivatives(self.times, q, window, polyorder)
            except InvalidInput as error:
                raise InvalidSamples(str(error), self.source) from None
        return MotionSamples.from_joint_trajectory(arm, q, dq, ddq, self.wrenches, self.times)


def is_motion_table(table: Table, arm) -> bool:
    """True when the table has a ``t`` column and joint columns (a moving recording)."""
    try:
        has_times = times_from_table(table) is not None
        return has_times and detect_orientation(table, arm.joint_names)[0] == "joints"
    except InvalidSamples:
        return False


def motion_from_table(table: Table, arm, spelling: ColumnSpelling | None = None) -> MotionRecording:
    """A :class:`MotionRecording` from a parsed motion CSV.

    Raises:
        InvalidSamples: missing ``t``, joint or wrench columns, joint angles in
            degrees, fewer than 3 rows, or times not increasing (with file and line).
    """
    # ROS names (force.x, ...) as for static samples
    table = spelled_table(table, spelling)
    times = times_from_table(table)
    if times is None:
        missing_columns(table, (TIME_COLUMN,), "time")
    missing_columns(table, WRENCH_CHANNELS, "wrench")
    kind, columns = detect_orientation(table, arm.joint_names)
    if kind != "joints":
        raise InvalidSamples(
            f"a moving recording needs joint columns (the arm's {arm.joint_names} or "
            f"q1..q{arm.nq}), found {kind} columns",
            table.source,
        )
    joints = table.floats(columns)
    check_radians(table, columns, joints, arm)
    if len(times) < 3:
        raise InvalidSamples(
            f"{len(times)} row(s); a moving recording needs at least 3 (its derivatives)",
            table.source,
        )
    stalled = np.flatnonzero(np.diff(times) <= 0)
    if stalled.size:
        row = int(stalled[0]) + 1
        raise InvalidSamples(
            f"time stamps do not increase: t = {times[row]:.9g} s after {times[row - 1]:.9g} s; "
            "expected strictly increasing stamps (rows out of order or repeated; sort the file "
            "or fix its clock)",
            table.source,
            table.lines[row],
        )
    velocities, accelerations = given_derivatives(table, columns, times, joints)
    wrenches = table.floats(WRENCH_CHANNELS)
    check_wrench_magnitude(table, wrenches)
    return MotionRecording(table.source, times, joints, wrenches, table, velocities, accelerations)


DERIVATIVE_TOLERANCE = 0.2
"""Largest RMS disagreement, as a fraction of their RMS, between given velocities (accelerations)
and the
finite-difference derivative of the positions (velocities)."""


def _derivative_columns(table: Table, columns: list[str], kind: str) -> list[str] | None:
    prefix, suffixes = (
        ("dq", ("_vel", "_velocity")) if kind == "velocity" else ("ddq", ("_acc", "_acceleration"))
    )
    for names in (
        [f"{prefix}{i + 1}" for i in range(len(columns))],
        *([f"{c}{suffix}" for c in columns] for suffix in suffixes),
    ):
        present = [name in table.header for name in names]
        if all(present):
            return names
        if any(present):
            missing = [name for name, here in zip(names, present) if not here]
            raise InvalidSamples(
                f"joint {kind} columns {missing} are missing (the others are given); give all "
                f"{len(columns)} or none",
                table.source,
            )
    return None


def given_derivatives(table: Table, columns: list[str], times: np.ndarray, joints: np.ndarray):
    """The recording's own joint velocities and accelerations ``(N, nq)`` [rad/s, rad/s²], or
    ``(None, None)``.

    Both are needed (one alone is ignored with a warning), and each must agree
    with the time derivative (central differences) of the one below it within
    :data:`DERIVATIVE_TOLERANCE` of its RMS: degrees per second, another joint
    order or a sign would not.
    """
    velocity_names = _derivative_columns(table, columns, "velocity")
    acceleration_names = _derivative_columns(table, columns, "acceleration")
    if velocity_names is None or acceleration_names is None:
        if velocity_names is not None or acceleration_names is not None:
            logger.warning(
                "%s: joint velocities or accelerations given without the other; both are taken "
                "from "
                "the positions instead",
                table.source,
            )
        return None, None
    velocities, accelerations = table.floats(velocity_names), table.floats(acceleration_names)
    for given, below, names, unit in (
        (velocities, joints, velocity_names, "rad/s"),
        (accelerations, velocities, acceleration_names, "rad/s²"),
    ):
        derivative = np.gradient(below, times, axis=0)
        scale = float(np.sqrt(np.mean(derivative**2)))
        mismatch = float(np.sqrt(np.mean((given - derivative) ** 2)))
        if mismatch > DERIVATIVE_TOLERANCE * scale + 1e-9:
            raise InvalidSamples(
                f"columns {names[0]}..{names[-1]} disagree with the time derivative of the columns "
                "before them "
                f"(RMS difference {mismatch:.3g} against RMS {scale:.3g} {unit}): expected {unit} "
                "in the joint order "
                "(degrees? another order?); drop them to differentiate the positions",
                table.source,
            )
    return velocities, accelerations


def load_motion_csv(path, arm, spelling: ColumnSpelling | None = None) -> MotionRecording:
    """Read a motion CSV (see the module docstring; ``spelling``: other names and units)."""
    return motion_from_table(read_table(path), arm, spelling)


def uniform(times: np.ndarray, *arrays: np.ndarray) -> tuple[np.ndarray, ...]:
    """Resample ``arrays`` ``(N, k)`` onto a uniform grid at the median step when the stamps jitter
    (linear).
    """
    steps = np.diff(times)
    period = float(np.median(steps))
    if np.max(np.abs(steps - period)) <= JITTER_TOLERANCE * period:
        return (times, *arrays)
    grid = times[0] + period * np.arange(int(np.floor((times[-1] - times[0]) / period)) + 1)
    return (
        grid,
        *(
            np.column_stack([np.interp(grid, times, column) for column in array.T])
            for array in arrays
        ),
    )


def load_motion_bag(
    path,
    arm,
    joint_topic: str | None = None,
    wrench_topic: str | None = None,
    wrench_frame: str = "sensor",
) -> MotionRecording:
    """Read a moving recording from a ROS 2 bag (extra ``bags``), resampled to a uniform grid if
    needed.

    ``wrench_frame``: ``"sensor"`` or ``"base"``, as for static bags
    (:func:`~ftkin.io.wrench_frames.wrenches_in_sensor_frame`; the frame_id is checked the same
    way).
    """
    from .bags import read_bag
    from .wrench_frames import wrenches_in_sensor_frame

    recording = read_bag(path, arm, joint_topic, wrench_topic)
    wrenches = wrenches_in_sensor_frame(
        recording.wrenches,
        arm.rotation_sensor_to_base(recording.joint_positions),
        recording.wrench_frame_id,
        arm,
        wrench_frame,
        recording.source,
    )
    times, joints, wrenches = uniform(recording.times, recording.joint_positions, wrenches)
    return MotionRecording(recording.source, times, joints, wrenches)
