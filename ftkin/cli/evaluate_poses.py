"""``ftkin evaluate-poses POSES.csv``: predicted standard errors of any pose set."""

import numpy as np

from ..io.samples_csv import orientations_from_table, pose_ids_from_table, read_table
from ..io.time_columns import times_from_table
from ..planning.evaluation import evaluate_poses
from .arg_types import add_command, option
from .common import add_arm_arguments, arm_from_args
from .plan import add_expectation_arguments, expectation_from_args


def register(subparsers) -> None:
    add_command(
        subparsers,
        "evaluate-poses",
        help="predict the calibration's standard errors for a pose set",
        description="Read poses (joint columns by URDF name or q1..qn [rad], alpha,beta,gamma "
        "[deg, "
        "R = Rz Ry Rx] or qw,qx,qy,qz; wrench columns not needed) and print the predicted standard "
        "error of every calibration parameter. Rows sharing a 'pose' id count as one pose (the "
        "first row).",
        options=(option("poses", metavar="POSES.csv"),),
        groups=(
            add_expectation_arguments,
            add_arm_arguments,
        ),
        run=run,
    )


def run(args) -> int:
    table = read_table(args.poses)
    # one row per distinct ``pose`` id (its first row); joint columns: the bundled arm by default
    pose_ids = pose_ids_from_table(table)
    rows = slice(None) if pose_ids is None else np.sort(np.unique(pose_ids, return_index=True)[1])
    rotations = orientations_from_table(table, arm_from_args(args)).rotations[rows]
    print(f"{args.poses}: {len(rotations)} poses")
    expected, pose_times = expectation_from_args(args), None
    if (
        args.drift_rate is not None
        and args.pose_interval is None
        and (times := times_from_table(table)) is not None
    ):
        times = times[rows]
        order = np.argsort(times, kind="stable")  # the recording's own times (as visited)
        rotations, pose_times = rotations[order], times[order]
        print(f"poses in the order of their time column, {times.min():g} to {times.max():g} s")
    print(evaluate_poses(rotations, expected, pose_times=pose_times).report())
    return 0
