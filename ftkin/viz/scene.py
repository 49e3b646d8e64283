"""Static parts of the meshcat scene: the markers' shapes, the floor and the camera.

meshcat 0.3.2 cannot move the camera's orbit target, so the whole scene
(``/meshcat``, ``/Axes``) is shifted to put the arm's centre at the origin,
and the camera is placed through ``/Cameras/default/rotated/<object>``
(three.js axes: ``[x, z, -y]``). meshcat's grid does not follow a transform;
it is hidden and a translucent floor plate is drawn under the arm instead.
"""

from __future__ import annotations

import numpy as np

from ..kinematics.arm import Arm
from ..validation import as_vector
from .arrows import ArrowStyle, add_arrow_objects, rigid_transform
from .framing import PoseView
from .legend import ARROWS, BASE_GRAVITY, CENTER_OF_MASS, GRAVITY, MEASURED, VERTICAL

ROOT = "ftkin"
"""Scene folder of everything ftkin draws besides the arm."""

CAMERA_PATH = "/Cameras/default/rotated/<object>"
"""meshcat's camera object (three.js axes ``[x, z, -y]``, y up)."""

BACK_SIDE = 1
"""three.js ``THREE.BackSide``: only the inner faces are drawn."""

RADIUS_FACTORS = {MEASURED.name: 0.5, GRAVITY.name: 1.6, VERTICAL.name: 0.5}
"""Arrow radii relative to the style: a thin measured-force needle inside a wide predicted-gravity
sleeve.
"""

CAMERA_DIRECTION = np.array([0.55, -0.75, 0.35]) / np.linalg.norm([0.55, -0.75, 0.35])
"""From the orbit target towards the camera (base axes): front right, above."""


def add_markers(visualizer, geometry, style: ArrowStyle) -> None:
    """Sensor triad, arrows (unit shaft + cone head, unlit) and the COM sphere."""
    visualizer[f"{ROOT}/sensor"].set_object(geometry.triad(0.12))
    for layer in (*ARROWS, BASE_GRAVITY, VERTICAL):
        radius_factor = RADIUS_FACTORS.get(layer.name, 1.0)
        # The predicted-gravity arrow shows only its inner faces: unlit it looks the same, but the
        # measured-force needle inside it stays visible when the two coincide (a good calibration).
        side = BACK_SIDE if layer is GRAVITY else 2
        material = geometry.MeshBasicMaterial(color=layer.color, side=side)
        add_arrow_objects(
            visualizer[f"{ROOT}/{layer.name}"], geometry, style, material, radius_factor
        )
    visualizer[f"{ROOT}/{CENTER_OF_MASS.name}"].set_object(
        geometry.Sphere(0.7 * style.head_radius),
        geometry.MeshBasicMaterial(
            color=CENTER_OF_MASS.color, depthTest=False
        ),  # seen through the tool
    )


def arm_bounds(arm: Arm | None) -> tuple[np.ndarray, float]:
    """Centre [m] and largest extent [m] of the arm's frame origins at ``q = 0`` (clipped to the
    limits).
    """
    if arm is None:
        return np.zeros(3), 0.6
    q = np.clip(np.zeros(arm.nq), arm.lower_limits, arm.upper_limits)
    origins = np.array([arm.frame_placement(q, name)[1] for name in arm.frame_names])
    low, high = origins.min(axis=0), origins.max(axis=0)
    return 0.5 * (low + high), float(np.max(high - low))


def frame_view(visualizer, geometry, arm: Arm | None) -> None:
    """Centre the scene on the arm, draw the floor and place the camera."""
    target, extent = arm_bounds(arm)
    shift = rigid_transform(np.eye(3), -target)
    visualizer["/meshcat"].set_transform(shift)
    visualizer["/Axes"].set_transform(shift)
    visualizer["/Grid"].set_property("visible", False)
    size = 2.0 * max(extent, 0.5)
    floor = visualizer[f"{ROOT}/floor"]
    material = geometry.MeshLambertMaterial(
        color=0xD8D8D8, transparent=True, opacity=0.45
    )  # the arm may reach below
    floor.set_object(geometry.Box([size, size, 0.004]), material)
    floor.set_transform(rigid_transform(np.eye(3), [target[0], target[1], -0.003]))
    set_camera(visualizer, 1.25 * max(extent, 0.5) * CAMERA_DIRECTION)


def set_camera(visualizer, position) -> None:
    """Camera position relative to the orbit target, base axes [m]."""
    x, y, z = as_vector(position, 3, "camera position [m]")
    visualizer[CAMERA_PATH].set_property("position", [float(x), float(z), float(-y)])


def apply_view(sink, view: PoseView, animated: bool) -> None:
    """Aim the camera of ``sink`` (a visualizer or an animation frame) at ``view.target``.

    The scene is shifted by ``-target`` (meshcat cannot move the orbit target),
    the camera goes to ``view.offset`` and the floor is shown only when it
    cannot hide an arrow.
    """
    shift = rigid_transform(np.eye(3), -view.target)
    x, y, z = (float(v) for v in view.offset)
    sink["/meshcat"].set_transform(shift)
    sink["/Axes"].set_transform(shift)
    if animated:
        sink[CAMERA_PATH].set_property("position", "vector3", [x, z, -y])
        sink[f"/meshcat/{ROOT}/floor"].set_property("visible", "boolean", bool(view.floor_visible))
    else:
        sink[CAMERA_PATH].set_property("position", [x, z, -y])
        sink[f"/meshcat/{ROOT}/floor"].set_property("visible", bool(view.floor_visible))
