"""Where the camera goes at one pose: aimed at the sensor, seeing the arrows side-on (pure numpy).

meshcat's camera orbits a fixed target, so a view is a target (the sensor
origin, base frame B) and a camera offset from it. :func:`frame_pose` picks
the offset from a small set of candidate directions (azimuths around the
vertical × elevations above the horizon) by a cost that adds:

* the fraction of points along the arrows hidden behind the arm (an arm point
  within :data:`LINK_RADIUS` of the line of sight, between arrow and camera);
* how end-on the arrows are seen (``(v·u)²`` per arrow direction ``u``);
* how far the view is from the normal of the plane spanned by the measured
  and the predicted force (weighted by the sine of their angle: when they
  coincide any side view is as good);
* a camera below the floor plane, or elevations far from
  :data:`PREFERRED_ELEVATION`;
* a small preference for looking at the sensor from outside the arm (the arm
  behind the arrows), which also keeps consecutive poses alike.

The distance makes a sphere of radius ``max(1.2 × longest arrow, tool size)``
fill :data:`FILL` of the half-height of meshcat's 75° field of view. The floor
is shown only when every arrow point and the camera are above it, so it can
never hide an arrow (a segment between two points above a plane stays above
it).
"""

from dataclasses import dataclass

import numpy as np

from ..validation import as_vector

FIELD_OF_VIEW_DEG = 75.0
"""Vertical field of view of meshcat's default camera [deg]."""

FILL = 0.6
"""Fraction of the half-height of the image the framed sphere fills."""

LINK_RADIUS = 0.05
"""Radius of the arm around its sampled points, for the occlusion test [m]."""

PREFERRED_ELEVATION = np.radians(25.0)
"""Preferred angle of the camera above the horizon at the target [rad]."""

AZIMUTHS = np.radians(np.arange(0.0, 360.0, 20.0))
ELEVATIONS = np.radians([10.0, 25.0, 40.0, 55.0, 70.0])


@dataclass(frozen=True)
class PoseView:
    """The camera at one pose (base frame B).

    Attributes:
        target: Orbit target, the sensor origin [m].
        offset: Camera position minus target [m].
        floor_visible: Whether the floor may be drawn (it cannot hide an arrow).
        radius: Radius of the framed sphere around the target [m].
        hidden_fraction: Fraction of the arrow points the arm hides from this camera.
    """

    target: np.ndarray
    offset: np.ndarray
    floor_visible: bool
    radius: float
    hidden_fraction: float

    @property
    def position(self) -> np.ndarray:
        """Camera position [m]."""
        return self.target + self.offset

    @property
    def right(self) -> np.ndarray:
        """Unit vector pointing right on screen (horizontal, base frame)."""
        forward = -self.offset / np.linalg.norm(self.offset)
        right = np.array([forward[1], -forward[0], 0.0])  # forward × z
        norm = np.linalg.norm(right)
        return right / norm if norm > 1e-9 else np.array([1.0, 0.0, 0.0])


def candidate_directions() -> np.ndarray:
    """``(K, 3)`` unit directions from the target towards the camera."""
    azimuth, elevation = (grid.ravel() for grid in np.meshgrid(AZIMUTHS, ELEVATIONS, indexing="ij"))
    return np.column_stack(
        [
            np.cos(elevation) * np.cos(azimuth),
            np.cos(elevation) * np.sin(azimuth),
            np.sin(elevation),
        ]
    )


def hidden_fractions(
    arrow_points: np.ndarray,
    arm_points: np.ndarray,
    cameras: np.ndarray,
    link_radius: float = LINK_RADIUS,
) -> np.ndarray:
    """Per camera position ``(K, 3)`` [m], the fraction of ``arrow_points`` ``(J, 3)`` hidden by
    ``arm_points`` ``(P, 3)``.

    An arrow point is hidden when an arm point lies within ``link_radius`` of
    the segment from it to the camera (and not at the arrow point itself).
    """
    if len(arm_points) == 0 or len(arrow_points) == 0:
        return np.zeros(len(cameras))
    sight = cameras[:, None, :] - arrow_points[None, :, :]  # (K, J, 3)
    length2 = np.einsum("kjd,kjd->kj", sight, sight)
    relative = arm_points[None, :, :] - arrow_points[:, None, :]  # (J, P, 3)
    along = np.einsum("jpd,kjd->kjp", relative, sight) / length2[..., None]  # (K, J, P)
    closest = arrow_points[None, :, None, :] + along[..., None] * sight[:, :, None, :]
    distance = np.linalg.norm(arm_points[None, None, :, :] - closest, axis=-1)
    in_between = (along > link_radius / np.sqrt(length2)[..., None]) & (along < 1.0)
    hidden = np.any(in_between & (distance < link_radius), axis=-1)  # (K, J)
    return hidden.mean(axis=-1)


