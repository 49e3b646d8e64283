"""The admittance law and the control-frame conversions (checked against Pinocchio's SE3
actions).
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from ftkin.control.admittance import Admittance, ControlFrame
from ftkin.exceptions import InvalidInput

K1 = np.array([1e-4, 2e-4, 3e-4, 1e-3, 2e-3, 3e-3])
K2 = np.array([1e-3, 2e-3, 3e-3, 1e-2, 2e-2, 3e-2])


def test_position_and_velocity_forms_follow_the_formulas(rng):
    desired = rng.normal(size=6)
    contact = rng.normal(size=6)
    law = Admittance(
        K1, K2, desired_wrench=desired, max_linear_velocity=10.0, max_angular_velocity=10.0
    )
    error = desired + contact  # ΔF = F_desired − (−F'): the tool applies −F'
    np.testing.assert_allclose(law.displacement(contact), K1 * error, rtol=1e-14)
    np.testing.assert_allclose(law.velocity(contact), K2 * error, rtol=1e-14)


def test_gains_accept_scalars_vectors_and_diagonal_matrices():
    a, b, c = (
        Admittance(k2=0.5),
        Admittance(k2=np.full(6, 0.5)),
        Admittance(k2=np.diag(np.full(6, 0.5))),
    )
    np.testing.assert_array_equal(a.k2, b.k2)
    np.testing.assert_array_equal(a.k2, c.k2)


def test_a_held_weight_makes_the_tool_yield_along_it():
    law = Admittance(k2=1e-3, frame="base")
    weight_on_tool = np.array(
        [0.0, 0.0, -2.0, 0.0, 0.0, 0.0]
    )  # gravity pulls the tool down (base z up)
    assert law.velocity(weight_on_tool)[2] == pytest.approx(-2e-3)


def test_selection_zeros_give_zero_output_on_those_axes(rng):
    selection = np.array([0, 0, 1, 0, 1, 0])
    law = Admittance(K1, K2, selection=selection, bumpless=False)
    for _ in range(5):
        out = law.update(rng.normal(size=6), 1e-3)
        assert np.all(out[selection == 0] == 0.0)
        assert np.all(out[selection == 1] != 0.0)


def test_deadband_is_continuous_and_zero_inside():
    law = Admittance(
        k2=1.0,
        force_deadband=0.1,
        torque_deadband=0.01,
        max_linear_velocity=10,
        max_angular_velocity=10,
    )
    inside = np.array([0.09, -0.09, 0.0, 0.009, -0.009, 0.0])
    assert np.all(law.velocity(inside) == 0.0)
    outside = np.array([0.3, -0.3, 0.1, 0.05, -0.05, 0.01])
    np.testing.assert_allclose(
        law.velocity(outside), [0.2, -0.2, 0.0, 0.04, -0.04, 0.0], atol=1e-15
    )


def test_filtered_derivative_of_a_ramp_follows_the_first_order_response():
    dt, cutoff, slope = 1e-3, 5.0, 3.0  # s, Hz, N/s
    law = Admittance(
        k1=1e-3, frame="sensor", derivative_cutoff=cutoff, selection=[0, 0, 1, 0, 0, 0]
    )
    alpha = 1.0 - np.exp(
        -dt * 2 * np.pi * cutoff
    )  # the exact discretisation of the first-order low-pass
    law.update(np.zeros(6), dt)  # bumpless start at ΔF = 0
    outputs = [law.update(np.array([0, 0, slope * dt * n, 0, 0, 0]), dt)[2] for n in range(1, 301)]
    expected = 1e-3 * slope * (1 - (1 - alpha) ** np.arange(1, 301))
    np.testing.assert_allclose(outputs, expected, rtol=1e-9)


def test_combined_form_integrates_to_the_position_form_when_a_force_appears():
    """Switched on before the load (bumpless=False), K1·dΔF/dt integrates to ΔX = K1·ΔF."""
    dt = 1e-3
    law = Admittance(k1=K1, bumpless=False, max_linear_velocity=10, max_angular_velocity=10)
    wrench = np.array([1.0, -2.0, 3.0, 0.1, -0.2, 0.3])
    travelled = sum(law.update(wrench, dt) * dt for _ in range(3000))
    np.testing.assert_allclose(travelled, law.displacement(wrench), rtol=1e-6)


def test_bumpless_start_has_no_derivative_kick():
    law = Admittance(k1=K1, k2=0.0)
    assert np.all(law.update(np.full(6, 5.0), 1e-3) == 0.0)


def test_saturation_keeps_direction_and_limits_each_norm():
    law = Admittance(k2=1.0, max_linear_velocity=0.01, max_angular_velocity=0.1)
    out = law.velocity(np.array([3.0, 4.0, 0.0, 0.0, 0.3, 0.4]))
    assert np.linalg.norm(out[:3]) == pytest.approx(0.01)
    assert np.linalg.norm(out[3:]) == pytest.approx(0.1)
    np.testing.assert_allclose(out[:3] / np.linalg.norm(out[:3]), [0.6, 0.8, 0.0])
    np.testing.assert_allclose(out[3:] / np.linalg.norm(out[3:]), [0.0, 0.6, 0.8])


def test_reset_forgets_the_filter():
    law = Admittance(k1=1e-3, bumpless=False)
    first = law.update(np.ones(6), 1e-3)
    law.update(np.ones(6), 1e-3)
    law.reset()
    np.testing.assert_allclose(law.update(np.ones(6), 1e-3), first, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"k1": -1.0}, "k1 must be non-negative"),
        ({"k2": np.ones((6, 6))}, "must be diagonal"),
        ({"k2": np.ones(5)}, "6-vector"),
        ({"selection": 0.5}, "0 or 1"),
        ({"frame": "flange"}, "frame must be one of"),
        ({"derivative_cutoff": 0.0}, "derivative_cutoff"),
        ({"k2": np.nan}, "finite"),
    ],
)
def test_bad_arguments_are_refused(kwargs, match):
    with pytest.raises(InvalidInput, match=match):
        Admittance(**kwargs)


# ------------------------------------------------------------------ frames
def _random_tool(rng):
    rotation = pin.exp3(rng.normal(size=3))
    return rotation, rng.normal(scale=0.1, size=3)


def test_wrench_in_tool_frame_matches_pinocchio_force_transform(rng):
    rotation_tool_to_sensor, point = _random_tool(rng)
    frame = ControlFrame("tool", point, rotation_tool_to_sensor)
    wrench = rng.normal(size=6)
    expected = (
        pin.SE3(rotation_tool_to_sensor, point).actInv(pin.Force(wrench[:3], wrench[3:])).vector
    )
    np.testing.assert_allclose(
        frame.wrench_from_sensor(wrench, pin.exp3(rng.normal(size=3))), expected, atol=1e-14
    )


def test_wrench_in_base_axes_at_the_control_point_matches_pinocchio(rng):
    _, point = _random_tool(rng)
    rotation_sensor_to_base = pin.exp3(rng.normal(size=3))
    frame = ControlFrame("base", point)
    wrench = rng.normal(size=6)
    # The sensor frame seen from a frame at the control point with base axes.
    sensor_in_point_frame = pin.SE3(rotation_sensor_to_base, -rotation_sensor_to_base @ point)
    expected = sensor_in_point_frame.act(pin.Force(wrench[:3], wrench[3:])).vector
    np.testing.assert_allclose(
        frame.wrench_from_sensor(wrench, rotation_sensor_to_base), expected, atol=1e-14
    )


def test_sensor_frame_leaves_the_wrench_alone(rng):
    wrench = rng.normal(size=6)
    np.testing.assert_array_equal(
        ControlFrame("sensor", [1, 2, 3]).wrench_from_sensor(wrench, np.eye(3)), wrench
    )


@pytest.mark.parametrize("name", ["sensor", "tool", "base"])
def test_twist_transport_to_the_sensor_origin_matches_pinocchio(rng, name):
    rotation_tool_to_sensor, point = _random_tool(rng)
    rotation_sensor_to_base = pin.exp3(rng.normal(size=3))
    frame = ControlFrame(name, point, rotation_tool_to_sensor)
    twist = rng.normal(size=6)
    # Placement of the control frame in "sensor origin, base axes".
    point_in_base = rotation_sensor_to_base @ frame.point_in_sensor
    axes = {
        "sensor": rotation_sensor_to_base,
        "tool": rotation_sensor_to_base @ rotation_tool_to_sensor,
        "base": np.eye(3),
    }[name]
    expected = pin.SE3(axes, point_in_base).act(pin.Motion(twist[:3], twist[3:])).vector
    np.testing.assert_allclose(
        frame.twist_to_sensor_origin(twist, rotation_sensor_to_base), expected, atol=1e-14
    )


def test_moment_about_the_tool_point_by_hand():
    frame = ControlFrame("tool", [0.0, 0.0, 0.12])
    wrench = np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3])
    # M_tool = M − r × F with r × F = (−0.24, 0.12, 0).
    np.testing.assert_allclose(
        frame.wrench_from_sensor(wrench, np.eye(3)), [1, 2, 3, 0.34, 0.08, 0.3], atol=1e-15
    )


def test_control_frame_refuses_a_non_rotation():
    with pytest.raises(InvalidInput, match="rotation matrix"):
        ControlFrame("tool", [0, 0, 0.1], np.diag([1.0, 1.0, -1.0]))


def test_filter_state_reads_and_writes_arrays_and_the_update_uses_them(rng):
    law = Admittance(K1, K2, max_linear_velocity=10.0, max_angular_velocity=10.0)
    wrench, dt = rng.normal(size=6), 1e-3
    law.update(wrench, dt)
    state = law.state
    previous = state.previous_error
    np.testing.assert_array_equal(previous, wrench)  # no deadband: ΔF = F'
    previous[0] += 1.0  # a read is a copy
    np.testing.assert_array_equal(state.previous_error, wrench)
    state.previous_error = np.zeros(
        6
    )  # a write is taken by the next update: dΔF/dt = (ΔF − 0)/dt, filtered
    state.filtered_derivative = [0.0] * 6
    alpha = -np.expm1(-dt * 2.0 * np.pi * law.derivative_cutoff)
    np.testing.assert_allclose(
        law.update(wrench, dt), K1 * alpha * wrench / dt + K2 * wrench, rtol=1e-14
    )
    with pytest.raises(InvalidInput, match="shape"):
        state.previous_error = np.zeros(5)
    with pytest.raises(InvalidInput, match="finite"):
        state.filtered_derivative = np.full(6, np.nan)


@pytest.mark.parametrize("name", ["sensor", "tool", "base"])
def test_float_transports_equal_the_pinocchio_transports(rng, name):
    """The tick's float transports are the fast paths of Pinocchio's: equal to 1e-12."""
    for _ in range(20):
        rotation_tool_to_sensor, point = _random_tool(rng)
        rotation = pin.exp3(rng.normal(size=3))
        frame = ControlFrame(name, point, rotation_tool_to_sensor)
        wrench, twist = rng.normal(size=6), rng.normal(size=6)
        np.testing.assert_allclose(
            frame.wrench_floats(wrench.tolist(), rotation.tolist()),
            frame.wrench_from_sensor(wrench, rotation),
            rtol=1e-12,
            atol=1e-14,
        )
        np.testing.assert_allclose(
            frame.twist_floats(twist.tolist(), rotation.tolist()),
            frame.twist_to_sensor_origin(twist, rotation),
            rtol=1e-12,
            atol=1e-14,
        )
