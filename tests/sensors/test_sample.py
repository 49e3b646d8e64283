"""SensorSample checks itself; the adapters' fast path builds the same sample."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput
from ftkin.sensors import SensorSample, StreamStats


def test_the_fast_path_builds_what_the_checked_constructor_builds():
    rng = np.random.default_rng(3)
    wrench, force, rate = rng.normal(size=6), rng.normal(size=3), rng.normal(size=3)
    checked = SensorSample(12.5, wrench, force, rate, 25.0)
    arrays = []
    for values in (wrench, force, rate):
        array = np.array(values, dtype=float)
        array.flags.writeable = False
        arrays.append(array)
    fast = SensorSample.trusted(12.5, *arrays, 25.0)
    for field in dataclasses.fields(SensorSample):
        np.testing.assert_array_equal(getattr(fast, field.name), getattr(checked, field.name))
    assert not checked.wrench.flags.writeable and not checked.specific_force.flags.writeable
    np.testing.assert_array_equal(checked.force, wrench[:3])
    np.testing.assert_array_equal(checked.torque, wrench[3:])
    assert checked.has_imu and not SensorSample(0.0, wrench).has_imu


def test_the_checked_constructor_copies_its_input():
    wrench = np.zeros(6)
    sample = SensorSample(1.0, wrench)
    wrench[0] = 5.0
    assert sample.wrench[0] == 0.0


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ((math.nan, np.zeros(6)), "t must be finite"),
        (("1.0", np.zeros(6)), "t must be a number"),
        ((True, np.zeros(6)), "t must be a number"),
        ((1.0, np.zeros(5)), r"wrench \[N, N·m\] must be 6 finite numbers"),
        ((1.0, [0, 0, 0, 0, 0, math.inf]), "must be 6 finite numbers"),
        ((1.0, ["a"] * 6), "must be 6 numbers"),
        ((1.0, np.zeros(6), np.zeros(2)), r"specific_force \[m/s²\] must be 3"),
        ((1.0, np.zeros(6), None, [0, math.nan, 0]), r"angular_velocity \[rad/s\]"),
        ((1.0, np.zeros(6), None, None, math.inf), r"temperature must be finite \[°C\]"),
        ((1.0, np.zeros(6), None, None, "warm"), "temperature must be a number"),
    ],
)
def test_bad_samples_are_refused_saying_what_was_expected(arguments, message):
    with pytest.raises(InvalidInput, match=message):
        SensorSample(*arguments)


def test_the_delivered_rate():
    np.testing.assert_allclose(StreamStats(1001, 0, 0, 10.0, 11.0).rate_hz, 1000.0, rtol=1e-12)
    assert StreamStats(1, 0, 0, 10.0, 10.0).rate_hz == 0.0
    assert StreamStats(0, 0, 0, None, None).rate_hz == 0.0
