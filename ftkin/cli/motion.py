"""Moving recordings on the command line: ``calibrate --dynamic``, ``compensate`` with inertia,
``plan --excitation``.
"""

from __future__ import annotations

import argparse
import logging

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.model import WRENCH_CHANNELS
from ..io.bags import is_bag_path
from ..io.csv_table import read_table, write_csv
from ..kinematics.arm import Arm
from ..planning.constraints import PoseConstraints
from ..planning.excitation import (
    DEFAULT_ACCELERATION_LIMIT,
    DEFAULT_AMPLITUDE,
    DEFAULT_VELOCITY_FRACTION,
    plan_excitation,
)
from .arg_types import bounded_int, positive_float

logger = logging.getLogger("ftkin.cli")


def add_derivative_arguments(parser: argparse.ArgumentParser) -> None:
    """``--sg-window``: the Savitzky–Golay window of the zero-phase derivatives."""
    parser.add_argument(
        "--sg-window",
        type=bounded_int(3, 100_001, "samples"),
        default=None,
        metavar="SAMPLES",
        help="odd Savitzky–Golay window for joint velocities and accelerations (default: about 51 "
        "ms)",
    )


def load_motion(path: str, args, arm: Arm):
    """A :class:`~ftkin.io.motion_recording.MotionRecording` from a motion CSV or a bag."""
    from ..io.motion_recording import (
        load_motion_bag,
        load_motion_csv,
    )  # with the dynamic model, when used

    if is_bag_path(path):
        return load_motion_bag(
            path,
            arm,
            getattr(args, "joint_topic", None),
            getattr(args, "wrench_topic", None),
            getattr(args, "wrench_frame", "sensor"),
        )
    return load_motion_csv(path, arm)


def calibrate_motion(args, arm: Arm | None, noise: SensorNoise | None):
    """``ftkin calibrate --dynamic``: the dynamic calibration of a moving recording."""
    from ..calibration.dynamic import calibrate_dynamic

    arm = arm or Arm.default()
    recording = load_motion(args.samples, args, arm)
    motion = recording.motion_samples(arm, args.sg_window)
    return calibrate_dynamic(motion, estimate_inertia=not args.no_inertia, g=args.g, noise=noise)


def compensate_motion(args, calibration, arm: Arm | None) -> int | None:
    """``ftkin compensate`` with the inertial term, or None when the log is not a moving
    recording.
    """
    from ..control.dynamic_compensation import DynamicCompensator
    from ..io.motion_recording import is_motion_table, load_motion_bag, motion_from_table

    arm = arm or Arm.default()
    if is_bag_path(args.log):
        recording = load_motion_bag(
            args.log, arm, args.joint_topic, args.wrench_topic, args.wrench_frame
        )
        header = ["t", *arm.joint_names, *WRENCH_CHANNELS]
        source_rows = [
            [*map(float, row)]
            for row in np.column_stack(
                [recording.times, recording.joint_positions, recording.wrenches]
            )
        ]
        wrench_columns = [header.index(name) for name in WRENCH_CHANNELS]
    else:
        table = read_table(args.log)
        if not is_motion_table(table, arm):
            logger.warning(
                "%s has no 't' and joint columns: static compensation only (no inertial term)",
                args.log,
            )
            return None
        recording = motion_from_table(table, arm)
        header, source_rows = table.header, table.rows
        wrench_columns = [table.column_index(name) for name in WRENCH_CHANNELS]
    motion = recording.motion_samples(arm, args.sg_window)
    contact = DynamicCompensator(
        calibration, arm, allow_other_arm=args.allow_other_arm
    ).compensate_motion(motion)
    rows = []
    for row, wrench in zip(source_rows, contact):
        out = list(row)
        for column, value in zip(wrench_columns, wrench):
            out[column] = float(value)
        rows.append(out)
    write_csv(args.output, header, rows)
    print(
        f"wrote {len(rows)} compensated rows to {args.output} with the inertial term (zero-phase "
        "Savitzky–Golay "
        "derivatives); median contact force |F'| "
        f"{np.median(np.linalg.norm(contact[:, :3], axis=1)):.4f} N"
    )
    return 0


