"""JointAdmittance with a DynamicCompensator: the inertial wrench leaves the contact on moving ticks."""

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
    assert np.max(np.abs(moving - static.compensate(q, raw))) > 1e-3  # the point-mass tool's inertia shows

    controller.step(q, raw, 1e-3)
    np.testing.assert_allclose(controller.last_status.contact_wrench, static.compensate(q, raw), atol=1e-12)

    with pytest.raises(InvalidInput):
        controller.step(q, raw, 1e-3, joint_velocities=dq, joint_accelerations=np.full(6, np.nan))
