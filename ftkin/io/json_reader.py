"""Typed access to a parsed JSON document, failing with
:class:`~ftkin.exceptions.CalibrationFileError` naming the key.
"""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import CalibrationFileError
from .calibration_checks import has_bool, short_repr


class JsonReader:
    """Typed access to a parsed document, raising CalibrationFileError with the key."""

    def __init__(self, path: str, document: dict):
        self.path, self.document = path, document

    def fail(self, message: str, key: str | None = None):
        raise CalibrationFileError(self.path, message, key)

    def get(self, key: str, required: bool = True):
        if key not in self.document:
            if required:
                self.fail("missing", key)
            return None
        return self.document[key]

    def optional(self, key: str, kind: type, default=None):
        """An optional value of JSON type ``kind`` (``str``, ``int``), ``default`` when absent or
        null.
        """
        value = self.get(key, required=False)
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, kind):
            self.fail(f"expected {kind.__name__} or null, got {short_repr(value)}", key)
        return value

    def optional_object(self, key: str) -> dict | None:
        """An optional JSON object: None when absent or null; anything but an object fails, naming
        the key.
        """
        value = self.get(key, required=False)
        if value is not None and not isinstance(value, dict):
            self.fail(f"expected an object or null, got {type(value).__name__}", key)
        return value

    def count(self, key: str, default: int) -> int:
        """An optional non-negative integer count (``sample_count``, ``pose_count``)."""
        value = self.optional(key, int, default)
        if not 0 <= value <= 2**53:
            self.fail(f"expected a count between 0 and 2**53, got {short_repr(value)}", key)
        return value

    def array(self, key: str, shape: tuple, required: bool = True, source=None):
        value = self.get(key, required) if source is None else source
        if value is None:
            return None
        if has_bool(value):
            self.fail(
                f"expected numbers of shape {shape}, got a boolean (true/false are not numbers)",
                key,
            )
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
        try:
            finite = (
                not isinstance(value, bool)
                and isinstance(value, (int, float))
                and math.isfinite(value)
            )
        except OverflowError:
            finite = False
        if not finite:
            self.fail(f"expected a finite number, got {short_repr(value)}", key)
        return float(value)


class NestedReader(JsonReader):
    """A :class:`JsonReader` for an object inside the document; keys are reported as
    ``prefix.key``.
    """

    def __init__(self, path: str, document: dict, prefix: str):
        super().__init__(path, document)
        self.prefix = prefix

    def fail(self, message: str, key: str | None = None):
        super().fail(message, f"{self.prefix}.{key}" if key else self.prefix)
