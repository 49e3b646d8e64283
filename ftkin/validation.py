"""Boundary checks: coerce arrays, check shape and finiteness, raise ftkin errors.

Library functions call these once at their entry, so the numerical code behind
them can assume clean ``float64`` arrays of the right shape.
"""

import dataclasses
import re

import numpy as np

from .exceptions import InvalidInput

_KIND_NAMES = {"b": "booleans", "c": "complex numbers", "O": "objects", "U": "text", "S": "bytes"}


def as_float_array(value, name: str) -> np.ndarray:
    """Convert real numbers to a float64 array or raise :class:`InvalidInput`.

    Booleans (also inside a list: numpy would turn ``[True, 1.5]`` into floats), complex numbers,
    text and object arrays (``None``, integers beyond int64, mixed types) are refused, not
    converted: ``True`` is not 1 N and ``"1.5"`` is not a number here.
    """
    try:
        array = value if isinstance(value, np.ndarray) else np.asarray(value)
    except (TypeError, ValueError) as error:
        raise InvalidInput(f"{name} must be numeric, got {type(value).__name__}: {error}") from None
    if isinstance(
        array, np.ma.MaskedArray
    ):  # numpy would drop the mask: a masked entry is no value
        if np.ma.is_masked(array):
            raise InvalidInput(f"{name} has masked entries (no value there): {_short(value)}")
        array = np.asarray(array.data)
    kind = array.dtype.kind
    if kind not in "iuf" or (isinstance(value, (list, tuple)) and _has_bool(value)):
        what = _KIND_NAMES.get("b" if kind in "iuf" else kind, f"dtype {array.dtype}")
        raise InvalidInput(f"{name} must be numeric (real numbers), got {what}: {_short(value)}")
    return array.astype(np.float64, copy=False)


def _has_bool(value) -> bool:
    """Whether a nested list holds a boolean (numpy turns ``[True, 1.5]`` into floats)."""
    if isinstance(value, (list, tuple)):
        return any(map(_has_bool, value))
    return isinstance(value, (bool, np.bool_))


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 60 else text[:60] + "..."


def as_real(value, name: str) -> float:
    """One real number as a float (a size-1 array too); booleans, text and complex refused."""
    array = as_float_array(value, name)
    if array.size != 1:
        raise InvalidInput(f"{name} must be a number, got shape {array.shape}")
    return float(array.reshape(-1)[0])


MAX_IMU_VALUE = 1e4
"""Largest accepted accelerometer [m/s²] or gyro [rad/s, rad/s²] entry: beyond, a unit mistake
or a corrupt sample."""

MAX_WRENCH = 1e6
"""Largest plausible load on the sensor [N, N·m] (a reading, a sensor offset, a tool weight).

Beyond it a value is a raw count or a unit mistake, and it would overflow the fit rather than
inform it.
"""


def check_wrench_magnitude(wrenches: np.ndarray, name: str) -> None:
    """Refuse an ``(N, 6)`` array with an entry beyond ±:data:`MAX_WRENCH` (names row, channel)."""
    beyond = np.argwhere(np.abs(wrenches) > MAX_WRENCH)
    if beyond.size:
        row, channel = (int(i) for i in beyond[0])
        raise InvalidInput(
            f"{name}[{row}] channel {'fx fy fz mx my mz'.split()[channel]} is "
            f"{wrenches[row, channel]:g}, beyond ±{MAX_WRENCH:g}: expected N and N·m, not raw "
            "counts or another unit"
        )


MAX_ID = 2**53
"""Largest id or count magnitude: every integer up to it is exact in a float64 (a CSV cell)."""


def as_integers(value, name: str, limit: int = MAX_ID) -> np.ndarray:
    """An int64 array of whole numbers of magnitude at most ``limit``, checked *before* the cast.

    Ids beyond the int64 range would wrap around in ``astype``; floats with a fraction, NaN,
    booleans and text are refused.
    """
    integers = isinstance(value, np.ndarray) and value.dtype.kind in "iu"
    numbers = value if integers else as_float_array(value, name)
    beyond = ~((numbers >= -limit) & (numbers <= limit))  # NaN is beyond too
    if np.any(beyond):
        bad = numbers.reshape(-1)[np.flatnonzero(beyond.reshape(-1))[0]]
        bound = "2**53" if limit == MAX_ID else f"{limit}"
        raise InvalidInput(
            f"{name} must be integers of magnitude at most {bound}, got {bad.item()}"
        )
    if numbers.dtype.kind == "f" and np.any(numbers != np.round(numbers)):
        raise InvalidInput(f"{name} must be integers, got a fraction")
    return numbers.astype(np.int64)


