"""``ftkin doctor SAMPLES.csv [robot options]``: which convention the data fit, on demand."""

from ..io.column_spelling import declared_wrench_units, spelled_table
from ..io.csv_table import read_table
from ..io.table_readings import check_sample_conventions, diagnose_table
from .arg_types import add_command, option
from .common import (
    add_arm_arguments,
    add_column_arguments,
    arm_from_args,
    column_spelling_from_args,
)


def register(subparsers) -> None:
    add_command(
        subparsers,
        "doctor",
        help="check a samples CSV for convention mistakes (radians for degrees, quaternion order, "
        "frame, units, signs)",
        description="Fit the samples as given and under each common mistake: Euler angles in "
        "radians, a quaternion "
        "stored x,y,z,w, the wrench in the base frame, the reaction instead of the load, one "
        "sensor axis reversed, "
        "joint angles in degrees, torques in N·mm, force and torque columns swapped or "
        "interleaved, a tool weight tilted from base -z; print the fit of each and name the "
        "reading that "
        "explains the data. "
        "Exit code 0 when the data fit as given (or only a suspicion), 1 when a mistake is named.",
        options=(option("samples", metavar="SAMPLES.csv"),),
        groups=(add_arm_arguments, add_column_arguments),
        run=run,
    )


def run(args) -> int:
    raw, spelling = read_table(args.samples), column_spelling_from_args(args)
    table = spelled_table(raw, spelling)
    report = diagnose_table(table, arm_from_args(args), declared_wrench_units(raw.header, spelling))
    print(
        f"{args.samples}: {len(table.rows)} readings; linear fit under each reading (chi² with the "
        "noise of the best):",
        report.table(),
        sep="\n",
    )
    detail = report.reason if report.verdict in ("ok", "undetermined") else report.message
    print(f"verdict: {report.verdict}: {detail}")
    return 1 if report.verdict == "mistake" else 0


def refuse_convention_mistakes(loaded, arm, declared_units: dict | None = None) -> None:
    """``calibrate``'s check of a samples file (bags carry their own conventions): the library's
    :func:`~ftkin.io.table_readings.check_sample_conventions`, so the API refuses the same file
    with the same words. ``declared_units``: the units the files' headers declare
    (:func:`~ftkin.io.column_spelling.declared_wrench_units`; ``loaded.table`` is already in SI).
    """
    if loaded.recording is None:
        check_sample_conventions(loaded.table, arm, declared_units)
