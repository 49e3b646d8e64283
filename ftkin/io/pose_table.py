"""A pose set read from a table (``ftkin evaluate-poses POSES.csv``): one sensor orientation per
distinct ``pose`` id, in the order the poses were visited.

The orientation columns are any a samples CSV takes (joint columns [rad] through an arm, Euler
angles [deg], quaternions; :func:`~ftkin.io.samples_csv.orientations_from_table`); wrench
columns are not needed. Rows sharing a ``pose`` id are one pose, its first row. With a time
column (:func:`~ftkin.io.time_columns.times_from_table`) the poses are put in the order of their
times [s] (stable: ties keep the file's order), the order a drifting bias met them in.
"""

from dataclasses import dataclass

import numpy as np

from .csv_table import Table
from .samples_csv import orientations_from_table, pose_ids_from_table
from .time_columns import times_from_table


@dataclass(frozen=True)
class PoseSet:
    """Poses to evaluate, in visiting order.

    Attributes:
        rotations: ``(P, 3, 3)`` sensor orientations ``R_BS``.
        times: ``(P,)`` time of each pose [s] (its first row's), ascending; None without a time
            column.
    """

    rotations: np.ndarray
    times: np.ndarray | None


def pose_set_from_table(table: Table, arm=None) -> PoseSet:
    """The poses of ``table``: one per distinct ``pose`` id (its first row; every row without a
    pose column), in the order of the time column when there is one.

    ``arm``: forward kinematics for joint columns (None: the bundled arm).

    Raises:
        InvalidSamples: no usable orientation columns, a malformed pose id or time column.
    """
    pose_ids = pose_ids_from_table(table)
    rows = (
        np.arange(len(table.rows))
        if pose_ids is None
        else np.sort(np.unique(pose_ids, return_index=True)[1])
    )
    rotations = orientations_from_table(table, arm).rotations[rows]
    times = times_from_table(table)
    if times is None:
        return PoseSet(rotations, None)
    times = times[rows]
    order = np.argsort(times, kind="stable")
    return PoseSet(rotations[order], times[order])