def as_wrenches(value, name: str) -> tuple[np.ndarray, bool]:
    """:func:`as_batch` of ``(N, 6)`` wrenches [N, N·m], none beyond ±:data:`MAX_WRENCH`.

    One pass for a valid batch (its largest and smallest entry; NaN fails both comparisons),
    the naming checks only when it fails: this guards the validated batch compensation.
    """
    wrenches, single = _rows(value, 6, name)
    if wrenches.size and not (wrenches.max() <= MAX_WRENCH and wrenches.min() >= -MAX_WRENCH):
        check_finite(wrenches, name)
        check_wrench_magnitude(wrenches, name)
    return wrenches, single


def as_wrench(value, name: str) -> np.ndarray:
    """One wrench ``(6,)`` [N, N·m], finite and within ±:data:`MAX_WRENCH`."""
    wrench = as_vector(value, 6, name)
    check_wrench_magnitude(wrench[np.newaxis], name)
    return wrench


def whole_number(value, name: str, minimum: int = 0, maximum: int = MAX_ID) -> int:
    """``value`` as an int (no bools, no fractions, no text) in ``[minimum, maximum]``."""
    whole = isinstance(value, (int, np.integer)) or (
        isinstance(value, (float, np.floating)) and float(value).is_integer()
    )
    if isinstance(value, (bool, np.bool_)) or not whole:
        raise InvalidInput(f"{name} must be an integer (a whole number), got {value!r}")
    if not minimum <= value <= maximum:
        bound = f"at least {minimum}" if value < minimum else f"at most {maximum}"
        raise InvalidInput(f"{name} must be {bound}, got {value}")
    return int(value)


def as_names(value, name: str) -> list[str]:
    """A list of names from any sequence of strings (a list, a tuple, a numpy array)."""
    names = value.tolist() if isinstance(value, np.ndarray) else value
    try:
        names = None if isinstance(names, (str, bytes)) else list(names)
    except TypeError:  # not a sequence
        names = None
    if names is None or not all(isinstance(n, str) for n in names):
        raise InvalidInput(f"{name} must be a sequence of strings (names), got {_short(value)}")
    return names


def check_finite(array: np.ndarray, name: str) -> None:
    """Raise :class:`InvalidInput` naming the first non-finite entry."""
    if not np.all(np.isfinite(array)):
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(array))[0])
        raise InvalidInput(
            f"{name} must be finite, found {float(array[index])} at index "
            f"{index if len(index) > 1 else index[0]}"
        )


def as_six_channels(value, name: str, non_negative: bool = False) -> np.ndarray:
    """Six per-channel values ``(6,)`` [N then N·m] from a scalar, ``[force, torque]`` or six
    numbers; finite, frozen.

    ``non_negative``: also refuse values below zero (rates, noise levels).
    """
    array = as_float_array(value, name)
    if array.shape == (2,):
        array = np.repeat(array, 3)
    if array.shape not in ((), (1,), (6,)):
        raise InvalidInput(
            f"{name} must be a scalar, [force, torque] or six channels, got shape {array.shape}"
        )
    array = np.broadcast_to(array, (6,)).copy()
    if not np.all(np.isfinite(array)) or (non_negative and np.any(array < 0)):
        requirement = "finite and ≥ 0" if non_negative else "finite"
        raise InvalidInput(
            f"{name} must be {requirement} (a scalar, [force, torque] or six channels), got {array}"
        )
    array.setflags(write=False)
    return array


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
    array, single = _rows(value, width, name)
    check_finite(array, name)
    return array, single


def _rows(value, width: int, name: str) -> tuple[np.ndarray, bool]:
    """``value`` as a float ``(N, width)`` array (a ``(width,)`` row accepted), unchecked values."""
    array = as_float_array(value, name)
    single = array.ndim == 1
    array = array[np.newaxis, :] if single else array
    if array.ndim != 2 or array.shape[1] != width:
        raise InvalidInput(
            f"{name} must have shape ({width},) or (N, {width}), got {np.shape(value)}"
        )
    return array, single


