"""argparse value types: numbers with their range and unit in the message, the number-list
options, and the subcommands' parsers as tables of :func:`option` rows (:func:`add_command`).

Each converter raises :class:`argparse.ArgumentTypeError`, which the CLI reports as
``ftkin <command>: error: argument --x: ...`` (exit 2), never a traceback.
"""

import argparse

from ..calibration.model import check_gravity
from ..options import float_text, int_text


def option(*flags: str, **keywords) -> tuple:
    """One row of :func:`add_options`: the arguments of ``add_argument``."""
    return flags, keywords


def add_options(parser, *options: tuple) -> None:
    """Add each :func:`option` row to ``parser`` (or an argument group)."""
    for flags, keywords in options:
        parser.add_argument(*flags, **keywords)


def add_command(subparsers, name: str, *, run, options=(), groups=(), **keywords):
    """Add the subcommand ``name`` that calls ``run(args) -> int``; ``keywords`` (help,
    description) go to ``add_parser``. Its :func:`option` rows come first, then each shared group
    ``add(parser)`` of ``groups`` (e.g. :func:`~ftkin.cli.common.add_arm_arguments`).

    Returns the parser, for a command that adds argument groups of its own.
    """
    parser = subparsers.add_parser(name, **keywords)
    add_options(parser, *options)
    for add in groups:
        add(parser)
    parser.set_defaults(func=run)
    return parser


def refuse(error: type[Exception], *checks: tuple) -> None:
    """Raise ``error(message)`` for the first ``(refused, message)`` of ``checks`` that is refused.

    Every check is evaluated up front: each condition and message must be safe to compute
    whatever the input (the order says which is reported when several apply).
    """
    for refused, message in checks:
        if refused:
            raise error(message)


def _number(text: str, accept, expected: str) -> float:
    try:
        value = float_text(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
    if not (accept(value) and abs(value) != float("inf")):
        raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
    return value


NUMBER_LIST_OPTIONS = ("--sensor-offset", "--mount-rpy-deg", "--com", "--imu-position")
"""Options that take several numbers; their values end at the first token that is not a number."""


def _is_number(token: str) -> bool:
    try:
        float_text(token)
    except ValueError:
        return False
    return True


def join_number_lists(argv: list[str]) -> list[str]:
    """``--sensor-offset 0 0 0.05 LOG.csv`` → ``--sensor-offset=0,0,0.05 LOG.csv``.

    A list option takes the numbers that follow it (at most 6) and no more, so
    it never swallows the positional file after it; negative numbers work.
    """
    out, listed, values = [], None, []  # the list option being read and its numbers so far
    for token in argv:
        if listed and len(values) < 6 and _is_number(token):
            values.append(token)
            out[-1] = f"{listed}={','.join(values)}"
        else:
            listed, values = (token if token in NUMBER_LIST_OPTIONS else None), []
            out.append(token)
    return out


def number_list(text: str) -> list[float]:
    """argparse type: finite numbers separated by commas (or spaces)."""
    parts = [part for part in text.replace(",", " ").split()]
    if not parts:
        raise argparse.ArgumentTypeError("expected numbers, got nothing")
    return [_number(part, lambda value: value == value, "a finite number") for part in parts]


def whole_number(text: str, what: str = "") -> int:
    """``text`` as an int, or :class:`argparse.ArgumentTypeError` naming ``what`` (e.g. "poses")."""
    try:
        return int_text(text)
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected a whole number{' of ' + what if what else ''}, got {text!r}"
        ) from None


def bounded_int(low: int, high: int, what: str):
    """argparse type factory: a whole number in ``[low, high]``, the message naming ``what``."""

    def convert(text: str) -> int:
        value = whole_number(text, what)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"expected {low} to {high:,} {what}, got {text}")
        return value

    return convert


def seed(text: str) -> int:
    """argparse type: a random seed, 0 to 2**63 - 1."""
    value = whole_number(text)
    refuse(
        argparse.ArgumentTypeError,
        (value < 0, f"the seed must be at least 0, got {text}"),
        (value >= 2**63, f"the seed must be below 2**63, got {text}"),
    )
    return value


def gravity(text: str) -> float:
    """argparse type: gravity [m/s²] by :func:`~ftkin.calibration.model.check_gravity` (1 to 30;
    Earth: 9.81; the Moon 1.6, Jupiter 24.8)."""
    from ..exceptions import InvalidInput

    value = _number(text, lambda v: True, "a finite number")
    try:
        return check_gravity(value)
    except InvalidInput as error:
        raise argparse.ArgumentTypeError(f"{error} (Earth: 9.80665)") from None


def finite_float(text: str) -> float:
    """argparse type: a finite number (``nan`` and ``inf`` are refused)."""
    return _number(text, lambda value: value == value, "a finite number")


def floor_height(text: str) -> float:
    """argparse type: a floor height within ±100 m [m, base z]."""
    return _number(text, lambda value: abs(value) <= 100.0, "a finite height within ±100 m")


def positive_float(text: str) -> float:
    """argparse type: a finite positive number."""
    return _number(text, lambda value: value > 0, "a finite positive number")


def non_negative_float(text: str) -> float:
    """argparse type: a finite number ≥ 0."""
    return _number(text, lambda value: value >= 0, "a finite number ≥ 0")
