"""Calibration report: the plotted numbers, the file, and the CLI."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.model import WRENCH_CHANNELS
from ftkin.cli import main
from ftkin.exceptions import InvalidInput, MissingDependency
from ftkin.io.calibration_file import save_calibration
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import SimulatedSensor
from ftkin.viz.report import report_data, report_figure, save_report

pytest.importorskip("matplotlib")
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def calibrated(arm, truth, rng):
    q = arm.random_configurations(8, rng, margin=0.1)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(arm, q, rng, 10)
    return calibrate(samples), samples


def test_report_data_matches_hand_computation(calibrated):
    result, samples = calibrated
    data = report_data(result, samples)
    for index, pose in enumerate(data["pose_ids"]):
        rows = samples.pose_ids == pose
        np.testing.assert_allclose(
            data["measured"][index], samples.wrenches[rows].mean(axis=0), atol=1e-12
        )
        expected_se = samples.wrenches[rows].std(axis=0, ddof=1) / np.sqrt(rows.sum())
        np.testing.assert_allclose(data["standard_error"][index], expected_se, rtol=1e-9)
    # residuals are the calibration's own per-pose residuals
    np.testing.assert_allclose(data["residuals"], result.residuals, atol=1e-9)
    np.testing.assert_allclose(data["measured"] - data["predicted"], data["residuals"])


def test_figure_has_measured_predicted_and_residual_panels(calibrated):
    result, samples = calibrated
    figure = report_figure(result, samples)
    titled = [axis.get_title() for axis in figure.axes if axis.get_title()]
    assert titled == list(WRENCH_CHANNELS)
    residual_axes = [axis for axis in figure.axes if axis.get_ylabel().startswith("residual")]
    assert len(residual_axes) == 6
    texts = [text.get_text() for axis in figure.axes for text in axis.texts]
    assert any("tool_mass" in text for text in texts)
    assert any("no standard errors" in text for text in texts) == (result.std_errors is None)


def test_save_png_and_bad_suffix(calibrated, tmp_path):
    result, samples = calibrated
    path = save_report(result, samples, tmp_path / "report.png")
    assert path.read_bytes()[:8] == PNG_SIGNATURE
    with pytest.raises(InvalidInput, match=r"\.png, \.pdf or \.svg"):
        save_report(result, samples, tmp_path / "report.jpg")
    with pytest.raises(InvalidInput, match="calibration must be an ftkin SensorModel"):
        report_data({"force_offset": [0, 0, 0]}, samples)
    with pytest.raises(InvalidInput, match="samples must be an ftkin.Samples"):
        report_data(result, samples.wrenches)


def test_missing_matplotlib(calibrated, monkeypatch):
    result, samples = calibrated
    monkeypatch.setitem(sys.modules, "matplotlib.figure", None)
    with pytest.raises(MissingDependency, match=r"ftkin\[plots\]"):
        report_figure(result, samples)


def test_cli_report(calibrated, arm, tmp_path, capsys):
    result, samples = calibrated
    calib = tmp_path / "calib.json"
    save_calibration(result, calib)
    csv_path = tmp_path / "samples.csv"
    rows = [
        [int(p), *map(float, q), *map(float, w)]
        for p, q, w in zip(samples.pose_ids, samples.joint_positions, samples.wrenches)
    ]
    write_csv(csv_path, ["pose", *arm.joint_names, *WRENCH_CHANNELS], rows)
    out = tmp_path / "report.png"
    assert main(["report", str(calib), str(csv_path), "-o", str(out)]) == 0
    assert out.read_bytes()[:8] == PNG_SIGNATURE
    assert "8 poses" in capsys.readouterr().out


def test_a_drift_aware_report_predicts_with_the_bias_at_each_pose_time(arm):
    from ftkin import SensorNoise, SimulatedSensor
    from ftkin.sim import SensorDrift
    from ftkin.sim.sensor import paper_like_truth, recording_times
    from ftkin.viz.report import SUMMARY_WIDTH, _wrapped

    rng = np.random.default_rng(8)
    q = arm.random_configurations(16, rng, margin=0.3)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise(0.02, 0.001), SensorDrift.typical())
    samples = sensor.samples_at_configurations(
        arm, q, rng, 5, times=recording_times(16, 5, 900.0, 0.01)
    )
    result = calibrate(samples, drift="poly:2")
    data = report_data(result, samples)
    poses = samples.pose_averages()
    expected = result.tool_gravity_wrench(poses.rotations) + result.bias_at(poses.times)  # by hand
    np.testing.assert_allclose(data["predicted"], expected, atol=1e-12)
    assert (
        np.sqrt(np.mean(data["residuals"][:, :3] ** 2)) < 0.05
    )  # the drift is not left in the residuals
    long = "  WARNING: " + "word " * 80
    assert all(len(line) <= SUMMARY_WIDTH for line in _wrapped(long).splitlines())
    assert _wrapped(long).splitlines()[1].startswith(" " * 6)
