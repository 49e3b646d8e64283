"""Reading times not in seconds (ms, ns stamps) are named, not silently fitted as a weeks-long
drift.
"""

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
    Samples(
        WRENCHES, ROTATIONS, [0, 1, 2], times=1.7e9 + np.array([0.0, 600.0, 1200.0])
    )  # ROS time in s: fine
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        Samples(
            WRENCHES, ROTATIONS, [0, 1, 2], times=np.array([0.0, 6e5, 1.2e6])
        )  # 20 min in ms: 13.9 days
    assert "look like milliseconds (divide by 1000: 1200 s)" in caplog.text


def test_a_motion_sampled_in_milliseconds_is_refused():
    times = np.arange(200) * 1.0  # 1 kHz stamps in ms
    q = np.sin(np.outer(times / 1000.0, np.ones(6)))
    with pytest.raises(InvalidInput, match="milliseconds"):
        joint_derivatives(times, q)
    smooth, velocity, _ = joint_derivatives(times / 1000.0, q)
    np.testing.assert_allclose(
        velocity[50:150], np.cos(np.outer(times[50:150] / 1000.0, np.ones(6))), atol=1e-6
    )


def test_a_pose_revisited_under_the_same_id_is_refused_for_a_drift_model(arm, caplog):
    from ftkin import calibrate
    from ftkin.sim.sensor import paper_like_truth

    rng = np.random.default_rng(2)
    q = arm.random_configurations(8, rng, margin=0.3).copy()
    q[7] = q[2]  # the last visit returns to pose 2
    truth = paper_like_truth()
    rotations = arm.rotation_sensor_to_base(np.repeat(q, 3, axis=0))
    wrenches = truth.predict(rotations) + rng.normal(0, 0.01, (24, 6))
    ids = np.repeat(np.arange(8), 3)
    times = np.arange(24) * 10.0
    ids[-3:] = 2  # the last visit reuses pose 2's id, 150 s later
    samples = Samples(wrenches, rotations, ids, times=times)
    with pytest.raises(
        InvalidSamples,
        match=r"pose 2 was recorded in 2 separate visits \(60–80 s, 210–230 s; 1 pose",
    ):
        calibrate(samples, drift="poly:2")
    # not asked for a drift model: auto keeps a constant bias and says why
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        assert calibrate(samples, drift="auto").drift.model == "none"
    assert "keeps a constant bias" in caplog.text
    assert (
        calibrate(samples, drift="none").pose_count == 7
    )  # a constant bias: the visits may be averaged
    ids[-3:] = 8
    assert calibrate(Samples(wrenches, rotations, ids, times=times), drift="auto").pose_count == 8


def test_constructors_never_freeze_the_callers_arrays():
    from ftkin import SensorModel
    from ftkin.calibration.drift import BiasDrift

    wrenches, rotations, ids, times = (
        np.zeros((3, 6)),
        np.tile(np.eye(3), (3, 1, 1)),
        np.arange(3),
        np.arange(3.0),
    )
    samples = Samples(wrenches, rotations, ids, times=times)
    force = np.array([1.0, 2.0, 3.0])
    model = SensorModel(
        force_offset=force,
        torque_offset=np.zeros(3),
        gravity_in_base=np.array([0.0, 0.0, -5.0]),
        center_of_mass=np.zeros(3),
    )
    bias = np.zeros((3, 6))
    BiasDrift("none", "given", times, bias, bias.copy())
    for array in (wrenches, rotations, ids, times, force, bias):
        assert array.flags.writeable
    wrenches[0, 0], force[0] = 9.0, 9.0  # and the objects keep their own values
    assert samples.wrenches[0, 0] == 0.0 and model.force_offset[0] == 1.0
    assert not samples.wrenches.flags.writeable and not model.force_offset.flags.writeable


def test_auto_on_a_long_stream_of_single_readings_compares_polynomials_only(arm):
    from ftkin import SensorNoise, SimulatedSensor, calibrate
    from ftkin.calibration.drift_fit import MAX_AUTO_WALK_POSES
    from ftkin.sim import SensorDrift
    from ftkin.sim.sensor import paper_like_truth

    rng = np.random.default_rng(3)
    count = MAX_AUTO_WALK_POSES + 100
    q = arm.random_configurations(count, rng, margin=0.3)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise(0.02, 0.001), SensorDrift.typical())
    samples = sensor.samples_at_configurations(
        arm, q, rng, 1, times=np.arange(count) * 2.0
    )  # no pose column
    result = calibrate(samples)  # auto (the walk's search over 600 poses took about a minute)
    assert not any(name.startswith("random-walk") for name in result.drift.criteria)
    assert result.drift.model.startswith("poly")  # the warm-up is found
