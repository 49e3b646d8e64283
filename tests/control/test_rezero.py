"""Re-zeroing without losing the tool weight, driver-zeroed readings, and the bias at a reading's
time.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Compensator, InvalidInput, SensorNoise, SimulatedSensor, calibrate
from ftkin.sim import recording_times

NOISE = SensorNoise(0.02, 0.001)


@pytest.fixture(scope="module")
def poses(arm):
    return arm.random_configurations(20, np.random.default_rng(8), margin=0.3)


def test_rezero_at_a_tilted_pose_still_compensates_the_tool_weight(arm, truth, poses, rng):
    drifted = SimulatedSensor(
        truth.__class__(
            truth.force_offset + [0.4, -0.3, 0.2],
            truth.torque_offset + [0.01, 0, -0.01],
            truth.gravity_in_base,
            truth.center_of_mass,
        ),
        NOISE,
    )
    q_tilted = np.array([0.3, -1.0, 1.2, 0.8, 1.1, -0.4])  # tool far from hanging straight down
    rotation = arm.rotation_sensor_to_base(q_tilted[None])[0]
    assert np.degrees(np.arccos(-rotation[:, 2] @ [0, 0, -1])) > 30  # the sensor z axis is tilted
    readings = drifted.read(np.repeat(rotation[None], 200, axis=0), rng)
    compensator = Compensator(truth, arm)
    bias = compensator.rezero(q_tilted, readings.mean(axis=0))
    # independent: bias = mean reading − [R^T a, P × R^T a]
    gravity = rotation.T @ truth.gravity_in_base
    np.testing.assert_allclose(
        bias,
        readings.mean(axis=0) - np.concatenate([gravity, np.cross(truth.center_of_mass, gravity)]),
    )
    np.testing.assert_allclose(
        compensator.compensate(q_tilted, readings.mean(axis=0)), 0.0, atol=1e-12
    )
    # at every other pose the contact is zero within the noise; the naive zero leaves the tool
    # weight in
    rotations = arm.rotation_sensor_to_base(poses)
    raw = drifted.read(np.repeat(rotations, 100, axis=0), rng).reshape(20, 100, 6).mean(axis=1)
    contact = compensator.compensate_batch(poses, raw)
    assert np.all(np.abs(contact) < 5 * NOISE.channel_std * np.sqrt(1 / 100 + 1 / 200))
    naive = Compensator(truth, arm)
    naive.set_bias(readings.mean(axis=0))  # "bias = the whole reading", what a driver zero does
    assert (
        np.max(np.linalg.norm(naive.compensate_batch(poses, raw)[:, :3], axis=1))
        > 0.5 * truth.tool_weight
    )


def test_driver_zeroed_readings_are_compensated_within_the_noise(arm, truth, poses, rng):
    sensor = SimulatedSensor(truth, NOISE)
    q0 = np.array([-0.5, -1.3, 1.5, -0.6, 1.4, 0.9])
    rotation0 = arm.rotation_sensor_to_base(q0[None])[0]
    driver_zero = sensor.read(np.repeat(rotation0[None], 500, axis=0), rng).mean(axis=0)
    rotations = arm.rotation_sensor_to_base(poses)
    zeroed = sensor.read(rotations, rng) - driver_zero
    compensator = Compensator(truth, arm)
    bias = compensator.driver_zeroed_at(q0)
    gravity0 = rotation0.T @ truth.gravity_in_base
    np.testing.assert_allclose(
        bias, -np.concatenate([gravity0, np.cross(truth.center_of_mass, gravity0)])
    )
    contact = np.array([compensator.compensate(q, w) for q, w in zip(poses, zeroed)])
    assert np.all(np.abs(contact) < 5 * NOISE.channel_std)
    # without the call, the tool weight at q0 is missing everywhere
    assert np.max(np.abs(Compensator(truth, arm).compensate_batch(poses, zeroed))) > 1.0
    with pytest.raises(InvalidInput):
        compensator.driver_zeroed_at([0.0, 1.0])


def test_bias_at_reading_times_inside_and_after_a_drifting_recording(arm, truth, poses, rng):
    times = recording_times(20, 5, 600.0, 0.01)
    drift = np.outer(times / 600.0, [0.3, -0.2, 0.1, 0.004, 0.0, -0.002])
    samples = SimulatedSensor(truth, NOISE).samples_at_configurations(
        arm, poses, rng, 5, times=times, bias_drift=drift
    )
    result = calibrate(samples, drift="poly:1")
    compensator = Compensator(result, arm)
    inside = np.array([10.0, 300.0, 500.0])
    np.testing.assert_allclose(compensator.bias_at(inside), result.drift.bias_at(inside))
    compensator.set_bias(result.bias + 0.05)
    np.testing.assert_allclose(
        compensator.bias_at([10_000.0, -5.0]), [result.bias + 0.05] * 2
    )  # outside: the current bias
    contact = compensator.compensate_samples(samples)
    np.testing.assert_allclose(
        np.sqrt(np.mean(contact[:, :3] ** 2)), 0.02, rtol=0.25
    )  # the noise alone
    batch = compensator.compensate_batch(samples.rotations, samples.wrenches, times=samples.times)
    np.testing.assert_allclose(batch, contact, rtol=1e-12, atol=1e-12)
