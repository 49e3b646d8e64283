"""The one goodness-of-fit test (ftkin.calibration.goodness_of_fit) against hand computations:
chi-square and its p-value (scipy.stats), the per-channel chi-square (an explicit hat matrix), the
verdict on both sides of FIT_ALPHA, outlier time spans, the file form; and the IMU's noise as the
dynamic IMU fit measures it (against the noise simulated)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy import stats
from scipy.signal import savgol_filter

import ftkin
from ftkin.calibration.diagnostics import FIT_ALPHA
from ftkin.calibration.goodness_of_fit import FitTest, fit_test
from ftkin.calibration.imu_dynamic import smoothed_noise_variance
from ftkin.exceptions import CalibrationFileError

CHANNELS = ("a", "b", "c")


def linear_fit(rng, rows=50, parameters=4, sigma=1.0):
    """Whitened residuals ``(rows, 3)`` of an ordinary least-squares fit and its Jacobian."""
    jacobian = rng.normal(size=(3 * rows, parameters))
    readings = jacobian @ rng.normal(size=parameters) + rng.normal(0.0, sigma, 3 * rows)
    estimate = np.linalg.lstsq(jacobian, readings, rcond=None)[0]
    return (readings - jacobian @ estimate).reshape(rows, 3), jacobian


def test_chi_square_p_value_and_channels_against_hand_computation():
    rng = np.random.default_rng(1)
    whitened, jacobian = linear_fit(rng)
    hat = jacobian @ np.linalg.inv(jacobian.T @ jacobian) @ jacobian.T  # explicit
    leverage = np.diag(hat).reshape(50, 3)
    chi_square, dof = float(np.sum(whitened**2)), 150 - 4

    given = fit_test("the fit", whitened, jacobian, channel_names=CHANNELS, noise_source="given")
    assert given.dof == dof and given.parameter_count == 4
    np.testing.assert_allclose(given.chi_square, chi_square, rtol=1e-12)
    np.testing.assert_allclose(given.p_value, stats.chi2.sf(chi_square, dof), rtol=1e-9)
    expected = np.sum(whitened**2, axis=0) / np.sum(1.0 - leverage, axis=0)
    np.testing.assert_allclose(given.channel_chi_square, expected, rtol=1e-9)
    assert given.verdict == "fits" and given.warning is None and given.outliers == ()

    spread = fit_test(
        "the fit",
        whitened,
        jacobian,
        channel_names=CHANNELS,
        noise_source="spread",
        noise_dof=30.0,
    )
    np.testing.assert_allclose(spread.p_value, stats.f.sf(chi_square / dof, dof, 30), rtol=1e-9)

    residuals = fit_test(
        "the fit", whitened, jacobian, channel_names=CHANNELS, noise_source="residuals"
    )
    assert residuals.p_value is None and residuals.verdict == "not tested"
    assert "own residuals" in residuals.untested_reason and "noise=" in residuals.untested_reason
    assert residuals.to_dict()["p_value"] is None


@pytest.mark.parametrize("factor, verdict", [(1.001, "does not fit"), (0.999, "fits")])
def test_the_verdict_on_both_sides_of_fit_alpha(factor, verdict, caplog):
    """A chi-square 0.1 % above the p = FIT_ALPHA point is a misfit, 0.1 % below it is not."""
    rng = np.random.default_rng(2)
    whitened, jacobian = linear_fit(rng)
    threshold = stats.chi2.isf(FIT_ALPHA, 150 - 4)
    whitened = whitened * np.sqrt(factor * threshold / np.sum(whitened**2))
    test = fit_test(
        "the test's fit", whitened, jacobian, channel_names=CHANNELS, noise_source="given"
    )
    assert test.verdict == verdict
    assert (test.p_value < FIT_ALPHA) == (verdict == "does not fit")
    logged = [r.getMessage() for r in caplog.records]
    if verdict == "fits":
        assert test.warning is None and not logged
    else:
        assert test.warning.startswith("the test's fit does not fit: chi² = ")
        assert logged == [test.warning]


def test_a_burst_is_an_outlier_time_span_and_white_noise_is_not():
    """20 s of white residuals at 100 Hz: no span flagged; a 5σ burst on one channel from 3.2 s to
    3.8 s is flagged as the 1 s window that holds it."""
    rng = np.random.default_rng(3)
    times = np.arange(0.0, 20.0, 0.01)
    whitened = rng.normal(size=(len(times), 3))
    jacobian = np.zeros((3 * len(times), 1))
    jacobian[::3, 0] = 1.0  # one parameter: the mean of channel a
    whitened[:, 0] -= whitened[:, 0].mean()

    def test(residuals):
        return fit_test(
            "the moving fit",
            residuals,
            jacobian,
            channel_names=CHANNELS,
            noise_source="given",
            times=times,
            log=False,
        )

    clean = test(whitened)
    assert clean.outlier_kind == "time spans" and clean.outliers == ()
    burst = whitened.copy()
    inside = (times >= 3.2) & (times <= 3.8)
    burst[inside, 2] += 5.0
    ((start, end),) = test(burst).outliers
    assert 3.0 <= start <= 3.2 and 3.8 <= end < 4.0


def test_the_file_keeps_the_test_and_refuses_a_verdict_its_p_contradicts(tmp_path):
    arm = ftkin.Arm.default()
    rng = np.random.default_rng(0)
    truth = ftkin.SensorModel.from_tool(1.5, [0.03, -0.02, 0.08], [2.0, -1.5, 3.0], [0.1, 0, 0])
    sensor = ftkin.SimulatedSensor(truth, ftkin.SensorNoise(0.03, 0.0015))
    q = arm.random_configurations(12, rng, margin=0.3)
    result = ftkin.calibrate(sensor.samples_at_configurations(arm, q, rng, readings_per_pose=10))
    path = ftkin.save_calibration(result, tmp_path / "c.json")
    loaded = ftkin.load_calibration(path)
    assert isinstance(loaded.fit_test, FitTest) and loaded.fit_test.fit_name == (
        "the static fit from joints"
    )
    assert loaded.diagnostics.fit_test == loaded.fit_test
    assert loaded.fit_test.p_value == result.diagnostics.p_value  # one test, one number
    document = json.loads(path.read_text())
    document["fit_test"]["verdict"] = "does not fit"
    (tmp_path / "d.json").write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="fit_test.*verdict 'does not fit' disagrees"):
        ftkin.load_calibration(tmp_path / "d.json")
    document["fit_test"]["verdict"] = "fits"
    document["fit_test"]["p_value"] = "0.5"
    (tmp_path / "e.json").write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="fit_test.p_value"):
        ftkin.load_calibration(tmp_path / "e.json")


def test_the_imu_noise_the_dynamic_fit_adds_is_the_noise_simulated():
    """White noise of known σ on smooth signals at 500 Hz: the raw σ² measured from the scatter
    about the Savitzky–Golay fit, and the variance it leaves in the smoothed value and the
    derivative, against the noise added (empirical, from the truth)."""
    rng = np.random.default_rng(4)
    period, window, polyorder = 0.002, 27, 4
    times = np.arange(0.0, 40.0, period)
    sigma = np.array([0.002, 0.003, 0.001, 0.01, 0.02, 0.015])  # gyro [rad/s], accel [m/s²]
    truth = np.sin(2 * np.pi * 0.3 * times[:, None] + np.arange(6))
    raw = truth + rng.normal(size=truth.shape) * sigma
    smooth = savgol_filter(raw, window, polyorder, axis=0)
    rate = savgol_filter(raw, window, polyorder, deriv=1, delta=period, axis=0)
    variance = smoothed_noise_variance(times, raw, smooth, rate, window, polyorder, np.zeros(3))
    truth_rate = 2 * np.pi * 0.3 * np.cos(2 * np.pi * 0.3 * times[:, None] + np.arange(6))
    inner = slice(window, -window)  # the filter's edges are fitted otherwise
    smooth_error = np.var((smooth - truth)[inner], axis=0)
    rate_error = np.var((rate - truth_rate)[inner], axis=0)
    np.testing.assert_allclose(variance["gyro"], smooth_error[:3], rtol=0.1)
    np.testing.assert_allclose(variance["corrected"], smooth_error[3:], rtol=0.1)
    np.testing.assert_allclose(variance["gyro_rate"], rate_error[:3], rtol=0.1)
