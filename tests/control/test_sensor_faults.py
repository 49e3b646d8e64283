"""Sensor faults in JointAdmittance.step: hold (dq = 0), report, keep the state clean, recover."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Compensator
from ftkin.calibration.information import SensorNoise
from ftkin.control.admittance import Admittance
from ftkin.control.joint_admittance import JointAdmittance
from ftkin.control.sensor_faults import FaultMonitor, SensorFault, SensorLimits
from ftkin.exceptions import InvalidInput
from ftkin.sim.sensor import SimulatedSensor, paper_like_truth

Q_DOWN = np.array([0.0, 0.0, -np.pi / 6, 0.0, -np.pi / 3, 0.0])
CONTACT = np.array([1.0, -0.5, 3.0, 0.05, -0.02, 0.01])  # [N, N·m], sensor frame
DT = 1e-3


def _controller(arm, force_limit=50.0, torque_limit=5.0, **limits):
    law = Admittance(
        k1=2e-4, k2=[2e-3] * 3 + [2e-2] * 3, frame="tool", force_deadband=0.02, bumpless=True
    )
    return JointAdmittance(
        arm,
        law,
        Compensator(paper_like_truth(), arm),
        force_limit=force_limit,
        torque_limit=torque_limit,
        sensor_limits=SensorLimits(**limits),
    )


def _readings(arm, rng, count, q=Q_DOWN, contact=CONTACT):
    """Noisy raw readings ``(count, 6)`` at ``q`` with the paper's noise."""
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise.paper())
    rotations = np.repeat(arm.rotation_sensor_to_base(q)[None], count, axis=0)
    return sensor.read(rotations, rng, contact)


def _nan_raw(q, raw, dt):
    raw = raw.copy()
    raw[2] = np.nan
    return q, raw, dt


def _inf_raw(q, raw, dt):
    raw = raw.copy()
    raw[4] = -np.inf
    return q, raw, dt


def _nan_q(q, raw, dt):
    q = q.copy()
    q[3] = np.nan
    return q, raw, dt


FAULTS = {
    "nan raw": (_nan_raw, SensorFault.NOT_FINITE),
    "inf raw": (_inf_raw, SensorFault.NOT_FINITE),
    "nan q": (_nan_q, SensorFault.NOT_FINITE),
    "dt jump": (lambda q, raw, dt: (q, raw, 20 * dt), SensorFault.DT_JUMP),
    "dt zero": (lambda q, raw, dt: (q, raw, 0.0), SensorFault.DT_JUMP),
    "dt negative": (lambda q, raw, dt: (q, raw, -dt), SensorFault.DT_JUMP),
    "dt nan": (lambda q, raw, dt: (q, raw, float("nan")), SensorFault.DT_JUMP),
    "saturated fz": (
        lambda q, raw, dt: (q, raw + [0, 0, 300.0, 0, 0, 0], dt),
        SensorFault.SATURATED,
    ),
}


@pytest.mark.parametrize("name", sorted(FAULTS))
def test_a_faulty_tick_holds_then_the_arm_recovers_like_a_fresh_controller(arm, rng, name):
    inject, expected = FAULTS[name]
    controller, fresh = _controller(arm, recovery_ticks=4), _controller(arm, recovery_ticks=4)
    raws = _readings(arm, rng, 40)
    for raw in raws[:20]:
        assert np.any(controller.step(Q_DOWN, raw, DT) != 0.0)
    dq = controller.step(*inject(Q_DOWN, raws[20], DT))
    status = controller.last_status
    assert (
        np.all(dq == 0.0) and status.fault is expected and status.held and "holding" in status.event
    )
    assert not status.safety_stop and np.all(np.isnan(status.contact_wrench))
    for raw in raws[21:24]:  # recovery_ticks - 1 good ticks: still held, reported as recovering
        assert np.all(controller.step(Q_DOWN, raw, DT) == 0.0)
        assert (
            controller.last_status.fault is expected
            and "recovering" in controller.last_status.event
        )
    for raw in raws[
        24:
    ]:  # from here on: the derivative restarted, the same as a controller started now
        dq, dq_fresh = controller.step(Q_DOWN, raw, DT), fresh.step(Q_DOWN, raw, DT)
        assert controller.last_status.fault is SensorFault.NONE and not controller.last_status.held
        np.testing.assert_allclose(dq, dq_fresh, rtol=1e-12, atol=1e-15)
        assert np.any(dq != 0.0)
    state = controller.admittance.state
    assert np.all(np.isfinite(state.previous_error)) and np.all(
        np.isfinite(state.filtered_derivative)
    )


