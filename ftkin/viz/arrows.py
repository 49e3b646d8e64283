"""Arrow geometry for meshcat, which has no arrow primitive (pure numpy).

An arrow is a cylinder shaft plus a cone head (a cylinder with
``radiusTop=0``). meshcat cylinders run along their local +Y axis, centred on
the origin, so an arrow from ``origin`` along ``vector`` is built from unit
shapes placed by a rigid transform and a per-axis scale:

* the shaft: a cylinder of height 1 scaled to the shaft length along Y,
  centred halfway between the origin and the base of the head;
* the head: a cone of height ``head_length``, uniformly shrunk when the arrow
  is shorter than ``2 × head_length``, its tip at ``origin + vector``.

A :class:`NodePose` keeps the rigid part and the scale apart: a live viewer
gets the product (:meth:`NodePose.matrix`), an animation track gets
position/quaternion and scale separately (meshcat's animation frames record
no scale in ``set_transform``).
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_positive, as_vector

MIN_SCALE = 1e-6
"""Smallest scale factor sent to the viewer (a zero scale makes a singular matrix)."""


@dataclass(frozen=True)
class NodePose:
    """Placement of one scene node: rigid transform ``(4, 4)`` and scale ``(3,)``."""

    rigid: np.ndarray
    scale: np.ndarray

    def matrix(self) -> np.ndarray:
        """The transform a live viewer gets: ``rigid @ diag(scale, 1)``."""
        return rigid_transform(self.rigid[:3, :3] * self.scale, self.rigid[:3, 3])


@dataclass(frozen=True)
class ArrowStyle:
    """Sizes of an arrow [m].

    Attributes:
        shaft_radius: Radius of the shaft [m].
        head_radius: Radius of the cone's base [m].
        head_length: Height of the cone [m] (shrunk for short arrows).
    """

    shaft_radius: float = 0.007
    head_radius: float = 0.018
    head_length: float = 0.045

    def __post_init__(self):
        for name in ("shaft_radius", "head_radius", "head_length"):
            object.__setattr__(self, name, as_positive(getattr(self, name), f"ArrowStyle.{name}"))


def rigid_transform(rotation: np.ndarray, translation) -> np.ndarray:
    """``(4, 4)`` homogeneous transform from a rotation ``(3, 3)`` and a translation ``(3,)``
    [m].
    """
    return np.vstack([np.column_stack([rotation, translation]), [0.0, 0.0, 0.0, 1.0]])


def rotation_y_to(direction) -> np.ndarray:
    """A rotation whose second column (the image of +Y) is the unit ``direction``.

    The other two axes are chosen continuously away from ``±Y``; any choice
    is right for a rotationally symmetric arrow.

    Raises:
        InvalidInput: ``direction`` is not a finite non-zero 3-vector.
    """
    y_axis = _unit(direction, "arrow direction")
    helper = np.array([1.0, 0.0, 0.0]) if abs(y_axis[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x_axis = helper - y_axis * (helper @ y_axis)
    x_axis /= np.linalg.norm(x_axis)
    return np.column_stack([x_axis, y_axis, np.cross(x_axis, y_axis)])


@dataclass(frozen=True)
class ArrowPlacement:
    """Where the unit shaft and the cone head of one arrow go (base frame).

    Attributes:
        shaft: Pose of the unit-height cylinder (scale ``[1, shaft_length, 1]``).
        head: Pose of the cone of height ``style.head_length`` (uniform scale).
        length: Drawn length ``|vector| × scale`` [m].
    """

    shaft: NodePose
    head: NodePose
    length: float


def arrow_placement(
    origin, vector, scale: float, style: ArrowStyle | None = None
) -> ArrowPlacement:
    """Place an arrow from ``origin`` [m] along ``vector`` (any unit) × ``scale`` [m per unit].

    A zero vector gives a vanishing arrow (scale :data:`MIN_SCALE`) pointing up.
    """
    style = style or ArrowStyle()
    origin = as_vector(origin, 3, "arrow origin")
    vector = as_vector(vector, 3, "arrow vector")
    norm = float(np.linalg.norm(vector))
    length = norm * as_positive(scale, "arrow scale")
    direction = vector / norm if length > 0.0 else np.array([0.0, 0.0, 1.0])
    rotation = rotation_y_to(direction)
    head_length = min(style.head_length, 0.5 * length)
    shaft = NodePose(
        rigid_transform(rotation, origin + direction * (0.5 * (length - head_length))),
        np.array([1.0, max(length - head_length, MIN_SCALE), 1.0]),
    )
    head = NodePose(
        rigid_transform(rotation, origin + direction * (length - 0.5 * head_length)),
        np.full(3, max(head_length / style.head_length, MIN_SCALE)),
    )
    return ArrowPlacement(shaft, head, length)


def add_arrow_objects(node, geometry, style: ArrowStyle, material, radius_factor: float = 1.0):
    """Put an arrow's unit shaft and cone head (``node["shaft"]``, ``node["head"]``) in a scene.

    ``node`` is a meshcat scene node, ``geometry`` the ``meshcat.geometry`` module; the radii
    of ``style`` are multiplied by ``radius_factor``. :func:`arrow_placement` places them.
    """
    node["shaft"].set_object(geometry.Cylinder(1.0, style.shaft_radius * radius_factor), material)
    cone = geometry.Cylinder(
        style.head_length, radiusTop=0.0, radiusBottom=style.head_radius * radius_factor
    )
    node["head"].set_object(cone, material)


def exaggerate_tilt(gravity_direction, factor: float) -> np.ndarray:
    """Unit gravity direction with its angle from ``-z`` multiplied by ``factor``.

    Used to make a base tilt of a fraction of a degree visible. The direction turns in the
    vertical plane through ``-z`` and itself (its azimuth kept); the angle is capped at 180°.
    """
    direction = _unit(gravity_direction, "gravity direction")
    horizontal = np.array([direction[0], direction[1], 0.0])  # towards ``direction``
    sin_angle = np.linalg.norm(horizontal)
    if sin_angle < 1e-12:
        return direction
    angle = min(np.arctan2(sin_angle, -direction[2]) * factor, np.pi)
    return np.array([0.0, 0.0, -np.cos(angle)]) + np.sin(angle) * horizontal / sin_angle


def _unit(vector, name: str) -> np.ndarray:
    vector = as_vector(vector, 3, name)
    norm = np.linalg.norm(vector)
    if norm == 0.0:
        raise InvalidInput(f"{name} must be non-zero")
    return vector / norm
