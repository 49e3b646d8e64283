"""The record of a live run (ftkin.robot.live_log): samples missed from the stamps, the settling
after connect, the log written as it comes; stamps and rows made by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ftkin import InvalidInput
from ftkin.robot.live_log import SampleLog, missed_packages, settle

PERIOD = 0.002  # [s], 500 Hz


def _stamps(steps_in_periods) -> np.ndarray:
    """Stamps [s] from 100 s on, 40 regular steps then the given ones (in periods)."""
    steps = np.concatenate([np.ones(40), steps_in_periods]) * PERIOD
    return 100.0 + np.concatenate([[0.0], np.cumsum(steps)])


@pytest.mark.parametrize(
    ("steps", "missed"),
    [
        ([], 0),
        ([1.49], 0),  # jitter: one period
        ([1.51], 1),  # two periods: one sample missed
        ([3.0], 2),
        ([3.0, 1.0, 5.0], 6),
    ],
)
def test_a_step_of_k_periods_misses_k_minus_one_samples(steps, missed):
    count, period = missed_packages(_stamps(steps))
    assert count == missed
    assert period == pytest.approx(PERIOD, rel=1e-9)


def test_too_few_or_still_stamps_count_nothing():
    assert missed_packages([5.0])[0] == 0 and math.isnan(missed_packages([5.0])[1])
    assert missed_packages([5.0, 5.0, 5.0]) == (0, 0.0)


def test_settle_skips_until_the_stamps_step_by_one_period():
    # three late steps (the queue worked off), then regular ones
    stamps = np.concatenate([[0.0], np.cumsum([0.006, 0.004, 0.010, *[PERIOD] * 40])])
    stream = iter([(t, None, None) for t in stamps])
    settle(stream, steady=25, limit=60.0)
    # consumed: the first sample, the three late steps, then 25 steps of one period
    assert next(stream)[0] == pytest.approx(stamps[1 + 3 + 25], abs=1e-12)
    short = iter([(t, None, None) for t in stamps[:10]])
    settle(short, steady=25, limit=60.0)  # the stream ends first: nothing left, no error
    assert next(short, None) is None


def test_the_log_holds_every_sample_and_never_overwrites(tmp_path):
    path = tmp_path / "live.csv"
    log = SampleLog(path, ["j1", "j2"])
    rows = [(100.0 + 0.002 * i, np.array([0.1 * i, -0.2]), np.arange(6.0) + i) for i in range(300)]
    for stamp, q, contact in rows:
        log.add(stamp, q, contact)
    log.close()
    lines = path.read_text().splitlines()
    assert lines[0] == "t,j1,j2,fx,fy,fz,mx,my,mz" and len(lines) == 301
    np.testing.assert_array_equal(
        np.loadtxt(path, delimiter=",", skiprows=1),
        [[stamp, *q, *contact] for stamp, q, contact in rows],
    )
    with pytest.raises(InvalidInput, match="exists: ftkin never overwrites a file"):
        SampleLog(path, ["j1", "j2"])
    assert len(path.read_text().splitlines()) == 301
