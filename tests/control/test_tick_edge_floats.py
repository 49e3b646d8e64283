"""``JointAdmittance.step`` over float edge cases: ``dq`` is always finite (hypothesis).

Subnormals, ±0, huge values, NaN and ±inf in ``dt``, ``q`` and the reading; a tick that cannot be
computed is a held fault (``dq = 0``), never a NaN.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from ftkin import Compensator
from ftkin.control.admittance import Admittance
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.control.sensor_faults import MIN_DT, SensorFault
from ftkin.sim.sensor import paper_like_truth

Q_DOWN = [0.0, 0.0, -math.pi / 6, 0.0, -math.pi / 3, 0.0]  # [rad]
EDGES = [0.0, -0.0, 5e-324, -5e-324, 2.2e-308, 1e-300, 1e300, -1e300, 1.7e308, -1.7e308]
EDGES += [math.nan, math.inf, -math.inf, 1e-3, -1e-3, 1.0]
edge = st.one_of(st.sampled_from(EDGES), st.floats(allow_nan=True, allow_infinity=True))


def controller(arm):
    law = Admittance(k1=1e-4, k2=[2e-3] * 3 + [2e-2] * 3, frame="tool")
    return JointAdmittance(arm, law, Compensator(paper_like_truth(), arm))


@settings(
    max_examples=300, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    dt=edge,
    joint=st.integers(0, 5),
    q_value=edge,
    channel=st.integers(0, 5),
    reading=edge,
    first_dt=st.sampled_from([1e-3, 5e-324, 1e-300]),
)
@example(dt=5e-324, joint=0, q_value=0.0, channel=0, reading=-0.86, first_dt=1e-3)  # the issue's
def test_dq_is_always_finite(arm, dt, joint, q_value, channel, reading, first_dt):
    tick = controller(arm)
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(np.array(Q_DOWN)))  # [N, N·m]
    q = list(Q_DOWN)
    tick.step(q, raw, first_dt)  # a first tick with a subnormal dt must not poison the next ones
    q[joint] = q_value
    raw = raw + [0.0, 0.0, 5.0, 0.0, 0.0, 0.0]  # a contact step: ΔF/dt is not 0/dt
    raw[channel] = reading
    dq = tick.step(q, raw, dt)
    assert np.all(np.isfinite(dq))
    steady = paper_like_truth().predict(arm.rotation_sensor_to_base(np.array(Q_DOWN)))
    assert np.all(np.isfinite(tick.step(Q_DOWN, steady, 1e-3)))  # and the next tick too


def test_a_subnormal_dt_is_a_fault(arm):
    tick = controller(arm)
    raw = paper_like_truth().predict(arm.rotation_sensor_to_base(np.array(Q_DOWN)))
    for dt in (5e-324, 1e-310, 0.0, -0.0, 0.5 * MIN_DT):
        assert not np.any(tick.step(Q_DOWN, raw, dt))
        assert tick.last_status.fault is SensorFault.DT_JUMP
        assert f"at least {MIN_DT:g} s" in tick.last_status.event
