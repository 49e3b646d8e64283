"""``ftkin evaluate-poses POSES.csv``: predicted standard errors of any pose set."""

from __future__ import annotations

import numpy as np

from ..csv_io import EULER_COLUMNS, POSE_COLUMN, QUATERNION_COLUMNS, check_radians, detect_orientation, read_table
from ..evaluation import evaluate_poses
from ..exceptions import InvalidSamples
from ..rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from .common import add_arm_arguments
from .plan import add_expectation_arguments, expectation_from_args, load_arm


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "evaluate-poses",
        help="predict the calibration's standard errors for a pose set",
        description="Read poses (joint columns by URDF name or q1..qn [rad], alpha,beta,gamma [deg, "
        "R = Rz Ry Rx] or qw,qx,qy,qz; wrench columns not needed) and print the predicted standard "
        "error of every calibration parameter. Rows sharing a 'pose' id count as one pose (the first row).",
    )
    parser.add_argument("poses", metavar="POSES.csv")
    add_expectation_arguments(parser)
    add_arm_arguments(parser)
    parser.set_defaults(func=run)


def pose_rotations(table, args) -> np.ndarray:
    """``R_BS`` ``(N, 3, 3)`` of the table's poses, one per distinct ``pose`` id."""
    needs_arm = not any(name in table.header for name in EULER_COLUMNS + QUATERNION_COLUMNS)
    arm = load_arm(args) if needs_arm or args.urdf or args.robot else None
    kind, columns = detect_orientation(table, arm.joint_names if arm is not None else None)
    values = table.floats(columns)
    if POSE_COLUMN in table.header:
        _, first_rows = np.unique(table.floats([POSE_COLUMN])[:, 0], return_index=True)
        values = values[np.sort(first_rows)]
    try:
        if kind == "euler":
            return euler_zyx_deg_to_matrix(values)
        if kind == "quaternion":
            return quaternion_to_matrix(values)
        check_radians(table, columns, values)
        return arm.rotation_sensor_to_base(values)
    except InvalidSamples:
        raise
    except ValueError as error:  # InvalidInput from the converters
        raise InvalidSamples(str(error), table.source) from None


def run(args) -> int:
    table = read_table(args.poses)
    rotations = pose_rotations(table, args)
    print(f"{args.poses}: {len(rotations)} poses")
    print(evaluate_poses(rotations, **expectation_from_args(args)).report())
    return 0
