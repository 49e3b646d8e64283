"""``ftkin compensate CALIB.json LOG.csv -o OUT.csv``."""

from __future__ import annotations

import numpy as np

from ..calibration.model import WRENCH_CHANNELS
from ..control.compensation import Compensator
from ..exceptions import InvalidInput
from ..io.calibration_file import load_calibration
from ..io.csv_table import write_csv
from .common import (
    add_samples_arguments,
    arm_for_calibration,
    load_samples_from_args,
    warn_if_kinematics_differ,
)
from .motion import add_derivative_arguments, compensate_motion


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "compensate",
        help="remove bias and tool gravity from a log of raw readings",
        description="Write the contact wrench (fx..mz, sensor frame, N and N·m) of every row of "
        "LOG.csv, "
        "keeping its other columns. LOG.csv has the same columns as a calibration samples file. "
        "With a 't' "
        "column [s] and a drifting calibration, rows inside the calibration's recording use the "
        "bias at their "
        "time, later rows the calibration's last bias. When the calibration has an inertia "
        "(calibrate --dynamic) "
        "and the log has a time column t and joint columns, the tool's inertial wrench is removed "
        "too (joint "
        "derivatives from the log, zero-phase).",
    )
    parser.add_argument("calibration", metavar="CALIB.json")
    parser.add_argument("log", metavar="LOG.csv")
    parser.add_argument("-o", "--output", metavar="OUT.csv", required=True)
    add_derivative_arguments(parser)
    parser.add_argument(
        "--allow-other-arm",
        action="store_true",
        help="accept robot options that differ from the arm recorded in the calibration "
        "(deliberate reuse)",
    )
    add_samples_arguments(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    arm = arm_for_calibration(args, calibration)
    compensator = Compensator(
        calibration, arm, allow_other_arm=args.allow_other_arm
    )  # checks arm against the record
    if calibration.has_inertia:
        done = compensate_motion(args, calibration, arm)
        if done is not None:
            return done
    elif args.sg_window is not None:
        raise InvalidInput(
            "--sg-window applies to a calibration with an inertia (ftkin calibrate --dynamic)"
        )
    loaded = load_samples_from_args(args.log, args, static_only=False, arm=arm)
    warn_if_kinematics_differ(loaded, calibration)
    contact = compensator.compensate_samples(loaded.samples)
    table = loaded.table
    wrench_columns = [table.column_index(name) for name in WRENCH_CHANNELS]
    rows = []
    for row, wrench in zip(table.rows, contact):
        out = list(row)
        for column, value in zip(wrench_columns, wrench):
            out[column] = float(value)
        rows.append(out)
    write_csv(args.output, table.header, rows)
    weights = Compensator.payload_weight(contact)
    print(
        f"wrote {len(rows)} compensated rows to {args.output} (median contact force |F'| "
        f"{np.median(weights):.4f} N)"
    )
    drift = calibration.drift
    if loaded.samples.times is not None and drift is not None and drift.model != "none":
        inside = int(np.sum(drift.covers(loaded.samples.times)))
        print(
            f"bias drift {drift.model}: {inside} rows inside the calibration recording used the "
            "bias at their time, "
            f"{len(rows) - inside} the last bias"
        )
    return 0
