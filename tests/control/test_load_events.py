"""LoadTracker's events: each rule tested on both sides of its k·σ threshold (noise-free readings,
the declared noise setting the bounds), pushes and noise that must not be taken for a load, and
the compensators that follow the hand."""

import math

import numpy as np
import pytest

from ftkin import Compensator, SensorModel
from ftkin.calibration.information import SensorNoise
from ftkin.control.admittance import Admittance
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.control.load_events import LoadThresholds, LoadTracker
from ftkin.exceptions import InvalidInput

GRAVITY = np.array([0.0, 0.0, -9.80665])
NOISE = SensorNoise([0.02, 0.025, 0.03], [0.002, 0.0025, 0.003])
K = 5.0
BLOCK = 6  # readings in a 5 ms block at 1 kHz: its first and its last 5 ms apart
SIGMA = NOISE.channel_std / math.sqrt(BLOCK)  # a block mean's standard deviation


def _wrench(rotation, mass, com):
    """The load's wrench by hand: f = m R_BSᵀ γ, τ = c × f."""
    force = mass * rotation.T @ GRAVITY
    return np.concatenate([force, np.cross(com, force)])


def _run(tracker, rotation, readings, start=0.0, gripper=None):
    """Tick ``readings`` ``(N, 6)`` at 1 kHz from ``start`` [s]; the labels and outputs."""
    labels, outputs = [], []
    for i, reading in enumerate(readings):
        out = tracker.tick(rotation.tolist(), reading.tolist(), start + i * 1e-3, gripper)
        labels.append(tracker.label)
        outputs.append(out)
    return labels, np.array(outputs)


def _step(tracker, rotation, before, after, gripper=None, seconds=0.3):
    """``before`` for ``seconds``, then ``after`` for ``seconds`` (constant, noise-free)."""
    count = int(seconds * 1000)
    readings = np.vstack([np.tile(before, (count, 1)), np.tile(after, (count, 1))])
    return _run(tracker, rotation, readings, gripper=gripper)


def _kinds(tracker):
    return [event.kind for event in tracker.events]


@pytest.mark.parametrize("factor, kind", [(K - 0.5, "grasp"), (K + 0.5, "contact")])
def test_a_force_across_gravity_beyond_k_sigma_is_a_contact(factor, kind):
    rotation, com = np.eye(3), np.array([0.0, 0.0, 0.06])
    load = _wrench(rotation, 0.3, com)
    load[0] += factor * SIGMA[0]  # across gravity (gravity is along −z here)
    load[3:] = np.cross(com, load[:3])  # the moment stays that of a force at the COM
    tracker = LoadTracker(NOISE, GRAVITY)
    _step(tracker, rotation, np.zeros(6), load)
    assert _kinds(tracker) == [kind]


@pytest.mark.parametrize("factor, kind", [(K - 0.5, "grasp"), (K + 0.5, "contact")])
def test_a_moment_along_the_force_beyond_k_sigma_is_a_contact(factor, kind):
    rotation = np.eye(3)
    load = _wrench(rotation, 0.3, np.array([0.01, 0.0, 0.06]))
    load[5] += factor * SIGMA[5]  # τ·ĝ ≠ 0: no COM gives it (ĝ = −z)
    tracker = LoadTracker(NOISE, GRAVITY)
    _step(tracker, rotation, np.zeros(6), load)
    assert _kinds(tracker) == [kind]


@pytest.mark.parametrize("factor, kind", [(K - 0.5, "release"), (K + 0.5, "contact")])
def test_a_release_is_the_force_back_to_the_tools_within_k_sigma(factor, kind):
    rotation = np.eye(3)
    load = _wrench(rotation, 0.4, np.array([0.0, 0.01, 0.05]))
    left = np.zeros(6)
    left[2] = factor * SIGMA[2]
    tracker = LoadTracker(NOISE, GRAVITY)
    _step(tracker, rotation, np.zeros(6), load)
    _run(tracker, rotation, np.tile(left, (300, 1)), start=0.6)
    assert _kinds(tracker) == ["grasp", kind]
    assert tracker.state == ("empty" if kind == "release" else "holding")


@pytest.mark.parametrize("mass, kind", [(0.49, "grasp"), (0.51, "tool_change")])
def test_without_a_gripper_a_mass_beyond_the_bound_is_a_tool_change(mass, kind):
    rotation = np.eye(3)
    tracker = LoadTracker(NOISE, GRAVITY, thresholds=LoadThresholds(max_load_mass=0.5))
    _, outputs = _step(tracker, rotation, np.zeros(6), _wrench(rotation, mass, [0, 0, 0.04]))
    assert _kinds(tracker) == [kind]
    assert tracker.events[0].mass == pytest.approx(mass, rel=1e-9)
    np.testing.assert_allclose(outputs[-1], 0.0, atol=1e-9)  # removed either way
    assert tracker.state == ("holding" if kind == "grasp" else "empty")