def add_excitation_arguments(parser: argparse.ArgumentParser) -> None:
    """``plan --excitation`` options."""
    group = parser.add_argument_group(
        "excitation trajectory (--excitation: for ftkin calibrate --dynamic)"
    )
    group.add_argument(
        "--excitation",
        action="store_true",
        help="plan a periodic Fourier-series excitation trajectory instead of poses",
    )
    for flag, default, metavar, help_text in (
        ("--duration", 30.0, "S", "recording length [s] (default: %(default)s)"),
        ("--rate", 1000.0, "HZ", "sample rate of the CSV [Hz] (default: %(default)s)"),
        ("--period", None, "S", "period of the series [s] (default: the duration)"),
    ):
        group.add_argument(
            flag, type=positive_float, default=default, metavar=metavar, help=help_text
        )
    group.add_argument(
        "--harmonics",
        type=bounded_int(1, 50, "harmonics"),
        default=5,
        metavar="K",
        help="harmonics per joint (default: %(default)s)",
    )
    for flag, default, metavar, help_text in (
        (
            "--velocity-fraction",
            DEFAULT_VELOCITY_FRACTION,
            "F",
            "fraction of the URDF velocity limits (default: %(default)s)",
        ),
        (
            "--acceleration-limit",
            DEFAULT_ACCELERATION_LIMIT,
            "RAD_S2",
            "joint acceleration limit [rad/s²] (default: %(default)s)",
        ),
        (
            "--amplitude",
            DEFAULT_AMPLITUDE,
            "RAD",
            "largest excursion of a joint from the zero configuration [rad] (default: %(default)s)",
        ),
    ):
        group.add_argument(
            flag, type=positive_float, default=default, metavar=metavar, help=help_text
        )
    group.add_argument(
        "--iterations",
        type=bounded_int(0, 100_000, "evaluations"),
        default=150,
        metavar="N",
        help="local search evaluations (default: %(default)s)",
    )


def run_excitation(args, arm: Arm) -> int:
    """``ftkin plan --excitation``: plan, print a summary, write the CSV."""
    floor = None if args.no_floor else args.floor_height
    constraints = PoseConstraints(
        args.margin, floor, None, tuple(args.joint_range), not args.no_self_collision
    )
    plan = plan_excitation(
        arm,
        args.duration,
        rate=args.rate,
        period=args.period,
        harmonics=args.harmonics,
        velocity_fraction=args.velocity_fraction,
        acceleration_limit=args.acceleration_limit,
        amplitude=args.amplitude,
        constraints=constraints,
        noise=SensorNoise(args.noise_force, args.noise_torque),
        max_iterations=args.iterations,
        seed=args.seed,
    )
    print(
        f"excitation: {len(plan.times)} samples at {args.rate:g} Hz over {args.duration:g} s, "
        f"period {plan.trajectory.period:g} s, "
        f"{plan.trajectory.cosine.shape[1]} harmonics; {constraints.describe()}"
    )
    print(
        f"  information: log det {plan.log_det:.2f}, condition number {plan.condition_number:.3g}"
    )
    print(
        "  peak joint speed [rad/s]: "
        + ", ".join(f"{v:.2f}" for v in np.abs(plan.joint_velocities).max(axis=0))
    )
    print(
        "  peak joint acceleration [rad/s²]: "
        + ", ".join(f"{v:.2f}" for v in np.abs(plan.joint_accelerations).max(axis=0))
    )
    if args.output:
        header, rows = plan.table()
        write_csv(args.output, header, [[*map(float, row)] for row in rows])
        print(f"wrote {args.output}")
    return 0
