"""``ftkin paper``: the paper's data through ftkin, beside the printed values."""

from __future__ import annotations

from ..paper import comparison_table, paper_calibration


def register(subparsers) -> None:
    parser = subparsers.add_parser("paper", help="reproduce the paper's calibration (Tables 1-3)")
    parser.add_argument("--method", default="linear", help="estimator (default: linear, the paper's)")
    parser.set_defaults(func=run)


def run(args) -> int:
    result = paper_calibration(args.method)
    print(result.summary())
    print()
    print(comparison_table(result))
    return 0
