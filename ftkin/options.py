"""Options declared once: a dataclass field with its unit, default, help, check and CLI spelling.

An options type of the library (``SegmentParameters``, ``ColumnSpelling``, ``CalibrationOptions``,
``PoseConstraints``, ...) declares each field with :func:`option`. The library reads the field
(its default, its check in the type's ``__post_init__``); the command line builds its flags from
the same declaration (:func:`ftkin.cli.declared.add_declared`), so that every command that takes
an option spells it, defaults it and explains it identically, and ``--help`` cannot drift from
the library.
"""

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

METADATA_KEY = "ftkin.option"


class _Unset:
    def __repr__(self) -> str:
        return "UNSET"


UNSET = _Unset()
"""A declaration's :attr:`~Declaration.cli_default` when it is the field's default."""


@dataclass(frozen=True)
class Declaration:
    """How one option reads and what it means.

    Attributes:
        help: One sentence: what the option does (no default: it is added from the field).
        unit: The unit of its value (``"m"``, ``"rad/s"``, ``"s"``; empty for none).
        flag: The command-line flag (default: ``--`` and the field name with dashes).
        metavar: The value's name in ``--help`` (a tuple for several values).
        parse: CLI text to value (an argparse ``type``); it raises
            :class:`argparse.ArgumentTypeError` with the expected range.
        choices: The allowed values, if a closed set.
        nargs: Number of values (argparse ``nargs``).
        action: An argparse action (``"store_true"``, ``"append"``).
        cli_default: The CLI's default when it differs from the field's (e.g. a list for
            ``"append"``, or None where commands resolve it each their way: the help then names
            the defaults itself); unset: the field's.
        cli: False for a field the command line builds from other flags (a noise from
            ``--noise-force`` and ``--noise-torque``).
    """

    help: str
    unit: str = ""
    flag: str | None = None
    metavar: str | tuple | None = None
    parse: Callable[[str], Any] | None = None
    choices: tuple | None = None
    nargs: int | str | None = None
    action: str | None = None
    cli_default: Any = UNSET
    cli: bool = True

    def flag_for(self, name: str) -> str:
        """The flag of the field ``name``."""
        return self.flag or "--" + name.replace("_", "-")


def option(default=dataclasses.MISSING, help: str = "", **declaration) -> Any:
    """A dataclass field declared as an option (see :class:`Declaration` for the keywords).

    ``default`` may be a callable returned by ``dataclasses.field(default_factory=...)`` style:
    pass ``default_factory=`` among the keywords instead.
    """
    factory = declaration.pop("default_factory", dataclasses.MISSING)
    metadata = {METADATA_KEY: Declaration(help, **declaration)}
    if factory is not dataclasses.MISSING:
        return dataclasses.field(default_factory=factory, metadata=metadata)
    return dataclasses.field(default=default, metadata=metadata)


def declared_options(cls) -> list[tuple[dataclasses.Field, Declaration]]:
    """The declared fields of an options dataclass, in order."""
    return [
        (field, field.metadata[METADATA_KEY])
        for field in dataclasses.fields(cls)
        if METADATA_KEY in field.metadata
    ]


def field_default(field: dataclasses.Field):
    """The default value of a dataclass field (a factory called)."""
    if field.default is not dataclasses.MISSING:
        return field.default
    if field.default_factory is not dataclasses.MISSING:
        return field.default_factory()
    return None


def number(low: float | None = None, high: float | None = None, *, above: bool = False):
    """A CLI parser of one finite number within ``[low, high]`` (``above``: ``> low``); its
    message names the range. For :attr:`Declaration.parse`."""
    import argparse
    import math

    if low is None and high is None:
        expected = "a finite number"
    elif high is None:
        expected = f"a finite number {'>' if above else '≥'} {low:g}"
    else:
        expected = f"a number in {'(' if above else '['}{low:g}, {high:g}]"

    def parse(text: str) -> float:
        try:
            value = float_text(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}") from None
        inside = math.isfinite(value) and (low is None or (value > low if above else value >= low))
        if not inside or (high is not None and value > high):
            raise argparse.ArgumentTypeError(f"expected {expected}, got {text!r}")
        return value

    return parse


def integer(low: int, high: int):
    """A CLI parser of one whole number in ``[low, high]``. For :attr:`Declaration.parse`."""
    import argparse

    def parse(text: str) -> int:
        try:
            value = int_text(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(
                f"expected a whole number in [{low}, {high}], got {text!r}"
            )
        return value

    return parse


def checked(convert, what: str = "a number"):
    """A CLI parser from a library check: ``convert(text)`` (e.g. ``check_gravity(float(text))``)
    whose :class:`~ftkin.exceptions.InvalidInput` or ``ValueError`` becomes argparse's error,
    with the library's own message. For :attr:`Declaration.parse`."""
    import argparse

    def parse(text: str):
        try:
            return convert(text)
        except ValueError as error:  # InvalidInput is a ValueError
            message = str(error)
            if "could not convert" in message or "invalid literal" in message:
                message = f"expected {what}, got {text!r}"
            raise argparse.ArgumentTypeError(message) from None

    return parse


def float_text(text: str) -> float:
    """A number written as a file or a command line writes one: ASCII digits, a sign, a point, an
    exponent (``nan``/``inf`` too, for the callers' own finiteness checks). Python's ``float``
    also reads ``"1_000"`` and other scripts' digits (``"３"``), which no logger writes: those
    raise :class:`ValueError`, as any other text."""
    if not text.isascii() or "_" in text:
        raise ValueError(f"could not convert string to float: {text!r}")
    return float(text)


def int_text(text: str) -> int:
    """A whole number in ASCII digits (see :func:`float_text`)."""
    if not text.isascii() or "_" in text:
        raise ValueError(f"invalid literal for int() with base 10: {text!r}")
    return int(text)
