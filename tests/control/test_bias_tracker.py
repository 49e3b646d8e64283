"""BiasTracker: a hand-computed Kalman update, convergence, and never an update in contact, fault or fast motion."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, BiasTracker, Compensator, InvalidInput, JointAdmittance, SensorModel

SIGMA = np.array([0.03] * 3 + [0.0015] * 3)
DT = 0.01


def _feed(tracker, contacts, q=None, free=None, fault=None):
    """Feed (T, 6) contact wrenches; returns the tick indices of updates and their spans."""
    ticks, spans = [], []
    for i, contact in enumerate(contacts):
        if tracker.observe(contact, DT, q=None if q is None else q[i], free=free if not callable(free) else free(i),
                           fault=bool(fault[i]) if fault is not None else False):
            ticks.append(i)
            spans.append(tracker.last_update_span)
    return ticks, spans


def test_first_update_is_the_random_walk_posterior_of_the_used_ticks(rng):
    rate, initial = np.array([0.002] * 3 + [4e-5] * 3), np.array([0.05] * 3 + [0.001] * 3)
    tracker = BiasTracker(rate[[0, 3]], SIGMA, window=0.5, guard=0.25, initial_std=initial[[0, 3]])
    offset = np.array([0.1, -0.08, 0.05, 0.002, -0.001, 0.0015])
    contacts = offset + rng.standard_normal((120, 6)) * SIGMA
    ticks, spans = _feed(tracker, contacts)
    # 25 ticks skipped (guard after the start); at tick 100 the ticks 25..75 have 0.25 s of consistent ticks after them
    assert ticks[0] == 100 and spans[0] == 75
    tracker2 = BiasTracker(rate[[0, 3]], SIGMA, initial_std=initial[[0, 3]])
    _feed(tracker2, contacts[:101])
    # independent: Gaussian conditioning of a random walk b(t) = b(0) + q W(t) on y_j = b(t_j) + e_j, t_j = (j + 1) dt
    times = (np.arange(25, 76) + 1) * DT
    for c in range(6):
        prior = initial[c] ** 2 + rate[c] ** 2 * np.minimum.outer(times, times)
        solve = np.linalg.solve(prior + SIGMA[c] ** 2 * np.eye(len(times)), prior[-1])
        np.testing.assert_allclose(tracker2.bias[c], solve @ contacts[25:76, c], rtol=1e-9)
        variance = prior[-1, -1] - prior[-1] @ solve + rate[c] ** 2 * (101 * DT - times[-1])
        np.testing.assert_allclose(tracker2.std[c] ** 2, variance, rtol=1e-9)


def test_converges_to_the_bias_on_free_still_readings(rng):
    tracker = BiasTracker([0.002, 4e-5], SIGMA, initial_std=[0.5, 0.01])
    truth = np.array([0.3, -0.2, 0.25, 0.006, -0.004, 0.005])
    for _ in range(100):  # the caller subtracts the tracker's bias each tick, as the Compensator does
        tracker.observe(truth - tracker.bias + rng.standard_normal(6) * SIGMA, DT, free=True)
    for _ in range(2000):
        tracker.observe(truth - tracker.bias + rng.standard_normal(6) * SIGMA, DT)
    assert np.all(np.abs(tracker.bias - truth) < 5 * SIGMA / np.sqrt(50))
    assert tracker.update_count > 20


def test_never_updates_during_contact_fault_or_fast_motion(rng):
    ticks = 6000
    contact = np.zeros((ticks, 6))
    in_contact = np.zeros(ticks, bool)
    for start in range(300, ticks - 400, 900):  # ramped contacts of 0.3 s up and down, 2..10 N
        length = rng.integers(200, 500)
        force = rng.uniform(2, 10) * rng.standard_normal(3) / np.sqrt(3)
        envelope = np.minimum(1.0, np.minimum(np.arange(length) + 1, length - np.arange(length)) / 30)
        contact[start: start + length, :3] = envelope[:, None] * force
        in_contact[start: start + length] = True
    readings = contact + rng.standard_normal((ticks, 6)) * SIGMA
    tracker = BiasTracker([0.002, 4e-5], SIGMA, initial_std=[0.01, 0.0002])
    update_ticks, spans = _feed(tracker, readings)
    assert len(update_ticks) > 20
    for tick, span in zip(update_ticks, spans):
        assert not np.any(in_contact[tick - span: tick + 1])
    # declared contact, faults and fast motion: never
    for kwargs in ({"free": False}, {"fault": np.ones(ticks, bool)},
                   {"q": np.outer(np.arange(ticks) * DT * 0.5, np.ones(6)), "free": True}):
        quiet = BiasTracker([0.002, 4e-5], SIGMA)
        assert _feed(quiet, np.zeros((ticks, 6)) + 0.01, **kwargs)[0] == []
    with pytest.raises(InvalidInput):
        BiasTracker([0.002, 4e-5], [0.0, 0.1])
    with pytest.raises(InvalidInput, match="rate"):
        BiasTracker.from_calibration(SensorModel.from_tool(1.0, [0, 0, 0.05]), noise=SIGMA)


def test_plugged_into_joint_admittance(arm, rng):
    truth = SensorModel.from_tool(1.0, [0.0, 0.0, 0.05], force_offset=[0.5, -0.2, 0.1])
    believed = SensorModel.from_tool(1.0, [0.0, 0.0, 0.05], force_offset=[0.4, -0.2, 0.1])
    tracker = BiasTracker([0.002, 4e-5], SIGMA, initial_std=[0.2, 0.001])
    compensator = Compensator(believed, arm, tracker)
    controller = JointAdmittance(arm, Admittance(k2=1e-4, selection=[0, 0, 1, 0, 0, 0]), compensator)
    q = arm.random_configurations(1, np.random.default_rng(1), margin=0.5)[0]
    rotation = arm.rotation_sensor_to_base(q[None])[0]
    clean = truth.predict(rotation)
    for i in range(300):
        raw = clean + rng.standard_normal(6) * SIGMA
        if i == 150:
            raw = np.full(6, np.nan)  # a sensor fault: held, never seen by the tracker
        controller.step(q, raw, DT, free=None)
    assert tracker.update_count >= 2
    np.testing.assert_allclose(compensator.bias[:3], truth.force_offset, atol=5 * 0.03 / np.sqrt(50))
    before = tracker.update_count
    for _ in range(300):
        controller.step(q, clean + [0, 0, 5.0, 0, 0, 0] + rng.standard_normal(6) * SIGMA, DT, free=False)
    assert tracker.update_count == before
