"""JointAdmittance with a DynamicCompensator: the inertial wrench leaves the contact on moving
ticks.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, Compensator, InvalidInput, JointAdmittance
from ftkin.control.dynamic_compensation import DynamicCompensator
from ftkin.sim.sensor import paper_like_truth


def test_moving_ticks_remove_the_inertial_wrench_and_static_ticks_do_not(arm):
    truth = paper_like_truth()
    dynamic = DynamicCompensator(truth, arm)
    controller = JointAdmittance(arm, Admittance(k2=1e-3, frame="tool"), dynamic)
    static = Compensator(truth, arm)
    rng = np.random.default_rng(11)
    q = arm.random_configurations(1, rng, margin=0.3)[0]
    dq, ddq = rng.normal(size=6) * 1.5, rng.normal(size=6) * 8.0
    raw = truth.predict(arm.rotation_sensor_to_base(q))[0] + [0.3, -0.2, 1.0, 0.01, 0.0, -0.01]

    controller.step(q, raw, 1e-3, joint_velocities=dq, joint_accelerations=ddq)
    moving = controller.last_status.contact_wrench
    np.testing.assert_allclose(moving, dynamic.compensate_moving(q, dq, ddq, raw), atol=1e-12)
    assert (
        np.max(np.abs(moving - static.compensate(q, raw))) > 1e-3
    )  # the point-mass tool's inertia shows

    controller.step(q, raw, 1e-3)
    np.testing.assert_allclose(
        controller.last_status.contact_wrench, static.compensate(q, raw), atol=1e-12
    )

    with pytest.raises(InvalidInput):
        controller.step(q, raw, 1e-3, joint_velocities=dq, joint_accelerations=np.full(6, np.nan))


def newton_euler_sum(theta, velocity: np.ndarray, acceleration: np.ndarray) -> tuple:
    """``Y(v, a) θ`` written out on floats (minus the inertial wrench) for LOCAL ``v``, ``a``
    ``(6,)`` (hand-derived).
    """
    m = theta[0]
    hx, hy, hz = theta[1:4]
    ixx, ixy, iyy, ixz, iyz, izz = theta[4:10]
    vx, vy, vz, wx, wy, wz = velocity.tolist()
    ax, ay, az, bx, by, bz = acceleration.tolist()
    # α = a_lin + ω × v_lin
    px = ax + wy * vz - wz * vy
    py = ay + wz * vx - wx * vz
    pz = az + wx * vy - wy * vx
    # ω × h, then ω × (ω × h)
    cx, cy, cz = wy * hz - wz * hy, wz * hx - wx * hz, wx * hy - wy * hx
    # Ī ω and Ī ω̇
    lx, ly, lz = (
        ixx * wx + ixy * wy + ixz * wz,
        ixy * wx + iyy * wy + iyz * wz,
        ixz * wx + iyz * wy + izz * wz,
    )
    return (
        m * px + (by * hz - bz * hy) + (wy * cz - wz * cy),
        m * py + (bz * hx - bx * hz) + (wz * cx - wx * cz),
        m * pz + (bx * hy - by * hx) + (wx * cy - wy * cx),
        ixx * bx + ixy * by + ixz * bz + (wy * lz - wz * ly) - (py * hz - pz * hy),
        ixy * bx + iyy * by + iyz * bz + (wz * lx - wx * lz) - (pz * hx - px * hz),
        ixz * bx + iyz * by + izz * bz + (wx * ly - wy * lx) - (px * hy - py * hx),
    )


def test_one_sample_path_equals_the_written_out_newton_euler_sum(arm):
    """compensate_moving (Pinocchio's body regressor) = static contact + Y(v, a) θ written out on
    floats.
    """
    import pinocchio as pin

    truth = paper_like_truth()
    theta = np.array([0.55, 0.004, -0.002, 0.033, 2e-3, 1e-4, 2.2e-3, -1e-4, 2e-4, 1e-3])
    dynamic, static = DynamicCompensator(truth, arm, theta), Compensator(truth, arm)
    data = arm.model.createData()
    rng = np.random.default_rng(5)
    for q in arm.random_configurations(50, rng):
        dq, ddq, raw = rng.normal(size=6) * 2.0, rng.normal(size=6) * 10.0, rng.normal(size=6) * 5.0
        pin.forwardKinematics(arm.model, data, q, dq, ddq)
        velocity = pin.getFrameVelocity(arm.model, data, arm.sensor_frame_id, pin.LOCAL).vector
        acceleration = pin.getFrameAcceleration(
            arm.model, data, arm.sensor_frame_id, pin.LOCAL
        ).vector
        expected = static.compensate(q, raw) + np.array(
            newton_euler_sum(theta.tolist(), velocity, acceleration)
        )
        np.testing.assert_allclose(
            dynamic.compensate_moving(q, dq, ddq, raw), expected, rtol=0, atol=1e-12
        )
        np.testing.assert_allclose(
            dynamic.compensate_moving(q.tolist(), dq.tolist(), ddq.tolist(), raw.tolist()),
            dynamic.compensate_moving(q, dq, ddq, raw),
            rtol=1e-12,
            atol=1e-12,
        )
    for position in range(4):  # a non-finite value in any input is refused
        inputs = [q.copy(), dq.copy(), ddq.copy(), raw.copy()]
        inputs[position][position] = np.inf
        with pytest.raises(InvalidInput, match="finite"):
            dynamic.compensate_moving(*inputs)