def test_the_gripper_state_decides_grasp_tool_change_and_release():
    rotation = np.eye(3)
    load = _wrench(rotation, 0.3, [0.02, 0.0, 0.05])
    opened = LoadTracker(NOISE, GRAVITY)  # a gravity step with the gripper open: the tool changed
    _, outputs = _step(opened, rotation, np.zeros(6), load, gripper=False)
    assert _kinds(opened) == ["tool_change"] and opened.state == "empty"
    # [m, m c]; m c along gravity (z here) is undetermined at one orientation: its least norm, 0
    np.testing.assert_allclose(opened.tool_offset, [0.3, 0.006, 0.0, 0.0], atol=1e-9)
    np.testing.assert_allclose(outputs[-1], 0.0, atol=1e-9)

    closed = LoadTracker(NOISE, GRAVITY)
    _step(closed, rotation, np.zeros(6), load, gripper=True)
    assert _kinds(closed) == ["grasp"]
    # set down on a surface, still in the closed gripper: a contact, the load kept
    _run(closed, rotation, np.zeros((300, 6)), start=0.6, gripper=True)
    assert _kinds(closed) == ["grasp", "contact"] and closed.state == "holding"
    _run(closed, rotation, np.zeros((300, 6)), start=0.9, gripper=False)  # the gripper opens
    assert _kinds(closed) == ["grasp", "contact", "release"] and closed.state == "empty"


def test_an_upward_force_while_empty_is_a_contact_even_with_the_gripper_open():
    """The tool resting on a surface: an upward force along gravity, a consistent moment."""
    rotation = np.eye(3)
    tracker = LoadTracker(NOISE, GRAVITY, thresholds=LoadThresholds(max_load_mass=0.1))
    _step(tracker, rotation, np.zeros(6), _wrench(rotation, -0.8, [0.0, 0.0, 0.1]), gripper=False)
    assert _kinds(tracker) == ["contact"] and "upward" in tracker.events[0].reason
    assert tracker.state == "empty" and not tracker.tool_offset.any()


def test_a_push_while_holding_is_a_contact_and_not_absorbed():
    rng = np.random.default_rng(4)
    rotation = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    load = _wrench(rotation, 0.35, np.array([0.01, 0.0, 0.07]))
    tracker = LoadTracker(NOISE, GRAVITY)
    noise = rng.normal(size=(3000, 6)) * NOISE.channel_std
    readings = np.vstack([noise[:300], load + noise[300:1500]])
    _run(tracker, rotation, readings)
    before = tracker.estimate()
    time = np.arange(600) * 1e-3
    direction = np.array([0.3, -0.8, 0.52]) / np.linalg.norm([0.3, -0.8, 0.52])
    force = np.outer(np.sin(np.pi * time / 0.6) ** 2 * 10.0, direction)
    push = np.hstack([force, np.cross([0.0, 0.0, 0.1], force)])
    labels, _ = _run(tracker, rotation, load + push + noise[1500:2100], start=1.5)
    labels_after, outputs = _run(tracker, rotation, load + noise[2100:], start=2.1)
    assert [e.kind for e in tracker.events] == ["grasp", "contact"]
    assert labels.count("contact") > 400 and labels_after[-1] == "holding"
    after = tracker.estimate()
    assert abs(after.mass - before.mass) < 3 * before.mass_std  # the push was not absorbed
    assert abs(after.mass - 0.35) < 5 * after.mass_std
    assert np.all(np.abs(outputs[-300:].mean(axis=0)) < 5 * SIGMA * math.sqrt(BLOCK / 300))


def test_noise_alone_makes_no_event_and_a_grasp_is_seen_within_50_ms():
    rng = np.random.default_rng(9)
    rotation = np.array([[1.0, 0.0, 0.0], [0.0, 0.6, -0.8], [0.0, 0.8, 0.6]])
    tracker = LoadTracker(NOISE, GRAVITY)
    _run(tracker, rotation, rng.normal(size=(20000, 6)) * NOISE.channel_std)
    assert tracker.events == [] and tracker.state == "empty"
    ramp = np.minimum(np.arange(500) / 10.0, 1.0)[:, None]  # lifted in 10 ms
    load = ramp * _wrench(rotation, 0.1, [0.0, 0.0, 0.05])
    _run(tracker, rotation, load + rng.normal(size=(500, 6)) * NOISE.channel_std, start=20.0)
    assert _kinds(tracker) == ["grasp"]
    assert tracker.events[0].time - 20.01 <= 0.05


