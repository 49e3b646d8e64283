"""Camera framing at one pose (pure numpy): occlusion test by hand, side-on views, floor rule,
distance.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.viz.framing import (
    FIELD_OF_VIEW_DEG,
    FILL,
    arm_points,
    candidate_directions,
    frame_pose,
    hidden_fractions,
)


def test_hidden_fractions_by_hand():
    arrow = np.array([[0.0, 0.0, 0.0]])
    camera = np.array([[0.0, 0.0, 1.0]])
    cases = [
        ([[0.0, 0.0, 0.5]], 1.0),  # on the line of sight, between arrow and camera
        ([[0.03, 0.0, 0.5]], 1.0),  # 3 cm off the line: within the 5 cm link radius
        ([[0.2, 0.0, 0.5]], 0.0),  # 20 cm off the line
        ([[0.0, 0.0, -0.5]], 0.0),  # behind the arrow
        ([[0.0, 0.0, 1.5]], 0.0),  # behind the camera
    ]
    for points, expected in cases:
        assert hidden_fractions(arrow, np.array(points, dtype=float), camera)[0] == expected, points
    two = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]])
    assert hidden_fractions(two, np.array([[0.0, 0.0, 0.5]]), camera)[0] == 0.5


def test_candidates_are_unit_directions_above_the_horizon():
    directions = candidate_directions()
    np.testing.assert_allclose(np.linalg.norm(directions, axis=1), 1.0)
    assert np.all(directions[:, 2] > 0.1)


def test_vertical_arrows_are_seen_from_the_side_above_the_floor_at_the_set_distance():
    origin = np.array([0.4, 0.1, 0.5])
    arrows = [[0.0, 0.0, -0.25], [0.0, 0.0, -0.25], [0.0, 0.0, 0.0]]
    view = frame_pose(origin, arrows, tool_size=0.1)
    direction = view.offset / np.linalg.norm(view.offset)
    elevation = np.degrees(np.arcsin(direction[2]))
    assert 10.0 <= elevation <= 40.0  # side-on, a little from above
    assert view.radius == pytest.approx(1.2 * 0.25)
    expected_distance = view.radius / (FILL * np.tan(np.radians(FIELD_OF_VIEW_DEG) / 2))
    assert np.linalg.norm(view.offset) == pytest.approx(expected_distance)
    assert view.floor_visible and view.position[2] > 0.0
    assert (
        direction[:2] @ origin[:2] > 0
    )  # from outside the arm (the base origin behind the sensor)
    np.testing.assert_allclose(view.right @ direction, 0.0, atol=1e-12)


def test_the_view_is_normal_to_the_plane_of_measured_and_predicted_force():
    tilt = np.radians(30.0)
    arrows = [
        [np.sin(tilt) * 0.25, 0.0, -np.cos(tilt) * 0.25],
        [0.0, 0.0, -0.25],
    ]  # both in the x-z plane
    view = frame_pose([0.0, 0.5, 0.6], arrows)
    direction = view.offset / np.linalg.norm(view.offset)
    assert abs(direction[1]) > 0.85  # along ±y, the plane's normal


def test_the_camera_avoids_the_side_where_the_arm_is():
    origin = np.array([0.5, 0.0, 0.6])
    arrows = [[0.0, 0.0, -0.25], [0.0, 0.0, -0.25]]
    free = frame_pose(origin, arrows)
    free_direction = free.offset / np.linalg.norm(free.offset)
    # A wall of arm points between the sensor and the camera the free view would take.
    centre = origin + 0.3 * free_direction
    u = np.cross(free_direction, [0.0, 0.0, 1.0])
    u /= np.linalg.norm(u)
    v = np.cross(u, free_direction)
    grid = np.linspace(-0.3, 0.3, 13)
    wall = np.array([centre + a * u + b * v for a in grid for b in grid])
    assert (
        hidden_fractions(
            origin + np.linspace(0.15, 1.0, 6)[:, None] * arrows[0], wall, free.position[None]
        )[0]
        > 0.5
    )
    blocked = frame_pose(origin, arrows, wall)
    assert blocked.hidden_fraction == 0.0
    assert (blocked.offset / np.linalg.norm(blocked.offset)) @ free_direction < 0.8


def test_the_floor_is_hidden_when_an_arrow_reaches_below_it():
    view = frame_pose([0.5, 0.0, 0.1], [[0.0, 0.0, -0.25], [0.0, 0.0, -0.25]])
    assert not view.floor_visible
    assert frame_pose([0.5, 0.0, 0.1], [[0.0, 0.0, -0.25]], floor_height=-0.5).floor_visible
    assert not frame_pose([0.5, 0.0, 0.1], [[0.0, 0.0, -0.25]], floor_height=None).floor_visible


def test_arm_points_run_along_the_chain(arm):
    q = np.array([0.3, 0.2, -0.3, 0.0, 0.2, 0.0])
    points = arm_points(arm, q)
    _, sensor = arm.frame_placement(q, "sensor")
    assert (
        np.min(np.linalg.norm(points - sensor, axis=1)) < 1e-12
    )  # the sensor origin is among them
    steps = np.linalg.norm(np.diff(points, axis=0), axis=1)
    assert steps.max() < 0.2  # no gaps wider than a link radius would cover