@pytest.mark.parametrize("channel", range(6))
@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_saturation_on_each_channel(arm, rng, channel, sign):
    limits = np.array([250.0, 250.0, 250.0, 6.0, 6.0, 6.0])
    controller = _controller(arm, recovery_ticks=1)
    raws = _readings(arm, rng, 3)
    controller.step(Q_DOWN, raws[0], DT)
    inside = raws[1].copy()
    inside[channel] = sign * limits[channel] * 0.999
    controller.step(Q_DOWN, inside, DT)
    assert controller.last_status.fault is not SensorFault.SATURATED
    controller.reset()
    beyond = raws[1].copy()
    beyond[channel] = sign * limits[channel]
    assert np.all(controller.step(Q_DOWN, beyond, DT) == 0.0)
    assert (
        controller.last_status.fault is SensorFault.SATURATED
        and f"channel {channel}" in controller.last_status.event
    )
    assert np.any(
        controller.step(Q_DOWN, raws[2], DT) != 0.0
    )  # recovery_ticks=1: the first good tick moves


def test_per_channel_ranges_and_disabled_checks(arm, rng):
    raws = _readings(arm, rng, 30)
    loud = raws[0] + [0.0, 0.0, 0.0, 0.0, 0.0, 2.0]  # mz ≈ 2 N·m: beyond a 1.5 N·m range on z only
    narrow = _controller(arm, torque_range=[6.0, 6.0, 1.5], force_limit=1e3, torque_limit=1e3)
    narrow.step(Q_DOWN, loud, DT)
    assert narrow.last_status.fault is SensorFault.SATURATED
    off = _controller(
        arm,
        force_range=None,
        torque_range=None,
        stuck_ticks=None,
        stuck_time=None,
        dt_ratio=None,
        force_limit=1e3,
        torque_limit=1e3,
    )
    for raw in (raws[0] + [300.0, 0, 0, 0, 0, 0], *[raws[1]] * 20):
        assert np.all(np.isfinite(off.step(Q_DOWN, raw, DT)))
        assert off.last_status.fault is SensorFault.NONE
    off.step(Q_DOWN, raws[2], 1.0)  # a 1000x dt: not checked
    assert off.last_status.fault is SensorFault.NONE
    off.step(Q_DOWN, raws[3], 0.0)  # but dt <= 0 always is
    assert off.last_status.fault is SensorFault.DT_JUMP


def test_stuck_sensor_is_detected_after_k_repeats_and_recovers_on_new_readings(arm, rng):
    controller = _controller(arm, stuck_ticks=10, stuck_time=None, recovery_ticks=2)
    raws = _readings(arm, rng, 20)
    for raw in raws[:5]:
        controller.step(Q_DOWN, raw, DT)
    frozen = raws[5]
    faults = []
    for _ in range(15):  # the same reading 15 times: ticks 11..15 (10 repeats and more) are stuck
        dq = controller.step(Q_DOWN, frozen, DT)
        faults.append(controller.last_status.fault)
        assert np.all(np.isfinite(dq))
    assert faults[:10] == [SensorFault.NONE] * 10 and faults[10:] == [SensorFault.STUCK] * 5
    assert np.all(dq == 0.0) and "unchanged for 15 ticks" in controller.last_status.event
    controller.step(Q_DOWN, raws[6], DT)
    assert (
        controller.last_status.fault is SensorFault.STUCK
        and "recovering" in controller.last_status.event
    )
    assert np.any(controller.step(Q_DOWN, raws[7], DT) != 0.0)


def test_stuck_time_triggers_in_a_slow_loop(arm, rng):
    controller = _controller(arm, stuck_ticks=None, stuck_time=0.05)
    raw = _readings(arm, rng, 1)[0]
    faults = [
        (controller.step(Q_DOWN, raw, 0.01), controller.last_status.fault)[1] for _ in range(8)
    ]
    # 10 ms ticks: 5 repeats = 0.05 s is not more than 0.05 s; the 6th repeat (7th reading) is
    assert faults == [SensorFault.NONE] * 6 + [SensorFault.STUCK] * 2


@pytest.mark.parametrize("resolution", [None, (1 / 16, 1 / 1000)])
def test_stuck_detection_does_not_false_trigger_on_a_noisy_sensor(arm, rng, resolution):
    """20,000 ticks of paper noise, raw and quantized like a 16-bit sensor (1/16 N, 1 mN·m
    counts).
    """
    controller = _controller(arm)
    raws = _readings(arm, rng, 20_000)
    if resolution is not None:
        step = np.repeat(resolution, 3)
        raws = np.round(raws / step) * step
        assert (
            np.mean(np.all(raws[1:] == raws[:-1], axis=1)) > 0
        )  # quantization does repeat some readings
    for raw in raws:
        controller.step(Q_DOWN, raw, DT)
        assert controller.last_status.fault is SensorFault.NONE
    assert sum(controller.monitor.counts.values()) == 0


