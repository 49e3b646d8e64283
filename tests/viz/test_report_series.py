"""Optional time-series panels of the report: found when present, plotted as given, absent
otherwise.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from ftkin import CalibrationResult
from ftkin.calibration.information import SensorNoise
from ftkin.exceptions import InvalidInput
from ftkin.sim.sensor import SimulatedSensor
from ftkin.viz.report import report_figure, save_report
from ftkin.viz.report_series import as_series, report_series

pytest.importorskip("matplotlib")


def _series(rng, n=50):
    times = np.linspace(0.0, 10.0, n)
    return times, rng.normal(size=(n, 6)) * [0.1, 0.1, 0.1, 0.01, 0.01, 0.01]


def test_forms_of_a_series_are_read_alike(rng):
    times, values = _series(rng)
    forms = [
        (times, values),
        {"times": times, "bias": values},
        SimpleNamespace(times=times, residual=values),
        SimpleNamespace(times=times.tolist(), values=values.tolist()),
    ]
    for form in forms:
        series = as_series("bias_trajectory", "bias", form)
        np.testing.assert_array_equal(series.times, times)
        np.testing.assert_array_equal(series.values, values)
    for bad in [
        (times, values[:, :5]),
        (times[:-1], values),
        {"times": times},
        (times, np.full_like(values, np.nan)),
    ]:
        with pytest.raises(InvalidInput, match="bias_trajectory"):
            as_series("bias_trajectory", "bias", bad)


def test_panels_appear_only_for_the_series_present_and_plot_the_given_values(arm, truth, rng):
    q = arm.random_configurations(6, rng, margin=0.1)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng)
    plain = report_figure(truth, samples)
    assert report_series(CalibrationResult.from_model(truth)) == []
    base_axes = len(plain.axes)

    bias_times, bias = _series(rng, 40)
    residual_times, residual = _series(rng, 70)
    added = [
        as_series("bias_trajectory", "bias of a drifting sensor", (bias_times, bias)),
        as_series(
            "motion_residual",
            "residual during motion",
            {"times": residual_times, "residual": residual},
        ),
    ]
    figure = report_figure(truth, samples, series=added)
    assert len(figure.axes) == base_axes + 4
    extra = figure.axes[base_axes:]
    titles = [ax.get_title() for ax in extra]
    assert titles == [
        "bias of a drifting sensor: forces",
        "bias of a drifting sensor: torques",
        "residual during motion: forces",
        "residual during motion: torques",
    ]
    for ax, (times, values, first) in zip(
        extra,
        [
            (bias_times, bias, 0),
            (bias_times, bias, 3),
            (residual_times, residual, 0),
            (residual_times, residual, 3),
        ],
    ):
        assert len(ax.lines) == 3
        for k, line in enumerate(ax.lines):
            np.testing.assert_array_equal(line.get_xdata(), times)
            np.testing.assert_array_equal(line.get_ydata(), values[:, first + k])

    assert len(report_figure(truth, samples, series=added[:1]).axes) == base_axes + 2


def test_a_report_with_series_is_written(tmp_path, arm, truth, rng):
    q = arm.random_configurations(6, rng, margin=0.1)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng)
    added = [as_series("bias_trajectory", "bias", _series(rng))]
    path = save_report(truth, samples, tmp_path / "report.png", series=added)
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_drift_aware_calibration_draws_its_bias_trajectory(arm, truth):
    """The ``drift`` of a real drift-aware calibration is a series: its times and its bias at each
    time.
    """
    from ftkin import SensorNoise, SimulatedSensor, calibrate
    from ftkin.sim.sensor import recording_times

    rng = np.random.default_rng(4)
    configurations = arm.random_configurations(16, rng, margin=0.3)
    times = recording_times(16, 3, 480.0, 0.02)
    drift = np.outer(times / 480.0, [0.2, -0.1, 0.1, 0.003, 0.0, 0.001])
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, configurations, rng, 3, times=times, bias_drift=drift
    )
    result = calibrate(samples, drift="poly:1")
    series = {one.name: one for one in report_series(result)}
    np.testing.assert_array_equal(series["drift"].times, result.drift.times)
    np.testing.assert_array_equal(series["drift"].values, result.drift.bias)
    assert "drift" not in {one.name for one in report_series(calibrate(samples, drift="none"))}
