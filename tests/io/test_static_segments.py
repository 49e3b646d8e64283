"""Static segments from joint trajectories with known still intervals."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput
from ftkin.io.static_segments import (
    SegmentParameters,
    StaticSegment,
    find_static_segments,
    joint_speed,
    segment_index,
)

RATE = 500.0  # [Hz]
SPEED = 0.5  # [rad/s] while moving


def trajectory(holds, rng=None, jitter=0.0, nq=3):
    """Piecewise: hold for each duration, then ramp at SPEED for 1 s. Returns times, q, still
    intervals.
    """
    times, values, still = [], [], []
    t, q = 0.0, np.zeros(nq)
    direction = np.array([1.0, -0.5, 0.25])[:nq] / 1.0
    for k, hold in enumerate(holds):
        segment_t = t + np.arange(round(hold * RATE)) / RATE
        times.append(segment_t)
        values.append(np.repeat(q[None], len(segment_t), axis=0))
        still.append((t, t + hold))
        t += hold
        if k < len(holds) - 1:
            ramp_t = t + np.arange(round(RATE)) / RATE
            times.append(ramp_t)
            values.append(q + np.outer(ramp_t - t, SPEED * direction))
            q = q + SPEED * direction
            t += 1.0
    times, values = np.concatenate(times), np.concatenate(values)
    if jitter:
        values = values + rng.normal(0, jitter, values.shape)
    return times, values, still


def test_joint_speed_on_a_ramp():
    times, q, _ = trajectory([1.0, 1.0])
    speed = joint_speed(times, q, 0.1)
    middle = (times > 1.2) & (times < 1.8)
    np.testing.assert_allclose(speed[middle], SPEED, rtol=1e-6)  # largest joint moves at SPEED
    assert np.all(speed[times < 0.9] == 0)


def test_segments_match_known_holds():
    parameters = SegmentParameters(
        speed_threshold=0.01, min_duration=1.0, settle_time=0.3, speed_window=0.1
    )
    times, q, still = trajectory([2.0, 3.0, 0.8, 2.5])
    search = find_static_segments(times, q, parameters)
    expected = [
        interval
        for interval in still
        if interval[1] - interval[0] - parameters.settle_time >= parameters.min_duration + 0.1
    ]
    assert len(search.segments) == len(expected) == 3
    assert len(search.still_stretches) == 4  # the 0.8 s hold is still but too short
    slack = parameters.speed_window / 2 + 2 / RATE
    for segment, (start, end) in zip(search.segments, expected):
        first_still = start if start == 0 else start + parameters.speed_window / 2
        assert (
            first_still + parameters.settle_time - slack
            <= segment.start
            <= first_still + parameters.settle_time + slack
        )
        assert end - slack <= segment.end <= end
        assert segment.duration >= parameters.min_duration


def test_encoder_jitter_does_not_split_segments(rng):
    """1e-4 rad jitter at 500 Hz: consecutive differences would read 0.07 rad/s; the window does
    not.
    """
    times, q, _ = trajectory([2.0, 2.0, 2.0], rng, jitter=1e-4)
    naive = np.max(np.abs(np.diff(q, axis=0)), axis=1) * RATE
    assert np.median(naive) > SegmentParameters().speed_threshold
    search = find_static_segments(times, q)
    assert len(search.segments) == 3


def test_no_segment_when_too_short_and_describe():
    times, q, _ = trajectory([1.2, 1.2])
    search = find_static_segments(times, q, SegmentParameters(min_duration=1.0, settle_time=0.5))
    assert search.segments == []
    assert "0 static segment(s) from 2 still stretch(es)" in search.describe()


def test_segment_index():
    segments = [StaticSegment(1.0, 2.0), StaticSegment(3.0, 4.0)]
    np.testing.assert_array_equal(
        segment_index([0.5, 1.0, 1.5, 2.5, 3.5, 4.0, 5.0], segments), [-1, 0, 0, -1, 1, 1, -1]
    )
    np.testing.assert_array_equal(segment_index([0.5, 1.0], []), [-1, -1])


def test_segment_index_matches_a_scan_of_every_segment(rng):
    bounds = np.sort(rng.uniform(0.0, 100.0, 40))
    segments = [StaticSegment(float(a), float(b)) for a, b in zip(bounds[::2], bounds[1::2])]
    times = np.concatenate([rng.uniform(-1.0, 101.0, 500), bounds])
    expected = np.full(len(times), -1)
    for index, segment in enumerate(segments):
        expected[(times >= segment.start) & (times <= segment.end)] = index
    np.testing.assert_array_equal(segment_index(times, segments), expected)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"speed_threshold": 0.0},
        {"min_duration": -1.0},
        {"settle_time": -0.1},
        {"speed_window": float("nan")},
        {"speed_threshold": "fast"},
        {"settle_time": None},
    ],
)
def test_parameters_validated(kwargs):
    with pytest.raises(InvalidInput):
        SegmentParameters(**kwargs)


def test_unsorted_times_and_bad_shapes():
    with pytest.raises(InvalidInput, match="sorted"):
        joint_speed([0.0, 2.0, 1.0], np.zeros((3, 2)), 0.1)
    with pytest.raises(InvalidInput, match=r"\(N, nq\)"):
        joint_speed([0.0, 1.0], np.zeros(2), 0.1)