def test_learned_dt_follows_a_lasting_rate_change_and_a_fixed_one_does_not(arm, rng):
    raws = _readings(arm, rng, 300)
    learned, fixed = (
        _controller(arm, recovery_ticks=1),
        _controller(arm, recovery_ticks=1, nominal_dt=DT),
    )
    for controller in (learned, fixed):
        for raw in raws[:100]:
            controller.step(Q_DOWN, raw, DT)
    slow = [[], []]
    for raw in raws[100:]:  # the loop drops to 100 Hz for good
        for faults, controller in zip(slow, (learned, fixed)):
            controller.step(Q_DOWN, raw, 10 * DT)
            faults.append(controller.last_status.fault)
    # the running average grows at most (dt_ratio - 1)·alpha = 4% per tick: 1 ms → 2 ms in ~18 ticks
    assert slow[0][0] is SensorFault.DT_JUMP and set(slow[0][30:]) == {SensorFault.NONE}
    assert set(slow[1]) == {SensorFault.DT_JUMP}


def test_no_nan_or_exception_under_random_faults(arm, rng):
    """A seeded storm of good and bad ticks: dq always finite, the filter state always finite."""
    controller = _controller(arm, recovery_ticks=2)
    raws = _readings(arm, rng, 3000)
    bad_values = (np.nan, np.inf, -np.inf, 1e300, -1e300, 0.0)
    held = 0
    for raw in raws:
        q, dt = Q_DOWN + rng.normal(scale=0.01, size=6), DT
        kind = rng.integers(8)
        if kind == 0:
            raw = raw.copy()
            raw[rng.integers(6)] = bad_values[rng.integers(len(bad_values))]
        elif kind == 1:
            q[rng.integers(6)] = bad_values[rng.integers(3)]
        elif kind == 2:
            dt = (0.0, -DT, np.nan, np.inf, 0.5)[rng.integers(5)]
        dq = controller.step(q, raw, dt)
        assert dq.shape == (6,) and np.all(np.isfinite(dq))
        held += controller.last_status.held
        state = controller.admittance.state
        assert np.all(np.isfinite(state.previous_error)) and np.all(
            np.isfinite(state.filtered_derivative)
        )
    assert 0 < held < len(raws) and not controller.safety_latched


def test_faults_do_not_clear_a_latched_safety_stop(arm, rng):
    controller = _controller(arm, force_limit=10.0, recovery_ticks=1)
    raws = _readings(arm, rng, 4)
    controller.step(Q_DOWN, raws[0] + [0, 0, 20.0, 0, 0, 0], DT)
    assert controller.safety_latched
    controller.step(*_nan_raw(Q_DOWN, raws[1], DT))
    assert (
        controller.last_status.fault is SensorFault.NOT_FINITE
        and controller.last_status.safety_stop
    )
    assert (
        np.all(controller.step(Q_DOWN, raws[2], DT) == 0.0) and controller.last_status.safety_stop
    )
    controller.reset()
    assert np.any(controller.step(Q_DOWN, raws[3], DT) != 0.0)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"force_range": -1.0}, "force_range"),
        ({"torque_range": [1.0, 2.0]}, "torque_range"),
        ({"force_range": "big"}, "force_range"),
        ({"stuck_ticks": 0}, "stuck_ticks"),
        ({"stuck_ticks": 2.5}, "stuck_ticks"),
        ({"stuck_time": float("nan")}, "stuck_time"),
        ({"dt_ratio": 1.0}, "dt_ratio"),
        ({"nominal_dt": 0.0}, "nominal_dt"),
        ({"recovery_ticks": 0}, "recovery_ticks"),
        ({"stuck_time": "long"}, "stuck_time"),  # regression: a TypeError leaked
        (
            {"recovery_ticks": "5"},
            "recovery_ticks",
        ),  # regression: a ValueError leaked / a str slipped through
        ({"stuck_ticks": float("inf")}, "stuck_ticks"),
    ],
)
def test_bad_limits_are_refused(kwargs, match):
    with pytest.raises(InvalidInput, match=match):
        SensorLimits(**kwargs)


def test_monitor_refuses_other_limits_objects():
    with pytest.raises(InvalidInput, match="SensorLimits"):
        FaultMonitor({"force_range": 1.0})


def test_monitor_check_takes_an_array_reading_and_refuses_a_wrong_shape():
    monitor = FaultMonitor()
    # regression: an array reading raised numpy's "truth value of an array is ambiguous"
    for _ in range(3):
        assert monitor.check(np.zeros(6), np.array([1.0, 2.0, 3.0, 0.1, 0.2, 0.3]), DT) == (
            SensorFault.NONE,
            "",
        )
    assert (
        monitor.check(np.zeros(6), np.array([np.nan, 0, 0, 0, 0, 0]), DT)[0]
        is SensorFault.NOT_FINITE
    )
    with pytest.raises(InvalidInput, match=r"shape \(6,\)"):
        monitor.check(np.zeros(6), np.zeros(5), DT)
