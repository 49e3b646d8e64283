"""``ftkin evaluate-poses POSES.csv``: predicted standard errors of any pose set."""

from ..io.pose_table import pose_set_from_table
from ..io.samples_csv import read_table
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
    poses = pose_set_from_table(read_table(args.poses), arm_from_args(args))
    print(f"{args.poses}: {len(poses.rotations)} poses")
    expected = expectation_from_args(args)
    # a drift meets the poses at their times, unless --pose-interval says when
    timed = (
        poses.times is not None and expected.drift_rate is not None and args.pose_interval is None
    )
    if timed:
        print(
            f"poses in the order of their time column, {poses.times[0]:g} to {poses.times[-1]:g} s"
        )
    pose_times = poses.times if timed else None
    print(evaluate_poses(poses.rotations, expected, pose_times=pose_times).report())
    return 0
