"""Block-style YAML for ftkin's own output files, without a YAML dependency.

Nested dicts become indented blocks; a list of rows (lists) becomes a block
sequence of flow rows; every other leaf (string, number, number list, None,
bool) is written as JSON, which is valid YAML flow syntax with correct string
escaping. Non-finite numbers are refused: YAML readers disagree about them.
"""

from __future__ import annotations

import json

import numpy as np

from ..exceptions import InvalidInput


def _flow(value) -> str:
    if isinstance(value, np.ndarray | np.generic):
        value = value.tolist()
    try:
        return json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        raise InvalidInput(f"cannot write {value!r} to YAML: expected finite numbers, strings or lists of them") from None


def yaml_lines(tree: dict, indent: int = 0) -> list[str]:
    """The lines of ``tree`` as block YAML, indented by ``indent`` spaces."""
    lines = []
    pad = " " * indent
    for key, value in tree.items():
        if isinstance(value, dict):
            lines.append(f"{pad}{key}:")
            lines.extend(yaml_lines(value, indent + 2))
        elif isinstance(value, list) and value and all(isinstance(row, list) for row in value):
            lines.append(f"{pad}{key}:")
            lines.extend(f"{pad}  - {_flow(row)}" for row in value)
        else:
            lines.append(f"{pad}{key}: {_flow(value)}")
    return lines


def yaml_text(tree: dict) -> str:
    """``tree`` as a block YAML document (ends with a newline)."""
    return "\n".join(yaml_lines(tree)) + "\n"
