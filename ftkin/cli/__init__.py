"""The ``ftkin`` command line: a thin layer over the library.

Each subcommand lives in its own module with ``register(subparsers)``, which
adds its parser and sets ``func(args) -> int``. Errors of ftkin's own type are
printed as one line (``ftkin: error: ...``) with exit code 2.
"""

import argparse
import contextlib
import importlib
import logging
import os
import shlex
import sys

from .._lazy import lazy_exports
from ..exceptions import FtkinError, InvalidInput

__getattr__, _ = lazy_exports(__name__, {}, globals())
"""Each subcommand's module loads on first access (``ftkin.cli.calibrate``)."""

COMMAND_MODULES = (
    "calibrate",
    "compensate",
    "rezero",
    "paper",
    "demo",
    "extract",
    "export",
    "report",
    "plan",
    "evaluate-poses",
    "view",
    "simulate",
    "doctor",
    "robot",
    "record",
)
"""Subcommand modules of ``ftkin.cli``, in the order ``--help`` lists them."""


OUTPUT_OPTIONS = {
    "output": "-o/--output",
    "html": "--html",
    "png": "--png",
    "plot": "--plot",
    "live_log": "--log",  # compensate --live
    "calibration_output": "--calibrate",
}
"""Namespace attributes that name files a subcommand writes, and their flags."""

INPUT_OPTIONS = (
    "calibration",
    "samples",
    "log",
    "recording",
    "poses",
    "replay",
    "trajectory",
    "urdf",
    "prior",
    "held_load",
)
"""Namespace attributes that name files a subcommand reads."""

OUTPUT_SUFFIXES = {"html": (".html", ".htm"), "png": (".png",), "plot": (".png",)}
"""File name endings of the outputs whose format is fixed (``-o`` takes a command's own)."""


def check_outputs(args: argparse.Namespace) -> None:
    """Refuse, before anything is read or written, outputs that would destroy a file.

    Every output option goes through :func:`ftkin.io.atomic.check_output_path`
    against every input of the command; two outputs naming one file are refused too.
    """
    from ..io.atomic import check_output_path
    from .arg_types import refuse

    inputs = {}
    for name in INPUT_OPTIONS:
        value = getattr(args, name, None)
        values = value if isinstance(value, list) else [value]
        for index, one in enumerate(values):  # FILE [FILE ...] positionals are lists
            if isinstance(one, str):
                inputs[name if len(values) == 1 else f"{name} #{index + 1}"] = one
    refuse(
        InvalidInput,
        *(
            (not value.strip(), f"the {name} file name is empty; expected a path to read")
            for name, value in inputs.items()
        ),
    )
    seen: dict[str, str] = {}
    for name, flag in OUTPUT_OPTIONS.items():
        if isinstance(value := getattr(args, name, None), str):
            check_output_path(value, list(inputs.values()), flag)
            suffixes = OUTPUT_SUFFIXES.get(name, ())
            if suffixes and not value.lower().endswith(suffixes):
                raise InvalidInput(f"{flag} writes {' or '.join(suffixes)}, got {value!r}")
            if (key := os.path.realpath(value)) in seen:
                raise InvalidInput(
                    f"{seen[key]} and {flag} both name {value}; give each output its own file"
                )
            seen[key] = flag


class _Parser(argparse.ArgumentParser):
    """An argument parser that takes a flag only as spelled (``allow_abbrev=False``), it and every
    subcommand's parser (``add_subparsers`` builds them of the same class): argparse's default
    would take ``--readings`` for ``--readings-per-pose`` and ``--floor`` for ``--floor-height``,
    so a spelling that was never a flag, or a prefix that a new flag makes ambiguous, would be
    read as another."""

    def __init__(self, *args, allow_abbrev: bool = False, **keywords):
        super().__init__(*args, allow_abbrev=allow_abbrev, **keywords)


def build_parser(argv: list[str] | None = None) -> argparse.ArgumentParser:
    """The argument parser with every subcommand registered.

    Given the command line ``argv`` whose command is known, only that
    subcommand is registered (its module, and the library behind it, alone
    are imported: the other subcommands cost ~0.3 s of imports). No flag is
    taken by a prefix of its name (:class:`_Parser`).
    """
    from .._version import __version__

    parser = _Parser(
        prog="ftkin",
        description="Calibrate and compensate a robot's wrist force/torque sensor.",
    )
    parser.add_argument("--version", action="version", version=f"ftkin {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress and warnings")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    command = next((argument for argument in argv or () if not argument.startswith("-")), None)
    for name in (command,) if command in COMMAND_MODULES else COMMAND_MODULES:
        importlib.import_module(f".{name.replace('-', '_')}", __name__).register(subparsers)
    return parser