def frame_pose(
    sensor_origin,
    arrows,
    arm_points=None,
    *,
    tool_size: float = 0.0,
    floor_height: float | None = 0.0,
    outward=None,
) -> PoseView:
    """The camera for one pose.

    Args:
        sensor_origin: Sensor origin, base frame [m] (the orbit target).
        arrows: ``(A, 3)`` drawn arrows from the sensor origin, base frame [m]
            (force × scale); the first two are the measured and the predicted force.
        arm_points: ``(P, 3)`` points along the arm, base frame [m] (or None).
        tool_size: Extent of the tool around the sensor [m].
        floor_height: Height of the drawn floor in the base frame [m], or None (no floor).
        outward: Horizontal direction from the arm towards the sensor (default:
            from the base origin); the camera prefers that side.
    """
    target = as_vector(sensor_origin, 3, "sensor origin [m]")
    arrows = np.asarray(arrows, dtype=float).reshape(-1, 3)
    arm_points = np.asarray([] if arm_points is None else arm_points, dtype=float).reshape(-1, 3)
    lengths = np.linalg.norm(arrows, axis=1)
    radius = max(1.2 * float(lengths.max(initial=0.0)), float(tool_size), 0.15)
    distance = radius / (FILL * np.tan(np.radians(FIELD_OF_VIEW_DEG) / 2))
    directions = candidate_directions()
    cameras = target + distance * directions
    samples = np.linspace(0.15, 1.0, 6)[:, None, None]  # along each arrow
    arrow_points = (target + samples * arrows[None, :, :]).reshape(-1, 3)
    hidden = hidden_fractions(arrow_points, arm_points, cameras)

    cost = 4.0 * hidden
    drawn = lengths > 1e-9  # none drawn: no end-on term
    units = arrows[drawn] / lengths[drawn, None]
    cost += 1.0 * ((directions @ units.T) ** 2) @ (lengths[drawn] / lengths[drawn].sum())  # end-on
    if len(arrows) >= 2 and lengths[0] > 1e-9 and lengths[1] > 1e-9:
        normal = np.cross(arrows[0] / lengths[0], arrows[1] / lengths[1])
        sine = float(np.linalg.norm(normal))
        if sine > 1e-6:
            cost += 2.0 * sine * (1.0 - (directions @ (normal / sine)) ** 2)
    elevation = np.arcsin(np.clip(directions[:, 2], -1.0, 1.0))
    cost += 0.6 * np.abs(elevation - PREFERRED_ELEVATION) / np.radians(45.0)
    if floor_height is not None:
        cost += 2.0 * (cameras[:, 2] < floor_height + 0.05)
    away = (target if outward is None else as_vector(outward, 3, "outward")) * [1.0, 1.0, 0.0]
    if np.linalg.norm(away) > 1e-6:
        cost -= 0.2 * (directions @ (away / np.linalg.norm(away)))
    best = int(np.argmin(cost))
    offset = distance * directions[best]
    lowest = min(arrow_points[:, 2].min(initial=target[2]), target[2] + offset[2])  # or the camera
    floor_visible = floor_height is not None and bool(lowest > floor_height + 0.01)
    return PoseView(target, offset, floor_visible, radius, float(hidden[best]))


def arm_points(arm, q, per_segment: int = 4) -> np.ndarray:
    """Points along the arm at ``q`` [rad], base frame [m]: frame origins and points between
    consecutive ones.
    """
    origins = np.array([arm.frame_placement(q, name)[1] for name in arm.frame_names[1:]])
    if len(origins) < 2:
        return origins
    t = np.linspace(0.0, 1.0, per_segment, endpoint=False)
    between = origins[:-1, None, :] + t[None, :, None] * (origins[1:] - origins[:-1])[:, None, :]
    return np.vstack([between.reshape(-1, 3), origins[-1:]])
