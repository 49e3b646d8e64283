"""Savitzky–Golay joint derivatives: zero-phase offline, known delay online."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import InvalidInput
from ftkin.calibration.derivatives import CausalDifferentiator, joint_derivatives


def _trajectory(times):
    # Two joints, analytic derivatives (a smooth periodic motion).
    q = np.column_stack([0.5 * np.sin(2.0 * times), 0.3 * np.cos(3.0 * times) + 0.1])
    dq = np.column_stack([1.0 * np.cos(2.0 * times), -0.9 * np.sin(3.0 * times)])
    ddq = np.column_stack([-2.0 * np.sin(2.0 * times), -2.7 * np.cos(3.0 * times)])
    return q, dq, ddq


def test_offline_derivatives_are_zero_phase_and_accurate():
    times = np.arange(0.0, 3.0, 1e-3)
    q, dq, ddq = _trajectory(times)
    rng = np.random.default_rng(0)
    smooth, velocity, acceleration = joint_derivatives(times, q + rng.normal(0.0, 1e-6, q.shape))
    inner = slice(100, -100)
    np.testing.assert_allclose(velocity[inner], dq[inner], atol=2e-3)
    np.testing.assert_allclose(acceleration[inner], ddq[inner], atol=0.08)
    np.testing.assert_allclose(smooth[inner], q[inner], atol=1e-5)
    # Zero phase: no lag (the error is not correlated with the derivative's own slope).
    lag = np.sum((velocity - dq)[inner] * ddq[inner]) / np.sum(ddq[inner] ** 2)
    assert abs(lag) < 1e-5


def test_causal_differentiator_equals_offline_delayed():
    times = np.arange(0.0, 0.5, 1e-3)
    q, _, _ = _trajectory(times)
    online = CausalDifferentiator(2, 1e-3, window=21, polyorder=3)
    assert online.delay == pytest.approx(0.010)
    outputs = [online.update(row) for row in q]
    assert all(out is None for out in outputs[:20])
    _, velocity, acceleration = joint_derivatives(times, q, window=21, polyorder=3)
    for k in (20, 100, 400):
        _, dq_k, ddq_k = outputs[k]
        np.testing.assert_allclose(dq_k, velocity[k - 10], atol=1e-9)
        np.testing.assert_allclose(ddq_k, acceleration[k - 10], atol=1e-6)


def test_derivatives_refuse_nonuniform_times():
    times = np.array([0.0, 0.001, 0.002, 0.0045, 0.005, 0.006])
    with pytest.raises(InvalidInput, match="uniformly"):
        joint_derivatives(times, np.zeros((6, 2)), window=5, polyorder=2)
