"""Typed access to a parsed JSON document, failing with :class:`~ftkin.exceptions.CalibrationFileError` naming the key."""

from __future__ import annotations

import math

import numpy as np

from ..exceptions import CalibrationFileError


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
        """An optional value of JSON type ``kind`` (``str``, ``int``), ``default`` when absent or null."""
        value = self.get(key, required=False)
        if value is None:
            return default
        if isinstance(value, bool) or not isinstance(value, kind):
            self.fail(f"expected {kind.__name__} or null, got {value!r}", key)
        return value

    def array(self, key: str, shape: tuple, required: bool = True, source=None):
        value = self.get(key, required) if source is None else source
        if value is None:
            return None
        try:
            array = np.array(value, dtype=np.float64)
        except (TypeError, ValueError):
            self.fail(f"expected numbers of shape {shape}, got {value!r}", key)
        if array.shape != shape and not (array.size == 0 and 0 in shape):
            self.fail(f"expected shape {shape}, got {array.shape}", key)
        if not np.all(np.isfinite(array)):
            self.fail("contains NaN or infinite values", key)
        return array.reshape(shape)

    def number(self, key: str) -> float:
        value = self.get(key)
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            self.fail(f"expected a finite number, got {value!r}", key)
        return float(value)


class NestedReader(JsonReader):
    """A :class:`JsonReader` for an object inside the document; keys are reported as ``prefix.key``."""

    def __init__(self, path: str, document: dict, prefix: str):
        super().__init__(path, document)
        self.prefix = prefix

    def fail(self, message: str, key: str | None = None):
        super().fail(message, f"{self.prefix}.{key}" if key else self.prefix)
