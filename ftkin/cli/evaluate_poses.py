"""``ftkin evaluate-poses POSES.csv``: predicted standard errors of any pose set."""

from __future__ import annotations

import numpy as np

from ..io.samples_csv import orientations_from_table, pose_ids_from_table, read_table
from ..io.time_columns import times_from_table
from ..planning.evaluation import evaluate_poses
from .common import add_arm_arguments, arm_from_args
from .plan import add_expectation_arguments, expectation_from_args


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "evaluate-poses",
        help="predict the calibration's standard errors for a pose set",
        description="Read poses (joint columns by URDF name or q1..qn [rad], alpha,beta,gamma "
        "[deg, "
        "R = Rz Ry Rx] or qw,qx,qy,qz; wrench columns not needed) and print the predicted standard "
        "error of every calibration parameter. Rows sharing a 'pose' id count as one pose (the "
        "first row).",
    )
    parser.add_argument("poses", metavar="POSES.csv")
    add_expectation_arguments(parser)
    add_arm_arguments(parser)
    parser.set_defaults(func=run)


def pose_rotations(table, args) -> np.ndarray:
    """``R_BS`` ``(N, 3, 3)`` of the table's poses, one per distinct ``pose`` id (its first row)."""
    # joint columns: the bundled arm by default
    return _first_rows(table, orientations_from_table(table, arm_from_args(args)).rotations)


def pose_times(table) -> np.ndarray | None:
    """Time [s] of each pose (its first row), from the table's time column, or None."""
    times = times_from_table(table)
    return None if times is None else _first_rows(table, times)


def _first_rows(table, values: np.ndarray) -> np.ndarray:
    """``values`` (one per table row) at the first row of each distinct ``pose`` id, if any."""
    pose_ids = pose_ids_from_table(table)
    if pose_ids is None:
        return values
    _, first_rows = np.unique(pose_ids, return_index=True)
    return values[np.sort(first_rows)]


def run(args) -> int:
    table = read_table(args.poses)
    rotations = pose_rotations(table, args)
    print(f"{args.poses}: {len(rotations)} poses")
    options = expectation_from_args(args)
    if (
        args.drift_rate is not None
        and args.pose_interval is None
        and (times := pose_times(table)) is not None
    ):
        options["pose_times"] = times  # the recording's own times (the poses as visited)
        order = np.argsort(times, kind="stable")
        rotations, options["pose_times"] = rotations[order], times[order]
        print(f"poses in the order of their time column, {times.min():g} to {times.max():g} s")
    print(evaluate_poses(rotations, **options).report())
    return 0
