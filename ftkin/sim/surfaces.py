"""Surfaces for the placement simulation: horizontal spring–dampers.

A surface is the plane ``z = height`` in the base frame. An object pressed
``penetration`` [m] into it (rate ``penetration_rate`` [m/s]) feels the upward
normal force ``N = max(0, k·δ + c·δ̇)`` for ``δ > 0`` and nothing otherwise: it
pushes, it never pulls. ``k`` and ``c`` are *effective* values: the surface in
series with the gripper's and the object's own compliance, which is why even
the book is only tens of kN/m. :func:`held_object_wrench` is what the
sensor feels of a held object pressed on a surface.
"""

import math
from dataclasses import dataclass, replace
from numbers import Real

import numpy as np

from ..exceptions import InvalidInput


@dataclass(frozen=True)
class Surface:
    """A compliant horizontal surface.

    Attributes:
        name: Label used in reports and plots.
        stiffness: ``k`` [N/m].
        damping: ``c`` [N·s/m].
        height: Top of the surface along base z [m].
    """

    name: str
    stiffness: float
    damping: float
    height: float = 0.0

    def __post_init__(self):
        if not (isinstance(self.stiffness, Real) and 0.0 < self.stiffness < math.inf):
            raise InvalidInput(
                f"surface stiffness [N/m] must be a finite number > 0, got {self.stiffness!r}"
            )
        if not (isinstance(self.damping, Real) and 0.0 <= self.damping < math.inf):
            raise InvalidInput(
                f"surface damping [N·s/m] must be a finite number >= 0, got {self.damping!r}"
            )

    def normal_force(self, penetration: float, penetration_rate: float) -> float:
        """Upward force [N] on an object ``penetration`` [m] deep, moving in at ``penetration_rate``
        [m/s].
        """
        if penetration <= 0.0:  # it pushes, it never pulls
            return 0.0
        return max(0.0, self.stiffness * penetration + self.damping * penetration_rate)

    def at_height(self, height: float) -> "Surface":
        """The same surface with its top at ``height`` [m]."""
        return replace(self, height=float(height))


SPONGE = Surface("sponge", stiffness=2.0e3, damping=20.0)
"""A sponge pad: soft, 2 kN/m, 20 N·s/m."""

BOOK = Surface("book", stiffness=2.0e4, damping=100.0)
"""A book on a table (with the gripper's compliance): stiff, 20 kN/m, 100 N·s/m."""

SURFACES = {surface.name: surface for surface in (SPONGE, BOOK)}
"""Surfaces by name."""


def surface_by_name(name: str) -> Surface:
    """:data:`SPONGE` or :data:`BOOK` by name; :class:`InvalidInput` lists the names."""
    if name not in SURFACES:
        raise InvalidInput(f"unknown surface {name!r}; expected one of {sorted(SURFACES)}")
    return SURFACES[name]


def held_object_wrench(
    rotation,
    sensor_origin,
    tool_point,
    object_height: float,
    object_weight: float,
    normal_force: float,
) -> np.ndarray:
    """Contact wrench ``(6,)`` [N, N·m] in the sensor frame of a held object pressed on a horizontal
    surface.

    The object hangs along the sensor z axis (``rotation`` = ``R_BS``): its
    weight [N] acts ``object_height / 2`` [m] below the tool point, the
    surface's upward ``normal_force`` [N] at its bottom ``object_height``
    below; moments about the sensor origin. Positions in the base frame [m].
    """
    axis = rotation[:, 2]
    bottom, middle = tool_point + axis * object_height, tool_point + axis * (0.5 * object_height)
    # r_b × (N ẑ) + r_m × (−W ẑ) = (N r_b − W r_m) × ẑ = (v_y, −v_x, 0)
    v = normal_force * (bottom - sensor_origin) - object_weight * (middle - sensor_origin)
    moment_base = np.array([v[1], -v[0], 0.0])
    return np.concatenate((rotation[2] * (normal_force - object_weight), rotation.T @ moment_base))
