"""``ftkin report CALIB.json SAMPLES -o report.png``: measured vs predicted per pose, residuals."""

from ..io.calibration_file import load_calibration
from ..viz.report import save_report
from .arg_types import add_command, option
from .common import (
    add_samples_arguments,
    arm_for_calibration,
    load_samples_from_args,
)


def register(subparsers) -> None:
    add_command(
        subparsers,
        "report",
        help="plot measured vs predicted wrench per pose and the residuals (needs ftkin[plots])",
        description="Draw a one-page report (PNG, PDF or SVG): per channel fx..mz the per-pose "
        "mean "
        "measured reading (± standard error) against the calibration's prediction, the residuals, "
        "and "
        "the parameters with standard errors when the calibration has them. SAMPLES is a samples "
        "CSV or "
        "a ROS 2 bag (same options as 'ftkin calibrate'; without --robot/--urdf the URDF recorded "
        "in the "
        "calibration file is used).",
        options=(
            option("calibration", metavar="CALIB.json"),
            option("samples", metavar="SAMPLES"),
            option("-o", "--output", required=True, metavar="report.png"),
            option("--title", help="figure title"),
        ),
        groups=(add_samples_arguments,),
        run=run,
    )


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    loaded = load_samples_from_args(args.samples, args, arm=arm_for_calibration(args, calibration))
    save_report(calibration, loaded.samples, args.output, args.title)
    print(f"wrote report of {len(set(loaded.samples.pose_ids.tolist()))} poses to {args.output}")
    return 0
