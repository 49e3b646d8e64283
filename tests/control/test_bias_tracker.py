"""BiasTracker: a hand-computed Kalman update, convergence, and never an update in contact, fault or
fast motion.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Admittance, Compensator, InvalidInput, JointAdmittance, SensorModel
from ftkin.control import BiasTracker

SIGMA = np.array([0.03] * 3 + [0.0015] * 3)
DT = 0.01


def _feed(tracker, contacts, q=None, free=None, fault=None):
    """Feed (T, 6) contact wrenches; returns the tick indices of updates and their spans.

    Also checks that ``last_update_ticks`` names the readings used: the span's first one up to the
    current tick at most.
    """
    ticks, spans = [], []
    for i, contact in enumerate(contacts):
        if tracker.observe(
            contact,
            DT,
            q=None if q is None else q[i],
            free=free if not callable(free) else free(i),
            fault=bool(fault[i]) if fault is not None else False,
        ):
            ticks.append(i)
            spans.append(tracker.last_update_span)
            first, last = tracker.last_update_ticks
            assert (
                tracker.tick_count - first == tracker.last_update_span
                and first <= last <= tracker.tick_count
            )
    return ticks, spans


def _used_readings(tracker, contacts, **kwargs):
    """Feed like :func:`_feed`; returns the ``(first, last)`` 0-based indices of the readings each
    update used.
    """
    used = []
    for contact in contacts:
        if tracker.observe(contact, DT, **kwargs):
            first, last = tracker.last_update_ticks
            used.append((first - 1, last - 1))
    return used


def test_first_update_is_the_random_walk_posterior_of_the_used_ticks(rng):
    rate, initial = np.array([0.002] * 3 + [4e-5] * 3), np.array([0.05] * 3 + [0.001] * 3)
    tracker = BiasTracker(rate[[0, 3]], SIGMA, window=0.5, guard=0.25, initial_std=initial[[0, 3]])
    offset = np.array([0.1, -0.08, 0.05, 0.002, -0.001, 0.0015])
    contacts = offset + rng.standard_normal((120, 6)) * SIGMA
    ticks, spans = _feed(tracker, contacts)
    # 25 ticks skipped (guard after the start); at tick 100 the ticks 25..75 have 0.25 s of
    # consistent ticks after them
    assert ticks[0] == 100 and spans[0] == 75
    tracker2 = BiasTracker(rate[[0, 3]], SIGMA, initial_std=initial[[0, 3]])
    _feed(tracker2, contacts[:101])
    # independent: Gaussian conditioning of a random walk b(t) = b(0) + q W(t) on y_j = b(t_j) +
    # e_j, t_j = (j + 1) dt
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
    for _ in range(
        100
    ):  # the caller subtracts the tracker's bias each tick, as the Compensator does
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
        envelope = np.minimum(
            1.0, np.minimum(np.arange(length) + 1, length - np.arange(length)) / 30
        )
        contact[start : start + length, :3] = envelope[:, None] * force
        in_contact[start : start + length] = True
    readings = contact + rng.standard_normal((ticks, 6)) * SIGMA
    tracker = BiasTracker([0.002, 4e-5], SIGMA, initial_std=[0.01, 0.0002])
    used = _used_readings(tracker, readings)
    assert len(used) > 20
    for first, last in used:
        assert not np.any(in_contact[first : last + 1])
    # declared contact, faults and fast motion: never
    for kwargs in (
        {"free": False},
        {"fault": np.ones(ticks, bool)},
        {"q": np.outer(np.arange(ticks) * DT * 0.5, np.ones(6)), "free": True},
    ):
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
    controller = JointAdmittance(
        arm, Admittance(k2=1e-4, selection=[0, 0, 1, 0, 0, 0]), compensator
    )
    q = arm.random_configurations(1, np.random.default_rng(1), margin=0.5)[0]
    rotation = arm.rotation_sensor_to_base(q[None])[0]
    clean = truth.predict(rotation)
    for i in range(300):
        raw = clean + rng.standard_normal(6) * SIGMA
        if i == 150:
            raw = np.full(6, np.nan)  # a sensor fault: held, never seen by the tracker
        controller.step(q, raw, DT, free=None)
    assert tracker.update_count >= 2
    np.testing.assert_allclose(
        compensator.bias[:3], truth.force_offset, atol=5 * 0.03 / np.sqrt(50)
    )
    before, contact_start = tracker.update_count, tracker.tick_count + 1
    for _ in range(300):
        controller.step(
            q, clean + [0, 0, 5.0, 0, 0, 0] + rng.standard_normal(6) * SIGMA, DT, free=False
        )
    # at most the end of the free run (readings from before the contact), nothing from the contact
    assert tracker.update_count <= before + 1 and tracker.last_update_ticks[1] < contact_start


def test_a_run_that_ends_still_uses_its_readings_older_than_the_guard(rng):
    """A contact ends a free run: the readings with ``guard`` s of consistent ones after them are
    used, not lost.
    """
    tracker = BiasTracker([0.002, 4e-5], SIGMA, window=0.5, guard=0.25, initial_std=[0.05, 0.001])
    free = rng.standard_normal((150, 6)) * SIGMA + [
        0.02,
        0,
        0,
        0,
        0,
        0,
    ]  # 1.5 s free, then a 5 N contact
    contacts = np.vstack([free, np.tile([5.0, 0, 0, 0, 0, 0], (20, 1))])
    used = []
    for raw in contacts:  # as the Compensator feeds it: the reading minus the current bias
        if tracker.observe(raw - tracker.bias, DT):
            used.append((tracker.last_update_ticks[0] - 1, tracker.last_update_ticks[1] - 1))
    # ticks 0..24 are the start guard; the run's last consistent tick is 149, so readings up to 149
    # - 25 = 124 are used
    assert used[-1][1] == 124 and used[0][0] == 25
    # independent: Gaussian conditioning of the random walk on readings 25..124 (as in the first
    # test)
    rate, initial = np.repeat([0.002, 4e-5], 3), np.repeat([0.05, 0.001], 3)
    times = (np.arange(25, 125) + 1) * DT
    for c in range(6):
        prior = initial[c] ** 2 + rate[c] ** 2 * np.minimum.outer(times, times)
        solve = np.linalg.solve(prior + SIGMA[c] ** 2 * np.eye(len(times)), prior[-1])
        np.testing.assert_allclose(tracker.bias[c], solve @ free[25:125, c], rtol=1e-9, atol=1e-15)
    # a run shorter than window + guard is thrown away whole
    short = BiasTracker([0.002, 4e-5], SIGMA, window=0.5, guard=0.25)
    assert _used_readings(short, np.vstack([free[:60], contacts[150:]])) == []