_SUMMARIZED_LOGS = ("fit_quality", "goodness_of_fit")
"""Loggers of ``ftkin.calibration`` whose warnings every fitting command's summary prints (the
static fits' diagnostics, every kind's fit test): kept out of the CLI's log, printed once."""


def main(argv=None) -> int:
    """Run the CLI; returns the exit code (0 success, 2 bad input or usage, 3 internal error).

    When the reader of stdout goes away (``ftkin ... | head -1``), the rest of
    the printout is dropped and the command still finishes its work (its
    ``-o`` file is written).
    """
    arguments = sys.argv[1:] if argv is None else list(argv)
    if "--version" in arguments and all(
        argument in ("--version", "-v", "--verbose") for argument in arguments
    ):
        # Answered before the subcommands (and the library behind them) are imported.
        from .._version import __version__

        print(f"ftkin {__version__}")
        return 0
    stdout, sys.stdout = sys.stdout, _QuietPipe(sys.stdout)
    once = {}  # a filter per handler: each handler sees each record once
    fit_logs = [logging.getLogger(f"ftkin.calibration.{name}") for name in _SUMMARIZED_LOGS]
    # every command that fits prints the summary, which lists these warnings
    fit_logs_disabled = [log.disabled for log in fit_logs]
    for log in fit_logs:
        log.disabled = True
    try:
        from .arg_types import join_number_lists

        arguments = join_number_lists(arguments)
        parser = build_parser(arguments)
        try:
            args = parser.parse_args(arguments)
        except SystemExit as exit_:  # usage errors and --help: an exit code, as every other outcome
            return exit_.code if isinstance(exit_.code, int) else 2
        logging.basicConfig(
            level=logging.INFO if args.verbose else logging.WARNING, format="ftkin: %(message)s"
        )
        for handler in logging.getLogger().handlers:
            once[handler] = _once_filter()
            handler.addFilter(once[handler])
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        args.command_line = shlex.join(["ftkin", *(sys.argv[1:] if argv is None else argv)])
        check_outputs(args)
        code = int(args.func(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not at interpreter exit
        return code
    except FtkinError as error:
        _say(f"ftkin: error: {error}")
        return 2
    except KeyboardInterrupt:
        _say("ftkin: interrupted")
        return 130
    except Exception as error:  # the guard: no traceback ever reaches a user
        return _unexpected(error)
    finally:
        sys.stdout = stdout
        for log, disabled in zip(fit_logs, fit_logs_disabled):
            log.disabled = disabled
        for handler, once_filter in once.items():
            handler.removeFilter(once_filter)


def _once_filter():
    """A logging filter that lets each warning text through once per command."""
    seen: set[str] = set()

    def let_through(record: logging.LogRecord) -> bool:
        text = record.getMessage()
        fresh = text not in seen
        seen.add(text)
        return fresh

    return let_through


class _QuietPipe:
    """stdout that stops writing, without an error, once its reader has closed the pipe."""

    def __init__(self, stream):
        self._stream = stream
        self.closed_pipe = False

    def _call(self, method, *args):
        if not self.closed_pipe:
            try:
                return getattr(self._stream, method)(*args)
            except BrokenPipeError:
                self.closed_pipe = True
                # the interpreter's final flush must not fail again
                with contextlib.suppress(OSError, ValueError, AttributeError):
                    os.dup2(os.open(os.devnull, os.O_WRONLY), self._stream.fileno())
        return len(args[0]) if args else None

    def write(self, text):
        return self._call("write", text)

    def flush(self):
        return self._call("flush")

    def __getattr__(self, name):
        return getattr(self._stream, name)


def _say(text: str) -> None:
    """One line on stderr; a closed stderr is not an error of its own."""
    with contextlib.suppress(OSError, ValueError):
        print(text, file=sys.stderr)


def _unexpected(error: Exception) -> int:
    """One line for an error ftkin did not foresee, naming its kind; the traceback only with -v."""
    import numpy as np

    kinds = {
        RecursionError: "the input is nested too deeply",
        OverflowError: "a number in the input is too large",
        MemoryError: "the input is too large for the memory available",
        np.linalg.LinAlgError: "the numbers are too extreme for the linear algebra (a matrix "
        "became singular)",
    }
    reason = next(
        (text for kind, text in kinds.items() if isinstance(error, kind)),
        "unexpected internal error",
    )
    logging.getLogger("ftkin.cli").info("details", exc_info=error)
    _say(f"ftkin: error: {reason} ({type(error).__name__}: {str(error)[:200]})")
    return 2 if reason != "unexpected internal error" else 3


def entry_point() -> None:
    """Console-script entry (``[project.scripts] ftkin``)."""
    sys.exit(main())
