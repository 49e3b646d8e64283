"""DynamicCompensator against MuJoCo inverse dynamics: with the true parameters the contact is
zero.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Compensator, DynamicCompensator, InvalidInput, SensorModel
from ftkin.calibration.log_cholesky import body_from_parameters

mujoco_recording = pytest.importorskip("ftkin.sim.mujoco.recording")
pytest.importorskip("mujoco")

TOOL = mujoco_recording.ToolInertia(1.5, [0.006, -0.012, 0.072], np.diag([0.006, 0.005, 0.002]))
BIAS = np.array([2.0, -1.5, 3.0, 0.1, -0.05, 0.02])
TILT = (0.005, -0.003)


@pytest.fixture(scope="module")
def setup(arm):
    recorder = mujoco_recording.MujocoRecorder(
        joint_names=arm.joint_names, tool=TOOL, base_tilt=TILT
    )
    model = SensorModel.from_tool(
        TOOL.mass, TOOL.center_of_mass, BIAS[:3], BIAS[3:], base_tilt=TILT
    )
    rng = np.random.default_rng(11)
    q = arm.random_configurations(20, rng)
    dq, ddq = rng.normal(0.0, 2.0, q.shape), rng.normal(0.0, 10.0, q.shape)
    contact = rng.normal(0.0, 1.0, (20, 6))
    raw = recorder.wrenches(q, dq, ddq) + BIAS + contact
    return DynamicCompensator(model, arm, TOOL.parameters()), model, q, dq, ddq, raw, contact


def test_contact_recovered_at_any_motion(setup, arm):
    compensator, model, q, dq, ddq, raw, contact = setup
    for i in range(len(q)):
        np.testing.assert_allclose(
            compensator.compensate_moving(q[i], dq[i], ddq[i], raw[i]), contact[i], atol=1e-9
        )
    np.testing.assert_allclose(
        compensator.compensate_trajectory(q, dq, ddq, raw), contact, atol=1e-9
    )
    # At rest it is the static compensator exactly.
    static = Compensator(model, arm)
    zeros = np.zeros(arm.nq)
    np.testing.assert_allclose(
        compensator.compensate_moving(q[0], zeros, zeros, raw[0]),
        static.compensate(q[0], raw[0]),
        rtol=1e-12,
        atol=1e-12,
    )
    # The static compensator alone misses the inertial wrench.
    assert np.abs(static.compensate(q[0], raw[0]) - contact[0]).max() > 0.5


def test_stream_has_the_documented_delay(arm):
    model = SensorModel.from_tool(TOOL.mass, TOOL.center_of_mass)
    compensator = DynamicCompensator(model, arm, TOOL.parameters())
    delay = compensator.start_stream(1e-3, window=11, polyorder=3)
    assert delay == pytest.approx(0.005)
    times = np.arange(0.0, 0.1, 1e-3)
    q = 0.3 * np.sin(np.outer(times, np.arange(1, 7)))
    raw = np.tile(np.arange(6.0), (len(times), 1))
    outputs = [compensator.compensate_stream(q_k, raw_k) for q_k, raw_k in zip(q, raw)]
    assert outputs[9] is None and outputs[10] is not None
    k = 60  # the output at tick k is for tick k − 5, with the analytic derivatives of q
    centre = times[k - 5]
    dq = 0.3 * np.arange(1, 7) * np.cos(centre * np.arange(1, 7))
    ddq = -0.3 * np.arange(1, 7) ** 2 * np.sin(centre * np.arange(1, 7))
    expected = compensator.compensate_moving(q[k - 5], dq, ddq, raw[k - 5])
    np.testing.assert_allclose(outputs[k], expected, atol=2e-3)
    # a refused sample (q not finite) enters neither buffer: the raw readings stay paired with their
    # joint angles
    varying = raw + np.arange(len(times))[:, None]  # a different reading every tick
    compensator.start_stream(1e-3, window=11, polyorder=3)
    clean = [compensator.compensate_stream(q_k, raw_k) for q_k, raw_k in zip(q, varying)]
    compensator.start_stream(1e-3, window=11, polyorder=3)
    for i, (q_k, raw_k) in enumerate(zip(q, varying)):
        if i == 30:
            with pytest.raises(InvalidInput):
                compensator.compensate_stream(np.full(6, np.nan), raw_k + 100.0)
        last = compensator.compensate_stream(q_k, raw_k)
    np.testing.assert_allclose(last, clean[-1], atol=1e-12)


def test_point_mass_without_inertia_and_errors(arm):
    model = SensorModel.from_tool(1.0, [0.0, 0.0, 0.05])
    compensator = DynamicCompensator(model, arm)
    mass, com, inertia = body_from_parameters(
        compensator.inertial_parameters + np.r_[np.zeros(4), 1e-9, 0, 1e-9, 0, 0, 1e-9]
    )
    assert mass == pytest.approx(1.0) and np.allclose(com, [0, 0, 0.05])
    with pytest.raises(InvalidInput, match="finite"):
        compensator.compensate_moving(np.zeros(6), np.full(6, np.nan), np.zeros(6), np.zeros(6))
    with pytest.raises(InvalidInput, match="shape"):
        compensator.compensate_moving(np.zeros(5), np.zeros(6), np.zeros(6), np.zeros(6))
    with pytest.raises(InvalidInput, match="start_stream"):
        compensator.compensate_stream(np.zeros(6), np.zeros(6))