def as_rotation_batch(
    value, name: str = "rotation_sensor_to_base", atol: float = 1e-6
) -> tuple[np.ndarray, bool]:
    """A batch of proper rotation matrices ``(N, 3, 3)``; ``(3, 3)`` accepted.

    Raises:
        InvalidInput: wrong shape, non-finite entries, or a matrix that is not
            orthonormal with determinant +1 (within ``atol``).
    """
    array = as_float_array(value, name)
    single = array.ndim == 2
    array = array[np.newaxis] if single else array
    if array.ndim != 3 or array.shape[1:] != (3, 3):
        raise InvalidInput(f"{name} must have shape (3, 3) or (N, 3, 3), got {np.shape(value)}")
    if not _all_rotations(array, atol):  # the detailed error names the first bad matrix
        check_finite(array, name)
        with np.errstate(all="ignore"):  # a huge matrix overflows: refused below, no warning
            gram_error = np.abs(np.einsum("nji,njk->nik", array, array) - np.eye(3)).max((1, 2))
            det = np.linalg.det(array)
        # compared so that NaN fails: a huge "rotation" overflows to inf − inf
        bad = np.flatnonzero(~(gram_error <= atol) | ~(det >= 0.0))
        if bad.size:  # none: a matrix on the tolerance's edge, rounded the other way: accepted
            i = int(bad[0])
            raise InvalidInput(
                f"{name}[{i}] is not a rotation matrix (|R^T R - I| = {gram_error[i]:.2e}, det = "
                f"{det[i]:.4f}); "
                "expected an orthonormal matrix with determinant +1"
            )
    return array, single


_BLOCK = 16384
"""Rotations checked per block by :func:`_all_rotations` (temporaries stay in cache)."""


def _all_rotations(array: np.ndarray, atol: float) -> bool:
    """True if every ``(3, 3)`` of ``array`` has ``|RᵀR − I| <= atol`` entry by entry and ``det >
    0``.

    Closed form, vectorised over the batch: the six distinct entries of ``RᵀR``
    are column dot products and ``det R = c2 · (c0 × c1)``. NaN and inf fail
    the comparisons, so this also checks finiteness.
    """
    for start in range(0, len(array), _BLOCK):
        block = array[start : start + _BLOCK]
        c0, c1, c2 = block[:, :, 0], block[:, :, 1], block[:, :, 2]
        norms = (np.einsum("nj,nj->n", a, a) for a in (c0, c1, c2))  # computed as checked
        products = (np.einsum("nj,nj->n", a, b) for a, b in ((c0, c1), (c0, c2), (c1, c2)))
        if not (
            all(((1.0 - atol <= norm) & (norm <= 1.0 + atol)).all() for norm in norms)
            and all((np.abs(product, out=product) <= atol).all() for product in products)
        ):
            return False
        det = (
            (c0[:, 1] * c1[:, 2] - c0[:, 2] * c1[:, 1]) * c2[:, 0]
            + (c0[:, 2] * c1[:, 0] - c0[:, 0] * c1[:, 2]) * c2[:, 1]
            + (c0[:, 0] * c1[:, 1] - c0[:, 1] * c1[:, 0]) * c2[:, 2]
        )
        if not (det > 0.0).all():
            return False
    return True


def as_positive(value, name: str) -> float:
    """A finite, strictly positive float."""
    number = as_real(value, name)
    if not np.isfinite(number) or number <= 0.0:
        raise InvalidInput(f"{name} must be a finite positive number, got {value!r}")
    return number


def as_in_range(value, name: str, low: float, high: float, unit: str = "") -> float:
    """A finite float in ``[low, high]``; the message names the range and its unit.

    Bounds keep physically absurd inputs (a 1e308 N tool, a 1e-300 N noise)
    out of the numerics, where they would overflow instead of meaning anything.
    """
    number = as_positive(value, name) if low > 0 else as_real(value, name)
    if not np.isfinite(number):
        raise InvalidInput(f"{name} must be finite, got {value!r}")
    if not low <= number <= high:
        suffix = f" {unit}" if unit else ""
        raise InvalidInput(f"{name} must be between {low:g} and {high:g}{suffix}, got {number:g}")
    return number


