"""Typed access to a parsed JSON document, failing with
:class:`~ftkin.exceptions.CalibrationFileError` naming the key.

The one reader of ftkin's JSON files: every getter is strict. ``null``, a
string, a boolean or a list where a number belongs is refused with the key and
what arrived (``true`` is not 1, ``"1.5"`` is not a number); a format version
outside the supported range is refused with the versions this ftkin reads.
"""

import sys
from dataclasses import dataclass

import numpy as np

from ..exceptions import CalibrationFileError


def short_repr(value) -> str:
    """``repr`` cut to 80 characters for messages."""
    text = repr(value)
    return text if len(text) <= 80 else text[:80] + "..."


def json_repr(value) -> str:
    """A JSON value as the file spells it (``null``, ``true``), cut to 80 characters."""
    special = value is None or isinstance(value, bool)
    return {None: "null", True: "true", False: "false"}[value] if special else short_repr(value)


@dataclass
class JsonReader:
    """Typed access to a parsed document, raising CalibrationFileError with the key."""

    path: str
    document: dict

    def fail(self, message: str, key: str | None = None):
        raise CalibrationFileError(self.path, message, key)

    def get(self, key: str, required: bool = True):
        if required and key not in self.document:
            self.fail("missing", key)
        return self.document.get(key)

    def optional(self, key: str, kind: type, default=None):
        """An optional value of JSON type ``kind`` (``str``, ``int``), ``default`` when absent or
        null.
        """
        value = self.get(key, required=False)
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, kind):
            self.fail(f"expected {kind.__name__} or null, got {json_repr(value)}", key)
        return value

    def optional_object(self, key: str) -> dict | None:
        """An optional JSON object: None when absent or null; anything but an object fails, naming
        the key.
        """
        value = self.get(key, required=False)
        if value is not None and not isinstance(value, dict):
            self.fail(f"expected an object or null, got {type(value).__name__}", key)
        return value

    def version(self, supported: int, key: str = "version") -> int:
        """The file's integer format version, refused when unknown or newer than ``supported``."""
        value, versions = self.get(key), f"this ftkin reads versions 1 to {supported}"
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail(f"expected an integer version, got {json_repr(value)}; {versions}", key)
        if value > supported:
            self.fail(
                f"written by a newer ftkin (file format version {value}); {versions}: upgrade "
                "ftkin",
                key,
            )
        if value < 1:
            self.fail(f"unknown format version {value}; {versions}", key)
        return value

    def check_types(self, types: dict) -> None:
        """Refuse a present key whose value is not of its JSON kind.

        ``types`` maps keys to ``"number"``, ``"numbers"`` (one, or a nested list), ``"integer"``,
        ``"integers"``, ``"string"`` or ``"strings"``; a trailing ``"?"`` also allows null
        (for lists: null entries, read as NaN).
        """
        for key, kind in types.items():
            value, nullable, base = self.document.get(key), kind.endswith("?"), kind.rstrip("?")
            if key not in self.document or (value is None and nullable):
                continue
            listed = base.endswith("s")
            leaf = _LEAF_CHECKS[base.removesuffix("s")]
            if listed and not isinstance(value, list) and base != "numbers":  # "numbers": or one
                self.fail(f"expected a list of {base}, got {json_repr(value)}", key)
            for item in _flatten([value]) if listed else [value]:
                if not (leaf(item) or (listed and nullable and item is None)):
                    expected = f"a list of {base}" if listed else f"a {base}"
                    self.fail(f"expected {expected}, got {json_repr(item)}", key)

    def count(self, key: str, default: int) -> int:
        """An optional non-negative integer count (``sample_count``, ``pose_count``)."""
        value = self.optional(key, int, default)
        if not 0 <= value <= 2**53:
            self.fail(f"expected a count between 0 and 2**53, got {short_repr(value)}", key)
        return value

    def array(self, key: str, shape: tuple, required: bool = True, source=None):
        """A float array of ``shape`` (null or absent: None when not ``required``)."""
        value = self.get(key, required) if source is None else source
        if value is None:
            if required:
                self.fail(f"expected numbers of shape {shape}, got null", key)
            return None
        if not isinstance(value, np.ndarray):  # null, a boolean, a string or an object leaf
            bad = [leaf for leaf in _flatten([value]) if not _is_number(leaf)]
            if bad:
                self.fail(f"expected numbers of shape {shape}, got {json_repr(bad[0])}", key)
        try:
            array = np.array(value, dtype=np.float64)
        except (TypeError, ValueError, OverflowError):
            self.fail(f"expected numbers of shape {shape}, got {short_repr(value)}", key)
        if array.shape != shape and not (array.size == 0 and 0 in shape):
            self.fail(f"expected shape {shape}, got {array.shape}", key)
        if not np.all(np.isfinite(array)):
            self.fail("contains NaN or infinite values", key)
        return array.reshape(shape)

    def number(self, key: str) -> float:
        value = self.get(key)
        # NaN fails the comparison; an integer beyond the float range is compared exactly
        if not (_is_number(value) and abs(value) <= sys.float_info.max):
            self.fail(f"expected a finite number, got {json_repr(value)}", key)
        return float(value)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


_LEAF_CHECKS = {
    "number": _is_number,
    "integer": lambda value: isinstance(value, int) and not isinstance(value, bool),
    "string": lambda value: isinstance(value, str),
}


def _flatten(items):
    for item in items:
        if isinstance(item, list):
            yield from _flatten(item)
        else:
            yield item


@dataclass
class NestedReader(JsonReader):
    """A :class:`JsonReader` for an object inside the document; keys are reported as
    ``prefix.key``.
    """

    prefix: str

    def fail(self, message: str, key: str | None = None):
        super().fail(message, f"{self.prefix}.{key}" if key else self.prefix)