def test_compensators_follow_the_hand(arm):
    """Compensator.compensate and JointAdmittance remove tool and load after a grasp, the tool
    alone after a release (raw readings from the calibration's own model plus a load by hand)."""
    tool = SensorModel.from_tool(0.6, [0.0, 0.01, 0.04], [1.0, -2.0, 0.5], [0.02, 0.01, -0.03])
    q = np.array([0.1, -0.3, 1.2, 0.2, -0.8, 0.4])
    rotation = arm.rotation_sensor_to_base(q[None])[0]
    gravity = tool.gravity_in_base / np.linalg.norm(tool.gravity_in_base) * tool.g
    load = 0.25 * rotation.T @ gravity
    load = np.concatenate([load, np.cross([0.0, 0.0, 0.08], load)])
    raw_empty = tool.predict(rotation[None])[0]
    compensator = Compensator(tool, arm, load=LoadTracker(NOISE, gravity))
    law = Admittance(k2=np.full(6, 1e-3), frame="tool", max_linear_velocity=1.0)
    controller = JointAdmittance(arm, law, Compensator(tool, arm, load=LoadTracker(NOISE, gravity)))
    noise = np.random.default_rng(5).normal(size=(600, 6)) * NOISE.channel_std  # not stuck
    bound = 5 * NOISE.channel_std + 5 * SIGMA  # a reading's noise and the estimate's error
    for raw in [raw_empty + n for n in noise[:200]] + [
        raw_empty + load + n for n in noise[200:400]
    ]:
        contact = compensator.compensate(q, raw)
        controller.step(q, raw, 1e-3)
    assert compensator.load.state == "holding" == controller.compensator.load.state
    assert np.all(np.abs(contact) < bound)
    assert np.all(np.abs(controller.last_status.contact_wrench) < bound)
    after_load = compensator.compensate_rotation(rotation, raw_empty)  # the load let go
    assert np.all(np.abs(after_load + load) < bound)
    for n in noise[400:]:
        contact = compensator.compensate(q, raw_empty + n)
    assert compensator.load.state == "empty"
    assert np.all(np.abs(contact) < 5 * NOISE.channel_std)
    # True builds the tracker from the calibration's noise: this one records none
    with pytest.raises(InvalidInput, match="--noise-force"):
        Compensator(tool, arm, load=True)


def test_the_tick_stays_finite_and_the_checked_path_names_bad_input():
    rng = np.random.default_rng(2)
    tracker = LoadTracker(NOISE, GRAVITY)
    for scale in (1e-12, 1.0, 1e4):
        for _ in range(400):
            rotation = np.linalg.qr(rng.normal(size=(3, 3)))[0]
            rotation *= np.linalg.det(rotation)
            out = tracker.tick(rotation.tolist(), (rng.normal(size=6) * scale).tolist())
            assert all(math.isfinite(v) for v in out)
    with pytest.raises(InvalidInput, match="gripper"):
        tracker.compensate(np.eye(3), np.zeros(6), gripper="closed")
    with pytest.raises(InvalidInput, match="time"):
        tracker.compensate(np.eye(3), np.zeros(6), time=float("nan"))
    with pytest.raises(InvalidInput):
        tracker.compensate(np.eye(3), np.zeros(5))
    with pytest.raises(InvalidInput, match="settle_blocks"):
        LoadThresholds(settle_blocks=0)
    with pytest.raises(InvalidInput, match="max_load_mass"):
        LoadThresholds(max_load_mass=-1.0)
    with pytest.raises(InvalidInput, match="k_sigma"):
        LoadThresholds(k_sigma=float("inf"))
    with pytest.raises(InvalidInput, match="period"):
        LoadTracker(NOISE, period=0)


def test_for_calibration_takes_the_noise_a_calibration_records(tool, rotations):
    """An ml calibration's noise, a linear one's residuals scaled to one reading, or advice."""
    from ftkin import calibrate
    from ftkin.sim.sensor import SimulatedSensor

    samples = SimulatedSensor(tool, NOISE).samples(rotations, np.random.default_rng(8), 50)
    ml = calibrate(samples, method="ml", noise=NOISE)
    tracker = LoadTracker.for_calibration(ml)
    np.testing.assert_allclose(tracker.noise.channel_std, ml.diagnostics.noise.channel_std)
    direction = ml.gravity_in_base / np.linalg.norm(ml.gravity_in_base)
    np.testing.assert_allclose(tracker.gravity_in_base, direction * ml.g, rtol=1e-12)
    linear = calibrate(samples, method="linear")
    # per-pose residuals of 50-reading means: about the noise over √50, scaled back by √50
    ratio = LoadTracker.for_calibration(linear).noise.channel_std / NOISE.channel_std
    assert np.all((ratio > 0.5) & (ratio < 1.6))
    # a recording's readings, when the calibration records no noise, are preferred to residuals
    rng = np.random.default_rng(3)
    readings = rng.normal(size=(3000, 6)) * NOISE.channel_std
    estimated = LoadTracker.for_calibration(linear, readings=readings).noise.channel_std
    np.testing.assert_allclose(estimated, NOISE.channel_std, rtol=0.1)
    recorded = LoadTracker.for_calibration(ml, readings=readings * 10).noise.channel_std
    np.testing.assert_allclose(recorded, ml.diagnostics.noise.channel_std)  # the fit's own first
    given = LoadTracker.for_calibration(linear, SensorNoise(0.1, 0.01))
    np.testing.assert_allclose(given.noise.channel_std, [0.1] * 3 + [0.01] * 3)
    with pytest.raises(InvalidInput, match="SensorModel"):
        LoadTracker.for_calibration("calib.json")


