"""The ``ftkin`` command line: a thin layer over the library.

Each subcommand lives in its own module with ``register(subparsers)``, which
adds its parser and sets ``func(args) -> int``. Errors of ftkin's own type are
printed as one line (``ftkin: error: ...``) with exit code 2.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from ..exceptions import FtkinError

COMMAND_MODULES = (
    "calibrate",
    "compensate",
    "paper",
    "demo",
    "extract",
    "export",
    "report",
    "plan",
    "evaluate-poses",
    "view",
    "simulate",
)
"""Subcommand modules of ``ftkin.cli``, in the order ``--help`` lists them."""


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered."""
    from .._version import __version__

    parser = argparse.ArgumentParser(
        prog="ftkin",
        description="Calibrate and compensate a robot's wrist force/torque sensor.",
    )
    parser.add_argument("--version", action="version", version=f"ftkin {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress and warnings")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in COMMAND_MODULES:
        importlib.import_module(f".{name.replace('-', '_')}", __name__).register(subparsers)
    return parser


def main(argv=None) -> int:
    """Run the CLI; returns the exit code (0 success, 2 bad input or usage)."""
    arguments = sys.argv[1:] if argv is None else list(argv)
    if "--version" in arguments and all(argument in ("--version", "-v", "--verbose") for argument in arguments):
        # Answered before the subcommands (and the library behind them) are imported.
        from .._version import __version__

        print(f"ftkin {__version__}")
        return 0
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="ftkin: %(message)s")
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except FtkinError as error:
        print(f"ftkin: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("ftkin: interrupted", file=sys.stderr)
        return 130


def entry_point() -> None:
    """Console-script entry (``[project.scripts] ftkin``)."""
    sys.exit(main())
