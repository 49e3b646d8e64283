"""Excitation trajectories: at rest at the start, within limits, collision-free, better than
random.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from ftkin import InvalidInput, PoseConstraints, plan_excitation
from ftkin.planning.constraints import FeasibilityChecker


def test_planned_excitation_meets_limits_and_beats_random(arm):
    constraints = PoseConstraints(floor_height=0.15)
    kwargs = dict(
        rate=100.0,
        period=6.0,
        harmonics=3,
        acceleration_limit=6.0,
        constraints=constraints,
        candidates=3,
    )
    planned = plan_excitation(arm, 6.0, max_iterations=25, seed=0, **kwargs)
    random = plan_excitation(arm, 6.0, optimize=False, seed=0, **kwargs)
    assert planned.log_det > random.log_det
    for plan in (planned, random):
        q, dq, ddq = plan.joint_positions, plan.joint_velocities, plan.joint_accelerations
        assert q.shape == (600, arm.nq) and plan.times[1] == pytest.approx(0.01)
        np.testing.assert_allclose(dq[0], 0.0, atol=1e-12)
        np.testing.assert_allclose(ddq[0], 0.0, atol=1e-12)
        assert np.all(np.abs(dq) <= 0.5 * arm.velocity_limits + 1e-9)
        assert np.all(np.abs(ddq) <= 6.0 + 1e-9)
        # an excitation drops the poses' clearance (its hulls must not touch), as it drops the tilt
        checker = FeasibilityChecker(arm, replace(constraints, clearance=0.0))
        assert all(checker.within_bounds(row) and checker.check(row) is not None for row in q[::5])
        # Derivatives are the analytic ones (finite differences of the positions).
        np.testing.assert_allclose(
            np.gradient(q, plan.times, axis=0)[1:-1], dq[1:-1], atol=2e-3 * np.abs(dq).max()
        )
    header, rows = planned.table()
    assert header[0] == "t" and header[1:7] == arm.joint_names and rows.shape == (600, 19)


def test_excitation_refuses_bad_arguments(arm):
    with pytest.raises(InvalidInput, match="harmonics"):
        plan_excitation(arm, 5.0, harmonics=1)
    with pytest.raises(InvalidInput, match="acceleration_limit"):
        plan_excitation(arm, 5.0, acceleration_limit=-1.0)


def test_excitation_spec_and_the_keyword_shortcut_agree(arm):
    from ftkin.planning import ExcitationSpec

    spec = ExcitationSpec(4.0, rate=50.0, harmonics=3, optimize=False, seed=2)
    from_spec = plan_excitation(arm, spec)
    shortcut = plan_excitation(arm, 4.0, rate=50.0, harmonics=3, optimize=False, seed=2)
    np.testing.assert_allclose(from_spec.joint_positions, shortcut.joint_positions, atol=1e-12)
    assert from_spec.times.shape == (200,)
    with pytest.raises(InvalidInput, match="plan_excitation takes no speed"):
        plan_excitation(arm, 4.0, speed=1.0)
    with pytest.raises(InvalidInput, match="not both"):
        plan_excitation(arm, spec, seed=1)
