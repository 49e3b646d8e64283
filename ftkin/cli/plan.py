"""``ftkin plan --n 12 -o poses.csv``: plan calibration poses for an arm (``--excitation``: a
trajectory for ``calibrate --dynamic``).
"""

import argparse

import numpy as np

from .. import Arm, InvalidInput, PlanSpec, SensorNoise, UrdfError, plan_poses
from ..io.csv_table import write_csv
from ..io.plan_file import PLAN_FORMATS, write_plan
from ..planning.drift_order import DEFAULT_POSE_INTERVAL
from ..planning.evaluation import PAPER_CENTER_OF_MASS, PAPER_TOOL_WEIGHT, ExpectedCalibration
from ..planning.excitation import (
    DEFAULT_ACCELERATION_LIMIT,
    DEFAULT_AMPLITUDE,
    DEFAULT_VELOCITY_FRACTION,
    plan_excitation,
)
from .arg_types import (
    add_command,
    add_options,
    bounded_int,
    finite_float,
    option,
    positive_float,
    refuse,
)
from .common import add_arm_arguments, arm_from_args
from .pose_options import add_constraint_arguments, add_readings_argument, constraints_from_args
from .shared_options import (
    CENTER_OF_MASS,
    DURATION,
    ESTIMATE_MOUNT,
    NOISE_FORCE,
    NOISE_TORQUE,
    POSES,
    SEED,
    noise_from_args,
    resolved,
)

# The expected tool and sensor noise (defaults: the paper's).
_TOOL_OPTIONS = (
    option(
        "--tool-weight",
        type=positive_float,
        default=PAPER_TOOL_WEIGHT,
        metavar="N",
        help="tool weight [N] (default: %(default)s)",
    ),
    CENTER_OF_MASS,
    NOISE_FORCE,
    NOISE_TORQUE,
)


def add_expectation_arguments(parser: argparse.ArgumentParser) -> None:
    """Expected tool, sensor noise and estimation the predicted standard errors are for."""
    group = parser.add_argument_group("expected tool and sensor noise (defaults: the paper's)")
    add_options(group, *_TOOL_OPTIONS)
    add_readings_argument(group)
    add_options(
        parser.add_argument_group("what the calibration will estimate"),
        ESTIMATE_MOUNT,
        option(
            "--drift-rate",
            type=finite_float,
            nargs=2,
            default=None,
            metavar=("N/√s", "NM/√s"),
            help="the bias drifts as a random walk of these rates (force, torque; e.g. a past "
            "calibration's drift rate): visit the poses in the order the drift spoils least "
            "(longer joint travel) and predict errors with the drift",
        ),
        option(
            "--pose-interval",
            type=positive_float,
            default=None,
            metavar="S",
            help="time from one pose to the next [s], with --drift-rate (default: "
            f"{DEFAULT_POSE_INTERVAL:g})",
        ),
    )


def expected_noise(args) -> SensorNoise:
    """The noise a prediction assumes: ``--noise-force``/``--noise-torque``, else the paper's."""
    return noise_from_args(args, SensorNoise.paper())


def expectation_from_args(args) -> ExpectedCalibration:
    """The calibration :func:`ftkin.planning.plan_poses` and
    :func:`ftkin.planning.evaluation.evaluate_poses` predict for.
    """
    return ExpectedCalibration(  # it checks them (--com's length, --pose-interval's --drift-rate)
        tool_weight=args.tool_weight,
        center_of_mass=resolved(args.com, PAPER_CENTER_OF_MASS),
        noise=expected_noise(args),
        readings_per_pose=args.readings_per_pose,
        estimate_mount=args.estimate_mount or "none",
        drift_rate=args.drift_rate,
        pose_interval=args.pose_interval,
    )


# plan --excitation: the trajectory for ftkin calibrate --dynamic.
_EXCITATION_OPTIONS = (
    option(
        "--excitation",
        action="store_true",
        help="plan a periodic Fourier-series excitation trajectory instead of poses",
    ),
    DURATION,
    option(
        "--rate",
        type=positive_float,
        default=1000.0,
        metavar="HZ",
        help="sample rate of the CSV [Hz] (default: %(default)s)",
    ),
    option(
        "--period",
        type=positive_float,
        default=None,
        metavar="S",
        help="period of the series [s] (default: the duration)",
    ),
    option(
        "--harmonics",
        type=bounded_int(1, 50, "harmonics"),
        default=5,
        metavar="K",
        help="harmonics per joint (default: %(default)s)",
    ),
    option(
        "--velocity-fraction",
        type=positive_float,
        default=DEFAULT_VELOCITY_FRACTION,
        metavar="F",
        help="fraction of the URDF velocity limits (default: %(default)s)",
    ),
    option(
        "--acceleration-limit",
        type=positive_float,
        default=DEFAULT_ACCELERATION_LIMIT,
        metavar="RAD_S2",
        help="joint acceleration limit [rad/s²] (default: %(default)s)",
    ),
    option(
        "--amplitude",
        type=positive_float,
        default=DEFAULT_AMPLITUDE,
        metavar="RAD",
        help="largest excursion of a joint from the zero configuration [rad] (default: "
        "%(default)s)",
    ),
    option(
        "--iterations",
        type=bounded_int(0, 100_000, "evaluations"),
        default=150,
        metavar="N",
        help="local search evaluations (default: %(default)s)",
    ),
)


