"""The oscillation detector on synthetic signals, and inside JointAdmittance."""

from __future__ import annotations

import math
import timeit

import numpy as np
import pytest

from ftkin import InvalidInput
from ftkin.control import Admittance, Compensator, JointAdmittance, SensorFault, SensorLimits
from ftkin.control.oscillation import OscillationDetector, OscillationLimits
from ftkin.kinematics.arm import Arm, bundled_urdf_path
from ftkin.sim.sensor import paper_like_truth

DT = 1e-3


def _first_trip(signal, dt=DT, limits=None):
    detector = OscillationDetector(limits)
    for i, value in enumerate(signal):
        if detector.update(float(value), 0.0, dt):
            return i * dt
    return math.inf


def test_noise_an_impact_and_a_slow_wobble_do_not_trip():
    rng = np.random.default_rng(0)
    t = np.arange(20000) * DT
    noise = 2.2 + rng.normal(0, 0.02, t.size)  # the paper's sensor noise on a held weight
    assert _first_trip(noise) == math.inf
    impact = noise + np.where(
        t > 1.0, 8.0 * np.exp(-(t - 1.0) / 0.02) * np.cos(2 * np.pi * 20 * (t - 1.0)), 0.0
    )
    assert (
        _first_trip(impact) == math.inf
    )  # a damped ring-down after touching: a few reversals, then quiet
    wobble = noise + 3.0 * np.sin(
        2 * np.pi * 5 * t
    )  # a slow, large swing (someone pushing by hand)
    assert _first_trip(wobble) == math.inf


@pytest.mark.parametrize("frequency", [40.0, 125.0, 333.0])
def test_a_chattering_force_trips_within_a_window(frequency):
    rng = np.random.default_rng(1)
    t = np.arange(2000) * DT
    chatter = np.abs(2.0 * np.sin(2 * np.pi * frequency * t)) * (t > 0.5) + rng.normal(
        0, 0.02, t.size
    )
    trip = _first_trip(chatter)
    assert 0.5 < trip < 0.5 + 0.15


def test_limits_are_checked():
    with pytest.raises(InvalidInput, match="OscillationLimits"):
        OscillationLimits(force_step=0.0)
    with pytest.raises(InvalidInput, match="OscillationLimits"):
        OscillationLimits(reversals=1)


def test_joint_admittance_holds_on_oscillation_and_names_the_gain(arm):
    truth = paper_like_truth()
    controller = JointAdmittance(
        arm, Admittance(k1=2e-4, k2=1e-4, frame="tool"), Compensator(truth, arm)
    )
    q = np.array([0.0, 0.0, -np.pi / 6, 0.0, -np.pi / 3, 0.0])
    unloaded = truth.predict(arm.rotation_sensor_to_base(q)).ravel()
    for i in range(300):  # the contact force jumps 0 <-> 3 N every other tick: a chattering contact
        raw = unloaded + np.array([0.0, 0.0, 3.0 * (i % 2), 0.0, 0.0, 0.0])
        dq = controller.step(q, raw, DT)
        if controller.last_status.fault is SensorFault.OSCILLATION:
            break
    status = controller.last_status
    assert status.fault is SensorFault.OSCILLATION and status.held and np.all(dq == 0.0)
    assert "lower k1" in status.event and i * DT < 0.05
    assert np.isfinite(status.contact_wrench).all()
    controller.step(q, unloaded, DT)  # latched
    assert controller.last_status.fault is SensorFault.OSCILLATION
    controller.reset()
    controller.step(q, unloaded, DT)
    assert controller.last_status.fault is SensorFault.NONE


def test_detector_costs_well_under_a_microsecond_per_tick():
    detector = OscillationDetector()
    calls = 20000
    seconds = (
        min(timeit.repeat(lambda: detector.update(2.2, 0.1, DT), number=calls, repeat=5)) / calls
    )
    assert seconds < 2e-6  # generous for a loaded machine; the benchmark prints the figure


def test_sensor_range_is_required_for_other_arms(tmp_path):
    copy = tmp_path / "my_arm.urdf"
    copy.write_text(bundled_urdf_path().read_text())
    other = Arm.from_urdf(copy, "ft_sensor", "tool")
    with pytest.raises(InvalidInput, match="measuring range"):
        JointAdmittance(other, Admittance(frame="tool"))
    JointAdmittance(
        other,
        Admittance(frame="tool"),
        sensor_limits=SensorLimits(force_range=100.0, torque_range=4.0),
    )


def test_incremental_counts_and_energy_equal_a_direct_recomputation():
    """The detector's O(1) per-tick update against the sums of its docstring, recomputed in
    numpy.
    """
    rng = np.random.default_rng(3)
    n, limits = 400, OscillationLimits()
    t = np.arange(n) * DT
    force = 5.0 + 1.5 * np.sin(2 * np.pi * 60 * t) + rng.normal(0.0, 0.3, n)
    torque = np.abs(0.2 + rng.normal(0.0, 0.05, n))
    dts = np.where(np.arange(n) % 7 == 3, 1.2 * DT, DT)  # a second dt exercises the cached decay
    detector, counts, energies = OscillationDetector(limits), [], []
    for f, m, dt in zip(force, torque, dts):
        detector.update(float(f), float(m), float(dt))
        counts.append(detector.count)
        energies.append(detector.energy)
    steps = np.diff(force + torque / limits.lever)  # δ for ticks 1..n-1
    decays = np.exp(-dts[1:] / limits.window)
    log_decay = np.cumsum(np.log(decays))  # Π d over ticks (k, m] = exp(L[m] − L[k])
    previous = np.concatenate([[0.0], steps[:-1]])
    reversal = steps * previous < 0.0
    starts = np.flatnonzero(reversal)
    swing_start = np.concatenate(
        [[0], starts]
    )  # a swing runs from one reversal (inclusive) to the next (exclusive)
    large = np.zeros(len(steps), dtype=bool)
    for begin, end in zip(swing_start[:-1], starts):
        large[end] = abs(steps[begin:end].sum()) > limits.force_step
    for m in range(len(steps)):
        weights = np.exp(log_decay[m] - log_decay[: m + 1])
        expected_count = weights[: m + 1][large[: m + 1]].sum()
        expected_energy = np.sum(weights * (1.0 - decays[: m + 1]) * steps[: m + 1] ** 2)
        assert counts[m + 1] == pytest.approx(expected_count, rel=1e-12, abs=1e-12)
        assert energies[m + 1] == pytest.approx(expected_energy, rel=1e-12, abs=1e-12)
    assert counts[0] == 0.0 and energies[0] == 0.0 and max(counts) > limits.reversals / 2
