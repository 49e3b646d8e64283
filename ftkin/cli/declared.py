"""Command-line flags built from the library's option declarations (:mod:`ftkin.options`).

:func:`declared_option` gives one declared field as a flag (an :func:`~ftkin.cli.arg_types.option`
row: the field's name as ``dest``, its default, its unit and its help), :func:`add_declared` adds
every declared field of an options type, and :func:`declared_values` reads them back into the
type's keywords. Two commands that take an option therefore spell it, default it and explain it
identically (``tests/cli/test_flags.py`` walks the parsers to check it).
"""

import argparse

from ..options import UNSET, declared_options, field_default
from .arg_types import option


def _shown(value) -> str:
    if isinstance(value, (list, tuple)):
        return " ".join(str(item) for item in value) or "none"
    return "none" if value is None else str(value)


def help_text(declaration, default) -> str:
    """The help line: what it does, its unit, and its default (when the field's is the CLI's)."""
    unit = f" [{declaration.unit}]" if declaration.unit else ""
    shown = default if declaration.cli_default is UNSET else declaration.cli_default
    if declaration.action in ("store_true", "store_false") or shown in (None, (), [], {}):
        return f"{declaration.help}{unit}"
    return f"{declaration.help}{unit} (default: {_shown(shown)})"


def declared_option(options_type, name: str) -> tuple:
    """The flag of the declared field ``name`` of ``options_type``, as an ``option`` row."""
    field, declaration = next(
        (field, declaration)
        for field, declaration in declared_options(options_type)
        if field.name == name
    )
    default = field_default(field)
    cli_default = default if declaration.cli_default is UNSET else declaration.cli_default
    keywords = {"dest": field.name, "help": help_text(declaration, default)}
    flag_only = declaration.action in ("store_true", "store_false")
    if declaration.action is not None:
        keywords["action"] = declaration.action
    if declaration.action != "store_true":
        keywords["default"] = cli_default
    if not flag_only:
        for attribute in ("metavar", "choices", "nargs"):
            if getattr(declaration, attribute) is not None:
                keywords[attribute] = getattr(declaration, attribute)
        if declaration.parse is not None:
            keywords["type"] = declaration.parse
    return option(declaration.flag_for(field.name), **keywords)


def add_declared(parser, options_type, *, only=None, skip=(), group: str | None = None):
    """Add the flags of ``options_type``'s declared fields to ``parser`` (or a new argument
    ``group`` titled so); ``only``/``skip``: field names to keep or leave out (in ``only``'s
    order when given).

    Returns the parser or group the flags went to.
    """
    target = parser.add_argument_group(group) if group else parser
    declared = {field.name: declaration for field, declaration in declared_options(options_type)}
    names = only if only is not None else list(declared)
    for name in names:
        if name in skip or not declared[name].cli:
            continue
        flags, keywords = declared_option(options_type, name)
        target.add_argument(*flags, **keywords)
    return target


def declared_values(options_type, args: argparse.Namespace, *, only=None, skip=()) -> dict:
    """``{field: value}`` of ``options_type``'s declared fields found in ``args``."""
    return {
        field.name: getattr(args, field.name)
        for field, _ in declared_options(options_type)
        if hasattr(args, field.name)
        and (only is None or field.name in only)
        and field.name not in skip
    }
