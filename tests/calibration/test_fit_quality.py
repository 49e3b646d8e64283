"""Fit quality, outlier poses and observability diagnostics (ftkin.calibration.fit_quality)."""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin import Samples, SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration.diagnostics import OUTLIER_ALPHA, FitDiagnostics
from ftkin.calibration.fit_quality import diagnose
from ftkin.calibration.ml import fit_ml
from ftkin.cli import main

NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
CABLE = np.array(
    [0.0, 0.4, -0.3, 0.02, 0.0, 0.0]
)  # a cable pulling on the tool at one pose [N, N·m]


def _with_cable(tool, rotations, rng, readings, pose=5):
    """Noisy samples with a constant contact wrench added at one pose (ids 0..11)."""
    samples = SimulatedSensor(tool, NOISE).samples(rotations, rng, readings)
    wrenches = samples.wrenches + np.where((samples.pose_ids == pose)[:, None], CABLE, 0.0)
    return Samples(wrenches, samples.rotations, samples.pose_ids)


# ------------------------------------------------------------------ outliers
@pytest.mark.parametrize("readings", [10, 1], ids=["noise from spread", "noise from residuals"])
def test_an_outlier_pose_is_detected_named_and_dropped(tool, rotations, rng, readings, caplog):
    samples = _with_cable(tool, rotations, rng, readings)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(samples)
    assert result.diagnostics.outlier_pose_ids == (5,)
    assert "OUTLIER poses: 5" in result.summary()
    assert any("outlier pose(s)" in message and "5 (" in message for message in result.warnings)
    assert any("outlier pose(s)" in record.getMessage() for record in caplog.records)

    refit = calibrate(samples, drop_outliers=True)
    assert refit.diagnostics.dropped_pose_ids == (5,)
    assert 5 not in refit.pose_ids and refit.pose_count == 11
    assert refit.diagnostics.outlier_pose_ids == ()
    assert "dropped as outliers before the final fit: poses 5" in refit.summary()
    sigma = np.sqrt(np.diag(refit.covariance))
    assert np.all(np.abs(refit.to_vector() - tool.to_vector()) < 4.5 * sigma)
    assert np.max(np.abs(result.to_vector() - tool.to_vector()) / sigma) > 5  # the outlier did harm


