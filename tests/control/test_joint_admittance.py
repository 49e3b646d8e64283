"""JointAdmittance.step: Jacobian mapping, selection, damping, limits, safety."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from ftkin import Arm, Compensator
from ftkin.control.admittance import Admittance
from ftkin.control.damped_least_squares import damped_least_squares
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.exceptions import InvalidInput
from ftkin.sim.sensor import paper_like_truth

Q_DOWN = np.array([0.0, 0.0, -np.pi / 6, 0.0, -np.pi / 3, 0.0])
K2 = np.array([2e-3, 2e-3, 2e-3, 2e-2, 2e-2, 2e-2])


def _controller(arm, frame="tool", selection=1.0, compensator=True, **kwargs):
    law = Admittance(
        k2=K2, selection=selection, frame=frame, max_linear_velocity=1.0, max_angular_velocity=5.0
    )
    comp = Compensator(paper_like_truth(), arm) if compensator else None
    return JointAdmittance(arm, law, comp, **kwargs)


def _well_conditioned(arm, rng, count):
    out = []
    while len(out) < count:
        q = arm.random_configurations(1, rng, margin=0.3)[0]
        if np.prod(np.linalg.svd(arm.jacobian(q), compute_uv=False)) > 0.01:
            out.append(q)
    return out


def _raw(arm, q, contact):
    return paper_like_truth().predict(arm.rotation_sensor_to_base(q)) + contact


@pytest.mark.parametrize("frame", ["sensor", "tool", "base"])
def test_commanded_dq_produces_the_commanded_twist(arm, rng, frame):
    controller = _controller(arm, frame)
    for q in _well_conditioned(arm, rng, 5):
        dq = controller.step(q, _raw(arm, q, rng.normal(size=6)), 1e-3)
        twist = controller.last_status.twist
        if frame == "base":
            jacobian = arm.jacobian(q, "tool", "local_world_aligned")
        else:
            jacobian = arm.jacobian(q, frame, "local")
        np.testing.assert_allclose(jacobian @ dq, twist, atol=1e-10)
        controller.reset()


def test_commanded_twist_matches_finite_differences_of_forward_kinematics(arm, rng):
    controller = _controller(arm, "base")
    q = _well_conditioned(arm, rng, 1)[0]
    dq = controller.step(q, _raw(arm, q, rng.normal(size=6)), 1e-3)
    twist = controller.last_status.twist
    h = 1e-6
    rotation_0, point_0 = arm.frame_placement(q - h * dq, "tool")
    rotation_1, point_1 = arm.frame_placement(q + h * dq, "tool")
    np.testing.assert_allclose((point_1 - point_0) / (2 * h), twist[:3], atol=1e-8)
    angular = rotation_0 @ pin.log3(rotation_0.T @ rotation_1) / (2 * h)  # base axes
    np.testing.assert_allclose(angular, twist[3:], atol=1e-7)


def test_selection_zeros_leave_those_axes_still(arm, rng):
    controller = _controller(arm, "tool", selection=[0, 0, 1, 0, 0, 0])
    q = Q_DOWN + rng.normal(scale=0.05, size=6)
    dq = controller.step(q, _raw(arm, q, rng.normal(size=6)), 1e-3)
    velocity = arm.jacobian(q, "tool", "local") @ dq
    assert abs(velocity[2]) > 1e-4
    np.testing.assert_allclose(np.delete(velocity, 2), 0.0, atol=1e-12)


def test_compensation_recovers_the_contact_and_none_passes_raw_through(arm, rng):
    q = Q_DOWN
    contact = rng.normal(size=6)
    raw = _raw(arm, q, contact)
    compensated = _controller(arm)
    compensated.step(q, raw, 1e-3)
    np.testing.assert_allclose(compensated.last_status.contact_wrench, contact, atol=1e-12)
    uncompensated = _controller(arm, compensator=False)
    uncompensated.step(q, raw, 1e-3)
    np.testing.assert_array_equal(uncompensated.last_status.contact_wrench, raw)


def test_damping_grows_towards_the_wrist_singularity_and_dq_stays_bounded(arm):
    twist = np.array([0.0, 0.01, 0.0, 0.0, 0.0, 0.0])
    dampings, speeds = [], []
    for q5 in (-0.5, -0.05, -0.01, -1e-3, 0.0):
        q = np.array([0.0, 0.0, -0.5, 0.0, q5, 0.0])
        dq, manipulability, damping = damped_least_squares(arm.jacobian(q), twist)
        assert np.all(np.isfinite(dq))
        dampings.append(damping)
        speeds.append(np.linalg.norm(dq))
    assert dampings[0] == 0.0
    assert np.all(np.diff(dampings) > 0)
    assert max(speeds) < 10 * speeds[0]  # an undamped inverse blows up as 1/q5


def test_undamped_solution_is_the_exact_inverse(arm, rng):
    q = _well_conditioned(arm, rng, 1)[0]
    jacobian, twist = arm.jacobian(q), rng.normal(size=6)
    dq, _, damping = damped_least_squares(jacobian, twist)
    assert damping == 0.0
    np.testing.assert_allclose(dq, np.linalg.solve(jacobian, twist), rtol=1e-9, atol=1e-12)


def test_joint_velocity_limits_scale_uniformly(arm, rng):
    controller = _controller(arm, "base", velocity_scale=0.002)
    q = Q_DOWN + rng.normal(scale=0.05, size=6)
    contact = np.array([5.0, -5.0, 5.0, 0.5, 0.5, -0.5])
    dq = controller.step(q, _raw(arm, q, contact), 1e-3)
    status = controller.last_status
    assert status.limit_scale < 1.0
    limits = arm.velocity_limits * 0.002
    assert np.all(np.abs(dq) <= limits * (1 + 1e-12))
    assert np.isclose(np.max(np.abs(dq) / limits), 1.0)
    sensor_twist = controller.frame.twist_to_sensor_origin(
        status.twist, arm.rotation_sensor_to_base(q)
    )
    unscaled = damped_least_squares(arm.jacobian(q), sensor_twist)[0]
    np.testing.assert_allclose(dq, status.limit_scale * unscaled, rtol=1e-10)


def test_slows_to_a_stop_at_a_joint_limit(arm):
    controller = _controller(arm, "base", limit_gain=5.0)
    push = np.array(
        [20.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    )  # along sensor x = tangential: joint 1 turns positive
    upper = arm.upper_limits[0]
    speeds = []
    for distance in (0.01, 0.004, 0.001, 0.0):
        q = Q_DOWN.copy()
        q[0] = upper - distance
        controller.reset()
        dq = controller.step(q, _raw(arm, q, push), 1e-3)
        assert 0.0 <= dq[0] <= 5.0 * distance + 1e-12
        speeds.append(abs(dq[0]))
    assert speeds[-1] == 0.0 and np.all(np.diff(speeds) < 0)


def test_contact_beyond_the_limit_stops_and_latches(arm):
    controller = _controller(arm, force_limit=10.0)
    q = Q_DOWN
    dq = controller.step(q, _raw(arm, q, np.array([0, 0, 12.0, 0, 0, 0])), 1e-3)
    status = controller.last_status
    assert np.all(dq == 0.0) and status.safety_stop and "exceeded" in status.event
    dq = controller.step(q, _raw(arm, q, np.array([0, 0, 1.0, 0, 0, 0])), 1e-3)
    assert np.all(dq == 0.0) and controller.last_status.safety_stop
    controller.reset()
    dq = controller.step(q, _raw(arm, q, np.array([0, 0, 1.0, 0, 0, 0])), 1e-3)
    assert np.any(dq != 0.0) and not controller.last_status.safety_stop


@pytest.mark.parametrize(
    "q, raw, dt, match",
    [
        (np.zeros(5), np.zeros(6), 1e-3, "shape"),
        (np.zeros(6), np.zeros((1, 6)), 1e-3, "shape"),
        (np.zeros(6), ["a"] * 6, 1e-3, "numeric"),
        (np.zeros(6), np.zeros(6), None, "numeric"),
    ],
)
def test_bad_step_inputs_are_refused(arm, q, raw, dt, match):
    with pytest.raises(InvalidInput, match=match):
        _controller(arm).step(q, raw, dt)


@pytest.mark.parametrize(
    "q, raw, dt, fault",
    [
        (np.full(6, np.nan), np.zeros(6), 1e-3, "not_finite"),
        (Q_DOWN, np.zeros(6), 0.0, "dt_jump"),
    ],
)
def test_non_finite_input_and_bad_dt_hold_instead_of_raising(arm, q, raw, dt, fault):
    controller = _controller(arm)
    dq = controller.step(q, raw, dt)
    assert (
        np.all(dq == 0.0) and controller.last_status.fault == fault and controller.last_status.held
    )


def test_tool_control_point_must_be_rigid_with_the_sensor():
    arm = Arm.default(tool_frame="link3")
    with pytest.raises(InvalidInput, match="same joint"):
        JointAdmittance(arm, Admittance(frame="tool"))


def test_a_still_command_past_a_joint_limit_does_not_raise(arm):
    # regression: dq exactly 0 with a joint past its limit raised numpy's "zero-size array"
    # ValueError
    controller = JointAdmittance(
        arm, Admittance(k2=0.0, frame="tool"), Compensator(paper_like_truth(), arm)
    )
    q = Q_DOWN.copy()
    q[0] = arm.lower_limits[0] - 0.01
    dq = controller.step(q, _raw(arm, q, np.array([0.0, 0.0, 1.0, 0.0, 0.0, 0.0])), 1e-3)
    assert np.all(dq == 0.0) and controller.last_status.limit_scale == 1.0
