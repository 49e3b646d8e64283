"""YAML for ftkin's own output files, written by PyYAML's ``safe_dump``.

A well-kept emitter quotes and escapes every key and value, so no name given
on the command line (a ``--node-name`` or ``--frame-id`` holding a newline,
a colon, a ``#``) can inject structure. Leaf lists are written in flow style
(``[0.0, 0.0, 0.047]``), dicts as blocks, keys in the given order. Numbers
keep their shortest round-trip form. Comments go above the document as ``#``
header lines (each line of a comment is prefixed, so a comment cannot inject
YAML either). Non-finite numbers are refused: YAML readers disagree about them.
"""

import math

import numpy as np

from ..exceptions import InvalidInput


def _plain(value):
    """``value`` as plain Python (dict, list, str, int, float, bool, None), or
    :class:`InvalidInput`.
    """
    if isinstance(value, (np.ndarray, np.generic)):
        value = value.tolist()
    if isinstance(value, dict):
        return {str(key): _plain(item) for key, item in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(item) for item in value]
    if isinstance(value, float) and not math.isfinite(value):
        raise InvalidInput(f"cannot write {value!r} to YAML: expected finite numbers")
    if value is None or isinstance(value, (str, int, float, bool)):
        return value
    raise InvalidInput(
        f"cannot write {value!r} to YAML: expected finite numbers, strings or lists of them"
    )


def yaml_text(tree: dict, comments=()) -> str:
    """``tree`` as a YAML document (ends with a newline), with ``comments`` as ``#`` lines above it.

    Raises:
        InvalidInput: a non-finite number or a value that is not plain data.
    """
    import yaml  # PyYAML loads when a file is written, not with ftkin

    body = yaml.safe_dump(
        _plain(tree), sort_keys=False, default_flow_style=None, allow_unicode=True, width=4096
    )
    lines = (line for comment in comments for line in str(comment).splitlines() or [""])
    return "".join(f"# {line}".rstrip() + "\n" for line in lines) + body