def test_cli_drop_outliers_names_the_pose(arm, tool, tmp_path, capsys):
    from ftkin.io.csv_table import write_csv

    rng = np.random.default_rng(5)
    configurations = np.repeat(arm.random_configurations(12, rng, margin=0.3), 4, axis=0)
    pose_ids = np.repeat(np.arange(1, 13), 4)
    wrenches = SimulatedSensor(tool, NOISE).read(arm.rotation_sensor_to_base(configurations), rng)
    wrenches[pose_ids == 9] += CABLE
    header = [*arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz", "pose"]
    write_csv(
        tmp_path / "s.csv",
        header,
        [[*q, *w, int(p)] for q, w, p in zip(configurations, wrenches, pose_ids)],
    )
    assert main(["calibrate", str(tmp_path / "s.csv")]) == 0
    assert "OUTLIER poses: 9" in capsys.readouterr().out
    assert main(["calibrate", str(tmp_path / "s.csv"), "--drop-outliers"]) == 0
    assert "dropped as outliers before the final fit: poses 9" in capsys.readouterr().out


@pytest.mark.parametrize("loss", ["soft_l1", "huber"])
def test_robust_loss_resists_the_outlier(tool, rotations, rng, loss):
    samples = _with_cable(tool, rotations, rng, 10)
    plain = calibrate(samples)
    robust = calibrate(samples, loss=loss)
    sigma = np.sqrt(np.diag(robust.covariance))
    assert np.max(np.abs(robust.to_vector() - tool.to_vector()) / sigma) < 4.5
    assert np.linalg.norm(robust.to_vector() - tool.to_vector()) < 0.5 * np.linalg.norm(
        plain.to_vector() - tool.to_vector()
    )
    assert robust.diagnostics.loss == loss and robust.diagnostics.outlier_pose_ids == (5,)


def test_pose_statistics_follow_their_null_distribution(tool, rotations):
    """On clean data the per-pose p-values are uniform and false alarms are rare."""
    rng = np.random.default_rng(99)
    sensor = SimulatedSensor(tool, NOISE)
    p_values, flagged = [], 0
    for _ in range(150):
        poses = sensor.samples(rotations, rng).pose_averages()
        diagnostics, _ = diagnose(fit_ml(poses, noise=NOISE), poses.pose_ids)
        p_values.append(diagnostics.pose_p_values)
        flagged += bool(diagnostics.outlier_pose_ids)
    p_values = np.concatenate(p_values)
    assert np.mean(p_values) == pytest.approx(0.5, abs=0.03)
    assert np.mean(p_values < 0.1) == pytest.approx(0.1, abs=0.025)
    assert flagged <= 2  # expected 150 × OUTLIER_ALPHA = 0.15
    assert OUTLIER_ALPHA <= 0.01


# ------------------------------------------------------------- goodness of fit
def test_crosstalk_fails_the_chi_square_test_and_inflates_the_errors(tool, rotations, caplog):
    rng = np.random.default_rng(8)
    samples = SimulatedSensor(tool, NOISE).samples(rotations, rng, 20)
    crosstalk = np.eye(6)
    crosstalk[0, 2] = crosstalk[3, 4] = 0.03  # fx picks up 3 % of fz, mx 3 % of my
    skewed = Samples(samples.wrenches @ crosstalk.T, samples.rotations, samples.pose_ids)
    clean = calibrate(samples)
    assert clean.diagnostics.fit_ok and clean.diagnostics.covariance_scale == 1.0
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        bad = calibrate(skewed)
    diagnostics = bad.diagnostics
    assert not diagnostics.fit_ok and diagnostics.p_value < 1e-3
    assert diagnostics.covariance_scale == pytest.approx(diagnostics.chi_square / diagnostics.dof)
    assert (
        diagnostics.channel_chi_square[0] > 5 * diagnostics.channel_chi_square[5]
    )  # fx is the misfit channel
    assert "DOES NOT FIT the noise" in bad.summary()
    assert any("do not fit the model" in record.getMessage() for record in caplog.records)


def test_clean_data_pass_the_chi_square_test(tool, rotations, rng):
    diagnostics = calibrate(
        SimulatedSensor(tool, NOISE).samples(rotations, rng, 5), noise=NOISE
    ).diagnostics
    assert diagnostics.fit_ok and diagnostics.dof == 6 * 12 - 12
    assert diagnostics.chi_square == pytest.approx(diagnostics.dof, rel=0.5)
    assert diagnostics.warnings == ()


# --------------------------------------------------------------- observability
def test_small_tilts_warn_about_the_poorly_determined_parameters(arm, tool, caplog):
    """Poses within ±1° of one another leave the COM and the biases weakly determined."""
    rng = np.random.default_rng(1)
    home = np.array([0.0, 0.0, -0.5236, 0.0, -1.0472, 0.0])
    configurations = home + rng.uniform(-0.02, 0.02, size=(12, arm.nq))
    rotations = arm.rotation_sensor_to_base(configurations)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(SimulatedSensor(tool, NOISE).samples(rotations, rng), noise=NOISE)
    diagnostics = result.diagnostics
    assert diagnostics.condition_number > 1e3
    assert np.linalg.norm(diagnostics.weakest_direction) == pytest.approx(1.0)
    assert {"center_of_mass[x]", "center_of_mass[z]", "force_offset[z]"} <= set(
        diagnostics.poorly_determined
    )
    assert any("center_of_mass is poorly determined" in message for message in result.warnings)
    assert "WARNING: center_of_mass is poorly determined" in result.summary()
    assert any("poorly determined" in record.getMessage() for record in caplog.records)


def test_condition_number_matches_the_normalized_information(tool, rotations, rng):
    poses = SimulatedSensor(tool, NOISE).samples(rotations, rng).pose_averages()
    fit = fit_ml(poses, noise=NOISE)
    diagnostics, covariance = diagnose(fit, poses.pose_ids)
    information = fit.information
    correlation = np.linalg.inv(
        information / np.sqrt(np.outer(np.diag(information), np.diag(information)))
    )
    assert diagnostics.condition_number == pytest.approx(np.linalg.cond(correlation), rel=1e-6)
    np.testing.assert_allclose(covariance @ information, np.eye(12), atol=1e-8)


def test_diagnostics_survive_a_dict_round_trip_with_missing_values(tool, rotations, rng):
    poses = SimulatedSensor(tool, NOISE).samples(rotations[:3], rng).pose_averages()
    diagnostics, _ = diagnose(
        fit_ml(poses), poses.pose_ids
    )  # noise from residuals: no chi-square test
    assert np.isnan(diagnostics.p_value)
    again = FitDiagnostics.from_dict(diagnostics.to_dict())
    assert again.to_dict() == diagnostics.to_dict()
    assert again.noise_source == "residuals" and again.fit_ok
    assert any(
        "standard errors are rough" in message for message in diagnostics.warnings
    )  # 3 poses: few dof


def test_robust_fit_on_four_poses_judges_no_pose_it_cannot(arm, tool, caplog):
    """A Huber fit on 4 poses of one reading named a pose an outlier at 1e150σ: the deletion
    residual (a least-squares formula) exceeded the whole chi-square of the robust fit, the scatter
    left for the other poses came out negative and was floored at 1e-300.
    """
    rotations = arm.rotation_sensor_to_base(
        arm.random_configurations(12, np.random.default_rng(7), margin=0.3)[:4]
    )
    samples = SimulatedSensor(tool, NOISE).samples(rotations, np.random.default_rng(0))
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(samples, loss="huber")
    diagnostics = result.diagnostics
    assert diagnostics.outlier_pose_ids == ()
    assert np.all(
        np.isnan(diagnostics.pose_normalized_residuals)
        | (diagnostics.pose_normalized_residuals < 10)
    )
    assert np.isnan(diagnostics.pose_p_values[1]) and "pose(s) 1 not tested" in caplog.text
    assert "largest pose residual" in result.summary()