FLOAT64 = np.dtype(np.float64)
"""The dtype of the one-sample fast paths (``array.dtype is FLOAT64``: native float64, no
conversion).
"""


def rotation_rows(value, atol: float = 1e-6) -> list | None:
    """``R.tolist()`` if ``value`` is one proper rotation ``(3, 3)``, else None.

    The one-sample form of :func:`as_rotation_batch`'s test (:func:`is_rotation_rows`).
    A None tells the caller to run :func:`as_rotation_batch` for the detailed error.
    """
    if type(value) is not np.ndarray or value.dtype is not FLOAT64:
        try:  # real numbers only: booleans and text are not converted
            value = as_float_array(value, "rotation")
        except InvalidInput:
            return None
    if value.shape != (3, 3):
        return None
    rows = value.tolist()
    return rows if is_rotation_rows(rows, atol) else None


def is_rotation_rows(rows: list, atol: float = 1e-6) -> bool:
    """True if ``rows`` (``R.tolist()`` of a float ``(3, 3)``) is a proper rotation.

    :func:`as_rotation_batch`'s test in closed form on Python floats:
    ``|RᵀR − I| <= atol`` entry by entry and ``det R > 0`` (NaN and inf fail
    the comparisons).
    """
    (a, b, c), (d, e, f), (g, h, i) = rows
    low, high = 1.0 - atol, 1.0 + atol  # column norms² within 1 ± atol, dot products within ± atol
    return (
        low <= a * a + d * d + g * g <= high
        and low <= b * b + e * e + h * h <= high
        and low <= c * c + f * f + i * i <= high
        and -atol <= a * b + d * e + g * h <= atol
        and -atol <= a * c + d * f + g * i <= atol
        and -atol <= b * c + e * f + h * i <= atol
        and a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g) > 0.0
    )


_ROS_TOKEN = r"[A-Za-z_][A-Za-z0-9_]*"
_ROS_NAME_RULES = {
    "node": (
        rf"(/({_ROS_TOKEN}/)*)?{_ROS_TOKEN}|/\*\*",
        "letters, digits and underscores, not starting with a digit, optionally after a "
        "namespace /ns/ (or the wildcard /**)",
    ),
    "frame": (
        rf"{_ROS_TOKEN}(/{_ROS_TOKEN})*",
        "tokens of letters, digits and underscores, each not starting with a digit, joined by "
        "single '/', no leading '/' (tf2)",
    ),
    "topic": (
        rf"/?{_ROS_TOKEN}(/{_ROS_TOKEN})*",
        "tokens of letters, digits and underscores, each not starting with a digit, joined by "
        "single '/', optionally absolute",
    ),
}
"""ROS 2 name rules by kind (design.ros2.org "Topic and Service name mapping", REP 105 and tf2's
frame ids): the regular expression and what it allows, for messages.
"""


def as_ros_name(value, kind: str, name: str) -> str:
    """``value`` if it is a valid ROS name of ``kind`` (``"node"``, ``"frame"`` or ``"topic"``).

    Besides the pattern, ROS 2 refuses ``__`` (reserved) and a trailing ``/``. The check runs
    before a name is written into a file the target system would then reject.

    Raises:
        InvalidInput: not a string, or a string the rules refuse (the message quotes the rule).
    """
    pattern, rule = _ROS_NAME_RULES[kind]
    if not isinstance(value, str):
        raise InvalidInput(f"{name} must be a ROS {kind} name (a string), got {value!r}")
    if not re.fullmatch(pattern, value) or "__" in value:
        raise InvalidInput(
            f"{name} {value!r} is not a valid ROS {kind} name: expected {rule}, no '__'"
        )
    return value


def set_checked(instance, **values) -> None:
    """Store checked values in the fields of a frozen dataclass (from its ``__post_init__``)."""
    for name, value in values.items():
        object.__setattr__(instance, name, value)


def from_fields(cls, options: dict, what: str):
    """``cls(**options)``, an unknown keyword named with the known ones (:class:`InvalidInput`)."""
    known = [item.name for item in dataclasses.fields(cls) if item.init]
    unknown = sorted(set(options) - set(known))
    if unknown:
        raise InvalidInput(f"{what} takes no {', '.join(unknown)}; expected: {', '.join(known)}")
    return cls(**options)
