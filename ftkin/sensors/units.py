"""Force and torque units a sensor may report, to SI: exact factors, an unknown unit refused.

The names are those of pynetft's ``ForceUnit`` / ``TorqueUnit`` values (the units an ATI Net F/T
box can be set to). Every factor is exact by definition: the pound is 0.45359237 kg and
standard gravity 9.80665 m/s² (so 1 lbf = 4.4482216152605 N and 1 kgf = 9.80665 N), the inch
0.0254 m and the foot 0.3048 m. A unit not in these tables is an error, never a guess: a box
set to a unit ftkin does not know would otherwise feed a wrong wrench in silence.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InvalidInput

POUND_FORCE = 4.4482216152605
"""1 lbf [N]: 0.45359237 kg × 9.80665 m/s² (exact)."""
KILOGRAM_FORCE = 9.80665
"""1 kgf [N] (exact)."""
INCH = 0.0254
"""[m] (exact)."""
FOOT = 0.3048
"""[m] (exact)."""

FORCE_UNITS: dict[str, float] = {
    "N": 1.0,
    "kN": 1e3,
    "lbf": POUND_FORCE,
    "klbf": 1e3 * POUND_FORCE,
    "kgf": KILOGRAM_FORCE,
}
"""Newtons per unit, by pynetft's ``ForceUnit`` value."""

TORQUE_UNITS: dict[str, float] = {
    "N-m": 1.0,
    "N-mm": 1e-3,
    "kN-m": 1e3,
    "lbf-in": POUND_FORCE * INCH,
    "lbf-ft": POUND_FORCE * FOOT,
    "kgf-cm": KILOGRAM_FORCE * 0.01,
}
"""Newton-metres per unit, by pynetft's ``TorqueUnit`` value."""


def _name(unit) -> str:
    value = getattr(unit, "value", unit)  # a pynetft enum member, or its value
    if not isinstance(value, str):
        raise InvalidInput(f"a unit is named by a string, got {unit!r}")
    return value


def newtons_per(unit) -> float:
    """Newtons in one ``unit`` (a name of :data:`FORCE_UNITS` or a pynetft ``ForceUnit``).

    Raises:
        InvalidInput: the unit is not one of :data:`FORCE_UNITS` (the message lists them).
    """
    name = _name(unit)
    try:
        return FORCE_UNITS[name]
    except KeyError:
        raise InvalidInput(
            f"unknown force unit {name!r}: ftkin converts {', '.join(FORCE_UNITS)}"
        ) from None


def newton_metres_per(unit) -> float:
    """Newton-metres in one ``unit`` (a name of :data:`TORQUE_UNITS` or a pynetft ``TorqueUnit``).

    Raises:
        InvalidInput: the unit is not one of :data:`TORQUE_UNITS` (the message lists them).
    """
    name = _name(unit)
    try:
        return TORQUE_UNITS[name]
    except KeyError:
        raise InvalidInput(
            f"unknown torque unit {name!r}: ftkin converts {', '.join(TORQUE_UNITS)}"
        ) from None


def wrench_scale(force_unit, torque_unit) -> np.ndarray:
    """``(6,)`` factors that turn a wrench in ``force_unit`` and ``torque_unit`` into N and N·m.

    ``wrench_si = wrench_in_units * wrench_scale(force_unit, torque_unit)``.
    """
    return np.repeat([newtons_per(force_unit), newton_metres_per(torque_unit)], 3)