def test_track_load_checks_a_recording_and_labels_every_row():
    from ftkin.control.load_track import track_load

    rotations = np.tile(np.eye(3), (900, 1, 1))
    contact = np.zeros((900, 6))
    contact[300:600] = _wrench(np.eye(3), 0.2, [0.01, 0.0, 0.05])
    track = track_load(LoadTracker(NOISE, GRAVITY), rotations, contact)
    assert len(track.labels) == 900 and track.labels.count("grasp") == 1
    assert track.labels.count("release") == 1 and [e.kind for e in track.events] == [
        "grasp",
        "release",
    ]
    grasped = track.labels.index("grasp")
    np.testing.assert_allclose(track.mass[grasped:599], 0.2, rtol=1e-9)
    assert np.all(track.mass[:grasped] == 0) and np.all(np.isnan(track.com_in_sensor[:grasped]))
    # x is across gravity (determined), z along it (not, at one orientation)
    np.testing.assert_allclose(track.com_in_sensor[500, 0], 0.01, rtol=1e-9)
    assert np.isnan(track.com_in_sensor[500, 2])
    # the tick's solve has a ridge of 1e-9 of the trace (solve_still_floats)
    np.testing.assert_allclose(track.contact[grasped + 1 : 599], 0.0, atol=1e-9)
    tracker = LoadTracker(NOISE, GRAVITY)
    with pytest.raises(InvalidInput, match="900 rotations but 899 wrenches"):
        track_load(tracker, rotations, contact[:-1])
    with pytest.raises(InvalidInput, match="times must be 900 finite"):
        track_load(tracker, rotations, contact, times=np.full(900, np.nan))
    with pytest.raises(InvalidInput, match="go back"):
        track_load(tracker, rotations, contact, times=np.arange(900)[::-1] * 1e-3)
    with pytest.raises(InvalidInput, match="gripper must be 900 booleans"):
        track_load(tracker, rotations, contact, gripper=np.ones(900))
    with pytest.raises(InvalidInput, match="contact_wrenches"):
        track_load(tracker, rotations, np.full((900, 6), np.inf))


@pytest.mark.parametrize("factor, kind", [(K - 0.5, "grasp"), (K + 0.5, "contact")])
def test_a_step_still_changing_beyond_k_sigma_between_blocks_is_a_contact(factor, kind):
    """Consecutive block means of a ramp differ by its slope times a block's 6 ms: within
    k √(2σ²/n) the step has settled (a gravity load), beyond it it is still changing."""
    rotation = np.eye(3)
    change = factor * math.sqrt(2.0) * SIGMA[2]  # [N] between consecutive block means
    per_tick = change / BLOCK
    readings = np.zeros((400, 6))
    readings[100:, 2] = -(np.arange(300) + 1) * per_tick  # a force growing along gravity (−z)
    tracker = LoadTracker(NOISE, GRAVITY)
    _run(tracker, rotation, readings)
    assert _kinds(tracker)[:1] == [kind]


def test_the_noise_of_a_recording_is_estimated_through_its_steps_and_motion():
    from ftkin.control.load_events import noise_from_readings

    rng = np.random.default_rng(21)
    time = np.arange(20000) * 1e-3
    slow = np.outer(np.sin(2 * np.pi * 0.5 * time), [1.0, -2.0, 0.5, 0.05, 0.02, -0.03])
    steps = np.outer((time > 5) & (time < 12), [3.0, 0.0, -6.0, 0.2, 0.1, 0.0])
    readings = slow + steps + rng.normal(size=(len(time), 6)) * NOISE.channel_std
    estimate = noise_from_readings(readings)
    np.testing.assert_allclose(estimate.channel_std, NOISE.channel_std, rtol=0.05)
    constant = noise_from_readings(np.ones((10, 6)))  # a channel that never changes: the floor
    assert np.all(constant.channel_std > 0)
    with pytest.raises(InvalidInput, match="at least 3 readings"):
        noise_from_readings(np.zeros((2, 6)))
    with pytest.raises(InvalidInput, match="readings"):
        noise_from_readings(np.full((5, 6), np.nan))
