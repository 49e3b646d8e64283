"""Reading times not in seconds (ms, ns stamps) are named, not silently fitted as a weeks-long drift."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin import Samples
from ftkin.calibration.derivatives import joint_derivatives
from ftkin.exceptions import InvalidInput, InvalidSamples

ROTATIONS, WRENCHES = np.tile(np.eye(3), (3, 1, 1)), np.zeros((3, 6))


def test_nanosecond_stamps_are_refused_with_the_factor():
    with pytest.raises(InvalidSamples, match=r"nanoseconds \(divide by 1e\+09: 1200 s\)"):
        Samples(WRENCHES, ROTATIONS, [0, 1, 2], times=np.array([0.0, 6e11, 1.2e12]))


def test_epoch_seconds_are_fine_and_millisecond_stamps_warn(caplog):
    Samples(WRENCHES, ROTATIONS, [0, 1, 2], times=1.7e9 + np.array([0.0, 600.0, 1200.0]))  # ROS time in s: fine
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        Samples(WRENCHES, ROTATIONS, [0, 1, 2], times=np.array([0.0, 6e5, 1.2e6]))  # 20 min in ms: 13.9 days
    assert "look like milliseconds (divide by 1000: 1200 s)" in caplog.text


def test_a_motion_sampled_in_milliseconds_is_refused():
    times = np.arange(200) * 1.0  # 1 kHz stamps in ms
    q = np.sin(np.outer(times / 1000.0, np.ones(6)))
    with pytest.raises(InvalidInput, match="milliseconds"):
        joint_derivatives(times, q)
    smooth, velocity, _ = joint_derivatives(times / 1000.0, q)
    np.testing.assert_allclose(velocity[50:150], np.cos(np.outer(times[50:150] / 1000.0, np.ones(6))), atol=1e-6)
