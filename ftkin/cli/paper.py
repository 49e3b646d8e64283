"""``ftkin paper``: the paper's data through ftkin, beside the printed values."""

from ..io.atomic import atomic_write_bytes
from ..sim.paper import comparison_table, paper_calibration, paper_csv_path
from .arg_types import add_command, option
from .shared_options import METHOD, resolved


def register(subparsers) -> None:
    add_command(
        subparsers,
        "paper",
        help="reproduce the paper's calibration (Tables 1-3)",
        options=(
            METHOD,
            option(
                "--no-ml",
                dest="show_ml",
                action="store_false",
                help="do not also print the ml fit with standard errors after the linear one",
            ),
            option(
                "-o",
                "--output",
                metavar="SAMPLES.csv",
                help="also write the paper's 9 poses (Tables 1-2) as a samples CSV, for ftkin "
                "calibrate",
            ),
        ),
        run=run,
    )


def run(args) -> int:
    args.method = resolved(args.method, "linear")  # the paper's own estimator
    result = paper_calibration(args.method)
    print(result.summary())
    print(f"\n{comparison_table(result)}")
    if args.method == "linear" and args.show_ml:
        print(
            "\nThe same data through the maximum-likelihood fit (ftkin's default), value ± "
            "standard error:"
        )
        print(paper_calibration("ml").summary())
    if args.output:
        atomic_write_bytes(args.output, paper_csv_path().read_bytes())
        print(f"wrote {args.output}")
    return 0
