"""Bad input on the control paths is an ftkin error, never a TypeError or a silently ignored
argument.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, Compensator, InvalidInput, JointAdmittance
from ftkin.sim.sensor import paper_like_truth


def test_compensate_refuses_a_scalar_or_short_reading(arm):
    compensator = Compensator(paper_like_truth(), arm)
    for raw in (5.0, [1.0, 2.0, 3.0], "abc"):
        with pytest.raises(InvalidInput):
            compensator.compensate(np.zeros(arm.nq), raw)


def test_admittance_update_checks_its_inputs():
    law = Admittance(k2=1e-3)
    np.testing.assert_allclose(
        law.update([0, 0, 2.0, 0, 0, 0], 0.01), [0, 0, 2e-3, 0, 0, 0]
    )  # a list is fine
    for dt in (0.0, -0.01, float("nan"), "x"):
        with pytest.raises(InvalidInput, match="dt must be"):
            law.update(np.zeros(6), dt)
    with pytest.raises(InvalidInput):
        law.update([1.0, 2.0], 0.01)


def test_joint_velocities_need_a_dynamic_compensator(arm):
    controller = JointAdmittance(arm, Admittance(k2=1e-3), Compensator(paper_like_truth(), arm))
    q = arm.random_configurations(1, np.random.default_rng(0), margin=0.5)[0]
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(q[None]))[0]
    with pytest.raises(InvalidInput, match="DynamicCompensator only"):
        controller.step(
            q, raw, 1e-3, joint_velocities=np.zeros(arm.nq), joint_accelerations=np.zeros(arm.nq)
        )
    with pytest.raises(InvalidInput, match="go together"):
        controller.step(q, raw, 1e-3, joint_velocities=np.zeros(arm.nq))
    assert controller.step(q, raw, 1e-3).shape == (arm.nq,)
