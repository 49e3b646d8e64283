"""Command-line flags built from the library's option declarations (:mod:`ftkin.options`).

:func:`add_declared` adds one flag per declared field of an options type, with the field's
name as ``dest``, its default, its unit and its help; :func:`declared_values` reads them back
into the type's keywords. Two commands that take an option therefore spell it, default it and
explain it identically (``tests/cli/test_flags.py`` walks every parser to check it).
"""

import argparse

from ..options import declared_options, field_default


def _shown(value) -> str:
    if isinstance(value, (list, tuple)):
        return " ".join(str(item) for item in value) or "none"
    return "none" if value is None else str(value)


def help_text(declaration, default) -> str:
    """The help line: what it does, its unit, and its default."""
    unit = f" [{declaration.unit}]" if declaration.unit else ""
    if declaration.action == "store_true" or default in (None, (), [], {}):
        return f"{declaration.help}{unit}"
    return f"{declaration.help}{unit} (default: {_shown(default)})"


def add_declared(parser, options_type, *, only=None, skip=(), group: str | None = None):
    """Add the flags of ``options_type``'s declared fields to ``parser`` (or a new argument
    ``group`` titled so); ``only``/``skip``: field names to keep or leave out.

    Returns the parser or group the flags went to.
    """
    target = parser.add_argument_group(group) if group else parser
    for field, declaration in declared_options(options_type):
        if (only is not None and field.name not in only) or field.name in skip:
            continue
        default = field_default(field)
        cli_default = default if declaration.cli_default is None else declaration.cli_default
        keywords = {"dest": field.name, "help": help_text(declaration, default)}
        if declaration.action is not None:
            keywords["action"] = declaration.action
            if declaration.action != "store_true":
                keywords["default"] = cli_default
        else:
            keywords["default"] = cli_default
            for name in ("metavar", "choices", "nargs"):
                if getattr(declaration, name) is not None:
                    keywords[name] = getattr(declaration, name)
            if declaration.parse is not None:
                keywords["type"] = declaration.parse
        target.add_argument(declaration.flag_for(field.name), **keywords)
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
