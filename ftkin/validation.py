"""Boundary checks: coerce arrays, check shape and finiteness, raise ftkin errors.

Library functions call these once at their entry, so the numerical code behind
them can assume clean ``float64`` arrays of the right shape.
"""

from __future__ import annotations

import numpy as np

from .exceptions import InvalidInput


def as_float_array(value, name: str) -> np.ndarray:
    """Convert to a float64 array or raise :class:`InvalidInput`."""
    try:
        array = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"{name} must be numeric, got {type(value).__name__}: {error}") from None
    return array


def check_finite(array: np.ndarray, name: str) -> None:
    """Raise :class:`InvalidInput` naming the first non-finite entry."""
    if not np.all(np.isfinite(array)):
        bad = np.argwhere(~np.isfinite(array))[0]
        index = tuple(int(i) for i in bad)
        raise InvalidInput(
            f"{name} must be finite, found {array[index]!r} at index {index if len(index) > 1 else index[0]}"
        )


def as_vector(value, size: int, name: str) -> np.ndarray:
    """A finite float vector of the given size."""
    array = as_float_array(value, name)
    if array.shape != (size,):
        raise InvalidInput(f"{name} must have shape ({size},), got {array.shape}")
    check_finite(array, name)
    return array


def as_batch(value, width: int, name: str) -> tuple[np.ndarray, bool]:
    """A finite ``(N, width)`` array; a single ``(width,)`` row is accepted.

    Returns:
        The ``(N, width)`` array and whether the input was a single row.
    """
    array = as_float_array(value, name)
    single = array.ndim == 1
    if single:
        array = array[np.newaxis, :]
    if array.ndim != 2 or array.shape[1] != width:
        raise InvalidInput(f"{name} must have shape ({width},) or (N, {width}), got {np.shape(value)}")
    check_finite(array, name)
    return array, single


def as_rotation_batch(value, name: str = "rotation_sensor_to_base", atol: float = 1e-6) -> tuple[np.ndarray, bool]:
    """A batch of proper rotation matrices ``(N, 3, 3)``; ``(3, 3)`` accepted.

    Raises:
        InvalidInput: wrong shape, non-finite entries, or a matrix that is not
            orthonormal with determinant +1 (within ``atol``).
    """
    array = as_float_array(value, name)
    single = array.ndim == 2
    if single:
        array = array[np.newaxis]
    if array.ndim != 3 or array.shape[1:] != (3, 3):
        raise InvalidInput(f"{name} must have shape (3, 3) or (N, 3, 3), got {np.shape(value)}")
    check_finite(array, name)
    gram_error = np.abs(np.einsum("nji,njk->nik", array, array) - np.eye(3)).max(axis=(1, 2))
    det = np.linalg.det(array)
    bad = np.flatnonzero((gram_error > atol) | (det < 0.0))
    if bad.size:
        i = int(bad[0])
        raise InvalidInput(
            f"{name}[{i}] is not a rotation matrix (|R^T R - I| = {gram_error[i]:.2e}, det = {det[i]:.4f}); "
            "expected an orthonormal matrix with determinant +1"
        )
    return array, single


def as_positive(value, name: str) -> float:
    """A finite, strictly positive float."""
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidInput(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(number) or number <= 0.0:
        raise InvalidInput(f"{name} must be a finite positive number, got {value!r}")
    return number


def as_in_range(value, name: str, low: float, high: float, unit: str = "") -> float:
    """A finite float in ``[low, high]``; the message names the range and its unit.

    Bounds keep physically absurd inputs (a 1e308 N tool, a 1e-300 N noise)
    out of the numerics, where they would overflow instead of meaning anything.
    """
    number = as_positive(value, name) if low > 0 else _finite(value, name)
    if not low <= number <= high:
        suffix = f" {unit}" if unit else ""
        raise InvalidInput(f"{name} must be between {low:g} and {high:g}{suffix}, got {number:g}")
    return number


def _finite(value, name: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError, OverflowError):
        raise InvalidInput(f"{name} must be a number, got {value!r}") from None
    if not np.isfinite(number):
        raise InvalidInput(f"{name} must be finite, got {value!r}")
    return number
