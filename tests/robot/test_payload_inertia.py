"""The payload hand-off arithmetic: measured − end effector + sensor body, in the flange frame."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.exceptions import NonPhysicalPayload
from ftkin.io.payload_inertia import Payload, RigidBody, controller_load


def _steiner(mass, com, inertia_about_com):
    """Inertia about the origin, written out (parallel-axis theorem), independent of Pinocchio."""
    c = np.asarray(com, dtype=float)
    return np.asarray(inertia_about_com) + mass * (c @ c * np.eye(3) - np.outer(c, c))


def test_point_mass_difference_and_sensor_body():
    measured = Payload(1.96, np.array([0.002, -0.01, 0.067]), "fr3_link8")
    hand = RigidBody(0.73, [-0.007, 0.007, 0.03], np.diag([0.001, 0.0025, 0.0017]))
    sensor = RigidBody.point(0.25, [0.0, 0.0, -0.01])
    load = controller_load(measured, hand, sensor)
    mass = 1.96 - 0.73 + 0.25
    moment = (
        1.96 * measured.center_of_mass - 0.73 * hand.center_of_mass + 0.25 * np.array([0, 0, -0.01])
    )
    np.testing.assert_allclose(load.mass, mass, rtol=1e-12)
    np.testing.assert_allclose(load.center_of_mass, moment / mass, rtol=1e-12, atol=1e-15)
    assert load.inertia is None  # a static calibration does not see rotational inertia
    assert load.flange_frame == "fr3_link8"


def test_known_inertias_combine_as_rigid_bodies():
    tool = RigidBody(1.2, [0.02, -0.01, 0.09], np.diag([0.004, 0.005, 0.002]))
    hand = RigidBody(0.73, [-0.007, 0.007, 0.03], np.diag([0.001, 0.0025, 0.0017]))
    total_mass = tool.mass + hand.mass
    com = (tool.mass * tool.center_of_mass + hand.mass * hand.center_of_mass) / total_mass
    about_origin = _steiner(tool.mass, tool.center_of_mass, tool.inertia) + _steiner(
        hand.mass, hand.center_of_mass, hand.inertia
    )
    about_com = about_origin - total_mass * (com @ com * np.eye(3) - np.outer(com, com))
    measured = Payload(total_mass, com, "fr3_link8", about_com)
    load = controller_load(measured, hand)
    np.testing.assert_allclose(load.mass, tool.mass, rtol=1e-12)
    np.testing.assert_allclose(load.center_of_mass, tool.center_of_mass, atol=1e-12)
    np.testing.assert_allclose(load.inertia, tool.inertia, atol=1e-12)


def test_negative_mass_names_the_end_effector_setting():
    measured = Payload(0.5, np.zeros(3), "fr3_link8")
    with pytest.raises(NonPhysicalPayload, match="negative mass.*end-effector setting"):
        controller_load(measured, RigidBody.point(0.73, [0, 0, 0.03]))


def test_inertia_that_is_not_positive_is_refused():
    hand = RigidBody(0.73, [0, 0, 0.03], np.diag([0.01, 0.01, 0.01]))
    measured = Payload(1.0, np.array([0, 0, 0.03]), "fr3_link8", np.diag([0.001] * 3))
    with pytest.raises(NonPhysicalPayload, match="not positive semidefinite"):
        controller_load(measured, hand)


def test_nothing_left_is_a_zero_load_and_a_moment_without_mass_is_refused():
    hand = RigidBody.point(0.73, [0, 0, 0.03])
    zero = controller_load(Payload(0.73, np.array([0, 0, 0.03]), "f"), hand)
    assert zero.mass == 0.0 and not np.any(zero.center_of_mass)
    with pytest.raises(NonPhysicalPayload, match="no mass but a first moment"):
        controller_load(Payload(0.73, np.array([0, 0, 0.2]), "f"), hand)


def test_franka_inertia_is_column_major():
    inertia = np.array([[2.0, 0.1, 0.2], [0.1, 2.5, 0.3], [0.2, 0.3, 3.0]]) * 1e-3  # a body's
    body = RigidBody.from_franka(0.5, [0, 0, 0.1], inertia.reshape(-1, order="F"))
    np.testing.assert_allclose(body.inertia, inertia, rtol=1e-12)
    np.testing.assert_allclose(body.franka_inertia(), inertia.reshape(-1, order="F"), rtol=1e-12)


def test_bodies_refuse_what_is_not_a_body():
    import numpy as np
    import pytest

    from ftkin.exceptions import InvalidInput
    from ftkin.io.payload_export import _body
    from ftkin.io.payload_inertia import RigidBody

    with pytest.raises(InvalidInput, match="positive semidefinite"):
        RigidBody(1.0, np.zeros(3), np.diag([1e-3, 1e-3, -1e-3]))
    with pytest.raises(InvalidInput, match=r"\[mass, cx, cy, cz\]"):
        _body(0.7)
    with pytest.raises(InvalidInput, match="mass must be finite and >= 0"):
        _body([-0.2, 0.0, 0.0, 0.01])