def register(subparsers) -> None:
    parser = add_command(
        subparsers,
        "plan",
        help="plan calibration poses (joint configurations) for the most accurate calibration",
        description="Choose N joint configurations (D-optimal: largest log det of the Fisher "
        "information) within joint limits, free of self-collision and above the floor, ordered "
        "for short joint travel; print the predicted standard error of every calibration "
        "parameter.",
        options=(
            option("-n", *POSES[0], **POSES[1]),  # -n: the short spelling plan has always had
            option("-o", "--output", metavar="POSES.csv", help="write the poses here"),
            option(
                "--format",
                choices=tuple(PLAN_FORMATS),
                default=None,
                help="output format (default: from the file name, else csv)",
            ),
        ),
        run=run,
    )
    add_constraint_arguments(parser)
    add_options(
        parser,
        SEED,
        option(
            "--max-travel-ratio",
            type=positive_float,
            default=None,
            metavar="R",
            help="with --drift-rate: keep the joint travel within R (≥ 1) times the short-travel "
            "order's (default: unbounded, about 2x)",
        ),
    )
    add_expectation_arguments(parser)
    add_options(
        parser.add_argument_group(
            "excitation trajectory (--excitation: for ftkin calibrate --dynamic)"
        ),
        *_EXCITATION_OPTIONS,
    )
    add_arm_arguments(parser)


def load_arm(args) -> Arm:
    """The arm named on the command line (the bundled arm by default)."""
    return arm_from_args(args) or Arm.default()


def run(args) -> int:
    refuse(
        InvalidInput,
        (
            args.format is not None and not args.output,
            f"--format {args.format} needs -o/--output FILE (the plan is printed as a table "
            "otherwise)",
        ),
        (
            args.excitation
            and (
                args.n is not None
                or args.max_tilt is not None
                or args.format not in (None, "csv")
                or args.drift_rate is not None
                or args.pose_interval is not None
                or args.max_travel_ratio is not None
            ),
            "--excitation plans a trajectory: --n, --max-tilt-deg, --format yaml/json, "
            "--drift-rate, --pose-interval and --max-travel-ratio do not apply",
        ),
        (
            not args.excitation and args.n is None,
            "give --n N (the number of poses), or --excitation for a trajectory",
        ),
    )
    if args.excitation:
        return _run_excitation(args, load_arm(args))
    spec = PlanSpec(
        args.n,
        constraints=constraints_from_args(args),
        expected=expectation_from_args(args),
        seed=args.seed,
        max_travel_ratio=args.max_travel_ratio,
    )
    arm = load_arm(args)
    try:
        plan = plan_poses(arm, spec)
    except UrdfError as error:  # only the collision geometry is loaded here: meshes not found
        raise UrdfError(error.path, [*error.reasons, "or plan with --no-self-collision"]) from None
    print(plan.report(), plan.pose_table(), sep="\n")
    if args.output:
        print(f"wrote {args.output} ({write_plan(plan, args.output, args.format)})")
    return 0


def _run_excitation(args, arm: Arm) -> int:
    """``ftkin plan --excitation``: plan, print a summary, write the CSV."""
    constraints = constraints_from_args(args)
    duration = resolved(args.duration, 30.0)
    plan = plan_excitation(
        arm,
        duration,
        rate=args.rate,
        period=args.period,
        harmonics=args.harmonics,
        velocity_fraction=args.velocity_fraction,
        acceleration_limit=args.acceleration_limit,
        amplitude=args.amplitude,
        constraints=constraints,
        noise=expected_noise(args),
        max_iterations=args.iterations,
        seed=args.seed,
    )
    peak_speed, peak_acceleration = (
        ", ".join(f"{v:.2f}" for v in np.abs(values).max(axis=0))
        for values in (plan.joint_velocities, plan.joint_accelerations)
    )
    print(
        f"excitation: {len(plan.times)} samples at {args.rate:g} Hz over {duration:g} s, "
        f"period {plan.trajectory.period:g} s, "
        f"{plan.trajectory.cosine.shape[1]} harmonics; {constraints.describe()}\n"
        f"  information: log det {plan.log_det:.2f}, condition number {plan.condition_number:.3g}\n"
        f"  peak joint speed [rad/s]: {peak_speed}\n"
        f"  peak joint acceleration [rad/s²]: {peak_acceleration}"
    )
    if args.output:
        header, rows = plan.table()
        write_csv(args.output, header, [[*map(float, row)] for row in rows])
        print(f"wrote {args.output}")
    return 0
