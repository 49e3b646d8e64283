"""Drift-aware calibration: the random-walk filter against dense linear algebra, drift recovered,
none kept when constant.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import multivariate_normal

from ftkin import InvalidInput, Samples, SensorModel, SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration import fisher_information
from ftkin.calibration.information import (
    covariance_from_information,
    extended_parameters,
    extended_standard_errors,
)
from ftkin.calibration.random_walk import log_likelihood, smooth, walk_gains, whiten
from ftkin.sim import SensorDrift, recording_times

NOISE = SensorNoise(0.03, 0.0015)
DATA = Path(__file__).parents[1] / "io" / "data"


def _walk_covariance(times, rate, noise_variance):
    """Dense covariance of y_i = w(t_i) + e_i for a walk pinned at the last time: q² min(T − t_i, T
    − t_j) + D.
    """
    to_end = times[-1] - times
    return rate**2 * np.minimum.outer(to_end, to_end) + np.diag(noise_variance)


def test_filter_is_the_exact_gaussian_likelihood_and_gls_whitening(rng):
    times = np.sort(rng.uniform(0, 100, 15))
    rate = np.array([0.05, 0.02, 0.1, 0.003, 0.001, 0.002])
    noise_variance = rng.uniform(0.5, 2.0, (15, 6)) * np.array([0.01] * 3 + [1e-5] * 3)
    gains = walk_gains(times, noise_variance, rate)
    data = rng.standard_normal((15, 6, 3))
    white = whiten(gains, data)
    for c in range(6):
        covariance = _walk_covariance(times, rate[c], noise_variance[:, c])
        inverse = np.linalg.inv(covariance)
        # whitened columns reproduce the generalized least-squares normal matrix Xᵀ Σ⁻¹ X
        np.testing.assert_allclose(
            white[:, c, :].T @ white[:, c, :], data[:, c, :].T @ inverse @ data[:, c, :], rtol=1e-9
        )
        # the RTS smoother is the conditional mean E[w | y] = K Σ⁻¹ y and its variance
        walk_part = covariance - np.diag(noise_variance[:, c])
        mean, variance = smooth(gains, times, data[:, :, 0], rate)
        np.testing.assert_allclose(mean[:, c], walk_part @ inverse @ data[:, c, 0], atol=1e-10)
        np.testing.assert_allclose(
            variance[:, c], np.diag(walk_part - walk_part @ inverse @ walk_part), atol=1e-10
        )
    expected = sum(
        multivariate_normal(
            np.zeros(15), _walk_covariance(times, rate[c], noise_variance[:, c])
        ).logpdf(data[:, c, 0])
        for c in range(6)
    )
    assert log_likelihood(gains, white[:, :, 0]) == pytest.approx(expected, rel=1e-10)


@pytest.fixture(scope="module")
def poses40(arm):
    return arm.random_configurations(40, np.random.default_rng(3), margin=0.3)


def test_polynomial_drift_is_recovered(arm, tool, poses40):
    rng = np.random.default_rng(11)
    times = recording_times(40, 5, 1200.0, 0.01)
    tau = times / 1200.0
    true_drift = np.outer(tau, [0.3, -0.2, 0.25, 0.006, -0.004, 0.005]) + np.outer(
        tau**2, [-0.2, 0.1, 0.1, -0.003, 0.002, 0.0]
    )
    sensor = SimulatedSensor(tool, NOISE)
    samples = sensor.samples_at_configurations(
        arm, poses40, rng, 5, times=times, bias_drift=true_drift
    )
    result = calibrate(samples, drift="poly:2")
    assert result.drift.model == "poly:2" and result.drift.selected_by == "given"
    truth_bias = tool.bias + true_drift
    estimated = result.bias_at(times)
    # the bias at every reading time, within 4 of its standard errors
    sigma = np.column_stack(
        [np.interp(times, result.drift.times, result.drift.bias_std[:, c]) for c in range(6)]
    )
    assert np.all(np.abs(estimated - truth_bias) < 4 * sigma)
    end_errors = np.concatenate(
        [result.std_errors["force_offset"], result.std_errors["torque_offset"]]
    )
    assert np.all(np.abs(result.bias - truth_bias[-1]) < 4 * end_errors)
    errors = (extended_parameters(result) - extended_parameters(tool))[[0, 1, 2, 9, 10, 11]]
    assert np.all(
        np.abs(errors)
        < 4 * extended_standard_errors(result, result.covariance)[[0, 1, 2, 9, 10, 11]]
    )
    # auto finds a drift too; the constant model is far off
    auto = calibrate(samples)
    assert auto.drift.model != "none" and auto.drift.selected_by == "auto"
    assert abs(calibrate(samples, drift="none").tool_mass - tool.tool_mass) > 5 * abs(
        auto.tool_mass - tool.tool_mass
    )


def test_random_walk_drift_and_its_rate_are_recovered(arm, tool, poses40):
    rng = np.random.default_rng(5)
    times = recording_times(40, 5, 1200.0, 0.01)
    drift = SensorDrift(random_walk=[0.004, 0.0001])
    sensor = SimulatedSensor(tool, NOISE, drift)
    true_drift = sensor.bias_drift(times, rng)
    samples = sensor.samples_at_configurations(
        arm, poses40, rng, 5, times=times, bias_drift=true_drift
    )
    result = calibrate(samples, drift="random-walk")
    assert result.drift.rate[0] == pytest.approx(0.004, rel=0.4)
    assert result.drift.rate[1] == pytest.approx(0.0001, rel=0.4)
    pose_truth = tool.bias + true_drift.reshape(40, 5, 6).mean(axis=1)
    z = (result.drift.bias - pose_truth) / result.drift.bias_std
    assert np.sqrt(np.mean(z**2)) < 1.5 and np.max(np.abs(z)) < 4.5
    # the random walk beats the constant model on the parameters
    assert abs(result.tool_mass - tool.tool_mass) < abs(
        calibrate(samples, drift="none").tool_mass - tool.tool_mass
    )


def test_constant_bias_with_times_keeps_the_constant_model_and_its_efficiency(arm, tool, rotations):
    rng = np.random.default_rng(2024)
    sensor = SimulatedSensor(tool, NOISE)
    times = recording_times(len(rotations), 4, 600.0, 0.01)
    trials, errors, picked = 20, [], []
    for _ in range(trials):
        samples = sensor.samples(rotations, rng, 4, times=times)
        result = calibrate(samples)
        picked.append(result.drift.model)
        if result.drift.model == "none":
            plain = calibrate(Samples(samples.wrenches, samples.rotations, samples.pose_ids))
            np.testing.assert_allclose(
                extended_parameters(result), extended_parameters(plain), rtol=1e-12, atol=1e-12
            )
            np.testing.assert_allclose(result.covariance, plain.covariance, rtol=1e-12, atol=0)
        errors.append(extended_parameters(result) - extended_parameters(tool))
    assert picked.count("none") >= trials - 1
    crlb = extended_standard_errors(
        tool, covariance_from_information(fisher_information(tool, rotations, NOISE, 4))
    )
    efficiency = crlb**2 / np.mean(np.square(errors), axis=0)
    assert np.mean(efficiency) >= 0.9


def test_without_times_nothing_changes(arm, truth):
    """The numbers a format-1 file written by the previous ftkin holds (same seed and poses), to
    1e-12 relative: another CPU's BLAS may differ in the last digits. Relative to each vector's
    largest entry: the minimum is found to rounding of the whole vector, so a component 400 times
    smaller than its vector's largest (the tilt's ``gravity_in_base[0]``) moved 3e-11 of itself
    when Levenberg–Marquardt's stop (``ftol``) became Gauss–Newton's (issue 38), whose answer
    has the smaller cost and a scaled gradient 2e-14 of the residuals' norm against the file's
    8e-12; the residuals likewise move 1e-13 of the readings' scale.
    """
    stored = json.loads((DATA / "calibration_v1.json").read_text())
    rng = np.random.default_rng(5)
    configurations = arm.random_configurations(8, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, configurations, rng, 3
    )
    result = calibrate(samples)
    assert result.drift is None
    for key in ("force_offset", "torque_offset", "gravity_in_base", "center_of_mass"):
        scale = np.abs(stored[key]).max()
        np.testing.assert_allclose(getattr(result, key), stored[key], rtol=0, atol=1e-12 * scale)
    covariance = np.array(stored["covariance"])
    scale = np.abs(covariance).max()
    np.testing.assert_allclose(result.covariance, covariance, rtol=1e-12, atol=1e-12 * scale)
    wrench_scale = np.abs(stored["poses"]["measured"]).max()  # residuals: to its rounding
    np.testing.assert_allclose(
        result.residuals, stored["poses"]["residuals"], rtol=0, atol=1e-12 * wrench_scale
    )


def test_drift_options_are_checked(tool, rotations, rng):
    sensor = SimulatedSensor(tool, NOISE)
    timed = sensor.samples(rotations, rng, 2, times=recording_times(12, 2, 60.0))
    untimed = sensor.samples(rotations, rng, 2)
    with pytest.raises(InvalidInput, match="unknown drift model"):
        calibrate(timed, drift="cubic")
    with pytest.raises(InvalidInput, match="degree must be 1..5"):
        calibrate(timed, drift="poly:0")
    with pytest.raises(InvalidInput, match="needs the time of each reading"):
        calibrate(untimed, drift="random-walk")
    with pytest.raises(InvalidInput, match="method='ml'"):
        calibrate(timed, drift="poly:1", method="linear")
    with pytest.raises(InvalidInput, match="same time"):
        calibrate(
            Samples(timed.wrenches, timed.rotations, timed.pose_ids, times=np.zeros(24)),
            drift="poly:1",
        )
    # auto quietly keeps the constant model where a drift does not apply
    assert calibrate(timed, loss="huber").drift.model == "none"
    assert calibrate(timed, method="linear").drift.model == "none"
    outlying = Samples(
        timed.wrenches + np.where(timed.pose_ids[:, None] == 3, 5.0, 0.0),
        timed.rotations,
        timed.pose_ids,
        times=timed.times,
    )
    dropped = calibrate(outlying, drop_outliers=True)
    assert dropped.diagnostics.dropped_pose_ids == (3,) and len(dropped.drift.times) == 11
    assert calibrate(untimed).drift is None


def test_samples_times_are_validated(tool, rotations, rng):
    samples = SimulatedSensor(tool, NOISE).samples(rotations, rng, 1)
    with pytest.raises(Exception, match="times must have shape"):
        Samples(samples.wrenches, samples.rotations, times=np.zeros(3))
    with pytest.raises(Exception, match="finite"):
        Samples(samples.wrenches, samples.rotations, times=np.full(12, np.nan))
    times = (
        Samples(samples.wrenches, samples.rotations, times=np.arange(12.0)).pose_averages().times
    )
    np.testing.assert_allclose(times, np.arange(12.0), rtol=1e-12, atol=0)


def test_sensor_drift_parts(rng):
    drift = SensorDrift(
        warmup=[0.5, 0.01],
        warmup_time_constant=300.0,
        temperature_coefficient=[0.02, 0.0004],
        temperature_times=[0.0, 1000.0],
        temperatures=[20.0, 30.0],
    )
    times = np.array([0.0, 300.0, 600.0, 2000.0])
    expected = np.outer(1 - np.exp(-times / 300.0), [0.5] * 3 + [0.01] * 3) + np.outer(
        np.minimum(times, 1000.0) / 100.0, [0.02] * 3 + [0.0004] * 3
    )
    np.testing.assert_allclose(drift.offsets(times, rng), expected, atol=1e-15)
    walk = SensorDrift(random_walk=0.01)
    draws = np.array([walk.offsets([100.0, 400.0], rng) for _ in range(2000)])
    np.testing.assert_allclose(np.var(draws[:, 0, :], axis=0), 0.01**2 * 100.0, rtol=0.12)
    np.testing.assert_allclose(
        np.var(draws[:, 1, :] - draws[:, 0, :], axis=0), 0.01**2 * 300.0, rtol=0.12
    )
    with pytest.raises(InvalidInput):
        SensorDrift(random_walk=-1.0)
    # the current constructor still works, and without drift the readings are the old ones
    sensor = SimulatedSensor(SensorModel.from_tool(1.0, [0, 0, 0.05]), NOISE)
    assert sensor.drift is None


@pytest.mark.parametrize("time_scale", ["60", None, [1.0, 2.0], 1j, float("nan")])
@pytest.mark.parametrize("selected_by", ["given", "me"])
def test_a_bias_drift_refuses_each_bad_field_with_invalid_input(selected_by, time_scale):
    """Regression: a bad time_scale crashed the table of refusals with a TypeError or ValueError
    even when an earlier row (selected_by) refused first.
    """
    from ftkin.calibration.drift import BiasDrift

    good = dict(model="none", times=[0.0, 1.0], bias=np.zeros((2, 6)), bias_std=np.ones((2, 6)))
    match = "selected_by" if selected_by == "me" else "time_scale must be a finite time > 0"
    with pytest.raises(InvalidInput, match=match):
        BiasDrift(selected_by=selected_by, time_scale=time_scale, **good)
