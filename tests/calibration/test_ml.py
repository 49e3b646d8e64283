"""The maximum-likelihood estimator (ftkin.calibration.ml) and its standard errors.

Checked against independent computations: the known truth, finite
differences, a brute-force fit on every raw reading, the linear solver in the
limit where both must agree, the Cramér–Rao bound and a Monte-Carlo spread.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.optimize import least_squares

from ftkin import (
    InvalidInput,
    Samples,
    SensorModel,
    SensorNoise,
    SimulatedSensor,
    calibrate,
    load_calibration,
    save_calibration,
)
from ftkin.calibration import fisher_information
from ftkin.calibration.information import (
    EXTENDED_NAMES,
    covariance_from_information,
    derived_gradients,
    extended_parameters,
    extended_standard_errors,
    standard_errors,
)
from ftkin.calibration.ml import WeightedProblem, _solve, fit_ml, noise_from_spread
from ftkin.cli import main
from ftkin.io.calibration_file import calibration_to_dict
from ftkin.io.csv_table import write_csv
from ftkin.sim.paper import PAPER_G, paper_samples

NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]


# ------------------------------------------------------------------ truth
@pytest.mark.parametrize("noise", [NOISE, None], ids=["noise given", "noise estimated"])
def test_noise_free_data_give_the_truth(tool, rotations, noise):
    samples = Samples(tool.predict(rotations), rotations)
    result = calibrate(samples, noise=noise)
    assert result.method == "ml"
    np.testing.assert_allclose(result.to_vector(), tool.to_vector(), rtol=0, atol=1e-9)
    assert abs(result.tool_weight - tool.tool_weight) < 1e-9


def test_solver_reaches_the_truth_from_a_poor_start(tool, rotations):
    """Not just the linear start handed back: 1 N, 0.1 N·m and 2 cm off, it still converges."""
    problem = WeightedProblem(
        rotations, tool.predict(rotations), np.ones(len(rotations)), NOISE.channel_std
    )
    start = (
        tool.to_vector() + np.r_[1.0, -1.0, 0.5, 1.0, 1.0, -1.0, 0.1, -0.1, 0.1, 0.02, -0.02, 0.02]
    )
    theta, _ = _solve(problem, start, "linear")
    np.testing.assert_allclose(theta, tool.to_vector(), rtol=0, atol=1e-9)


def test_fit_on_pose_means_equals_fit_on_every_reading(tool, rotations, rng):
    """Weighting pose means by counts is the fit over all raw readings (brute force, numeric
    Jacobian).
    """
    counts = rng.integers(1, 6, size=len(rotations))
    repeated = np.repeat(rotations, counts, axis=0)
    pose_ids = np.repeat(np.arange(len(rotations)), counts)
    raw = SimulatedSensor(tool, NOISE).read(repeated, rng)
    result = calibrate(Samples(raw, repeated, pose_ids), noise=NOISE)

    def every_reading(theta):
        return (
            (raw - SensorModel.from_vector(theta).predict(repeated)) / NOISE.channel_std
        ).ravel()

    brute = least_squares(
        every_reading, result.to_vector() + 1e-3, xtol=1e-14, ftol=1e-14, gtol=1e-14
    )
    np.testing.assert_allclose(result.to_vector(), brute.x, rtol=0, atol=1e-8)
    assert result.sample_count == counts.sum()


# ---------------------------------------------------------------- paper data
def test_paper_data_agree_with_the_linear_method_within_the_standard_errors():
    """The paper's data are not noise-free (residual RMS 0.02 N on 3 N), so the two fits differ
    by more than the printed digits; they agree to within half a standard error."""
    linear = calibrate(paper_samples(), method="linear", g=PAPER_G)
    ml = calibrate(paper_samples(), g=PAPER_G)
    sigma = extended_standard_errors(ml, ml.covariance)
    assert np.all(np.isfinite(sigma)) and np.all(sigma > 0)
    assert np.all(np.abs(extended_parameters(ml) - extended_parameters(linear)) < 0.6 * sigma)
    assert ml.diagnostics.noise_source == "residuals"
    assert ml.std_errors["tool_weight"] == pytest.approx(sigma[12])
    assert "3.154 ± 0.022 N" in ml.summary()


def test_paper_data_with_uninformative_torques_give_the_papers_force_step():
    """With torque noise → ∞ the gravity and force bias come from the forces alone:
    exactly the paper's step 1, which reproduces its printed digits."""
    linear = calibrate(paper_samples(), method="linear", g=PAPER_G)
    ml = calibrate(paper_samples(), g=PAPER_G, noise=SensorNoise(0.02, 1e6))
    np.testing.assert_allclose(ml.gravity_in_base, linear.gravity_in_base, rtol=0, atol=1e-9)
    np.testing.assert_allclose(ml.force_offset, linear.force_offset, rtol=0, atol=1e-9)
    # the paper's printed digits: within half a unit of the last one
    np.testing.assert_allclose(ml.base_tilt_deg, [-0.204, -0.129], rtol=0, atol=5e-4)


# ------------------------------------------------------------ standard errors
def test_delta_method_gradients_match_finite_differences(tool):
    theta = tool.to_vector()

    def derived(t):
        model = SensorModel.from_vector(t)
        return np.array([model.tool_weight, *model.base_tilt])

    step = 1e-6
    numeric = np.column_stack(
        [(derived(theta + step * e) - derived(theta - step * e)) / (2 * step) for e in np.eye(12)]
    )
    grads = derived_gradients(tool.gravity_in_base)
    analytic = np.vstack([grads["tool_weight"], grads["base_tilt_u"], grads["base_tilt_v"]])
    np.testing.assert_allclose(analytic, numeric, rtol=1e-6, atol=1e-9)


def test_extended_standard_errors_are_the_named_ones_and_the_delta_method(tool, rotations):
    covariance = covariance_from_information(fisher_information(tool, rotations, NOISE))
    sigma = extended_standard_errors(tool, covariance)
    named = standard_errors(tool, covariance)
    np.testing.assert_allclose(sigma[:12], np.sqrt(np.diag(covariance)), rtol=1e-12, atol=0)
    np.testing.assert_allclose(
        sigma,
        np.concatenate(
            [
                named[key]
                for key in ("gravity_in_base", "force_offset", "torque_offset", "center_of_mass")
            ]
            + [[named["tool_weight"]], named["base_tilt"]]
        ),
        rtol=1e-12,
        atol=0,
    )
    assert named["tool_mass"] == pytest.approx(named["tool_weight"] / tool.g)
    grads = derived_gradients(tool.gravity_in_base)
    for index, key in zip((12, 13, 14), ("tool_weight", "base_tilt_u", "base_tilt_v")):
        assert sigma[index] == pytest.approx(
            np.sqrt(grads[key] @ covariance @ grads[key]), rel=1e-12
        )
    assert len(EXTENDED_NAMES) == 15 and EXTENDED_NAMES[12:] == (
        "tool_weight",
        "base_tilt[u]",
        "base_tilt[v]",
    )
    np.testing.assert_array_equal(
        extended_parameters(tool)[12:], [tool.tool_weight, *tool.base_tilt]
    )


@pytest.mark.parametrize(
    "call, message",
    [
        (lambda m, r: standard_errors(m, np.eye(3)), r"covariance must have shape \(12, 12\)"),
        (
            lambda m, r: extended_standard_errors(m, np.full((12, 12), np.nan)),
            "covariance must be finite",
        ),
        (
            lambda m, r: covariance_from_information(np.eye(3)),
            r"information must have shape \(12, 12\)",
        ),
        (lambda m, r: covariance_from_information("x"), "information must be numeric"),
        (
            lambda m, r: fisher_information(m, r, (0.03, 0.0015)),
            "noise must be an ftkin.SensorNoise, got tuple",
        ),
        (
            lambda m, r: fisher_information(m, r, NOISE, [1, 2]),
            r"readings_per_pose must be a scalar or have shape \(12,\)",
        ),
        (
            lambda m, r: fisher_information(m, r, NOISE, 0),
            "readings_per_pose must be finite and positive",
        ),
    ],
)
def test_information_functions_refuse_bad_input(tool, rotations, call, message):
    with pytest.raises(InvalidInput, match=message):
        call(tool, rotations)


@pytest.mark.parametrize(
    "readings, given", [(1, True), (4, False)], ids=["noise given", "noise from spread"]
)
def test_standard_errors_match_the_monte_carlo_spread(tool, rotations, readings, given):
    rng = np.random.default_rng(2024)
    sensor = SimulatedSensor(tool, NOISE)
    trials = 300
    estimates, reported = np.empty((trials, 15)), np.empty((trials, 15))
    for trial in range(trials):
        result = calibrate(sensor.samples(rotations, rng, readings), noise=NOISE if given else None)
        estimates[trial] = extended_parameters(result)
        reported[trial] = extended_standard_errors(result, result.covariance)
    spread = np.std(estimates, axis=0, ddof=1)
    mean_reported = np.mean(reported, axis=0)
    np.testing.assert_allclose(mean_reported, spread, rtol=0.2)
    # and the reported errors are the Cramér–Rao bound (ml is efficient)
    crlb = extended_standard_errors(
        tool, covariance_from_information(fisher_information(tool, rotations, NOISE, readings))
    )
    np.testing.assert_allclose(mean_reported, crlb, rtol=0.05)
    assert np.all(
        np.abs(np.mean(estimates, axis=0) - extended_parameters(tool)) < 0.3 * crlb
    )  # unbiased (σ/√300 = 0.06σ)


# ---------------------------------------------------------------- noise levels
def test_noise_from_spread_and_from_residuals_find_the_true_levels(tool, rotations, rng):
    noise = SensorNoise([0.02, 0.03, 0.05], [0.001, 0.002, 0.0015])
    samples = SimulatedSensor(tool, noise).samples(rotations, rng, 200)
    spread, dof = noise_from_spread(samples.pose_averages())
    assert dof == 12 * 199
    np.testing.assert_allclose(spread, noise.channel_std, rtol=0.05)
    assert calibrate(samples).diagnostics.noise_source == "spread"
    # one reading per pose: from the residuals, forces and torques pooled (60 poses)
    single = SimulatedSensor(tool, NOISE).samples(np.tile(rotations, (5, 1, 1)), rng)
    from_residuals = fit_ml(single.pose_averages())
    assert from_residuals.noise_source == "residuals"
    np.testing.assert_allclose(from_residuals.noise.channel_std, NOISE.channel_std, rtol=0.15)


def test_given_noise_scales_the_covariance_but_not_the_estimate(tool, rotations, rng):
    samples = SimulatedSensor(tool, NOISE).samples(rotations, rng)
    once = calibrate(samples, noise=NOISE)
    doubled = calibrate(samples, noise=SensorNoise(0.06, 0.003))
    np.testing.assert_allclose(doubled.to_vector(), once.to_vector(), rtol=0, atol=1e-10)
    np.testing.assert_allclose(doubled.covariance, 4 * once.covariance, rtol=1e-6)


# --------------------------------------------------------------- input errors
@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"method": "bayes"}, "unknown calibration method 'bayes'; expected one of ml, linear"),
        ({"loss": "cauchy"}, "unknown loss 'cauchy'; expected one of linear, soft_l1, huber"),
        ({"noise": (0.03, 0.0015)}, "noise must be an ftkin.SensorNoise, got tuple"),
        ({"method": "linear", "drop_outliers": True}, r"apply to method='ml' \(--method ml\) only"),
    ],
)
def test_bad_options_are_refused(tool, rotations, kwargs, message):
    with pytest.raises(InvalidInput, match=message):
        calibrate(Samples(tool.predict(rotations), rotations), **kwargs)


# ------------------------------------------------------------ file and CLI
def test_calibration_file_round_trip_keeps_errors_and_diagnostics(tool, rotations, rng, tmp_path):
    result = calibrate(SimulatedSensor(tool, NOISE).samples(rotations, rng, 3))
    path = save_calibration(result, tmp_path / "calib.json")
    loaded = load_calibration(path)
    np.testing.assert_array_equal(loaded.covariance, result.covariance)
    assert loaded.diagnostics.to_dict() == result.diagnostics.to_dict()
    assert loaded.summary() == result.summary()
    document = json.loads(path.read_text())
    assert set(document["std_errors"]) >= {
        "gravity_in_base",
        "force_offset",
        "torque_offset",
        "center_of_mass",
        "tool_weight",
        "tool_mass",
        "base_tilt_deg",
    }
    np.testing.assert_allclose(
        document["std_errors"]["base_tilt_deg"], np.rad2deg(result.std_errors["base_tilt"])
    )


def test_version_1_file_without_covariance_or_diagnostics_still_loads(
    tool, rotations, rng, tmp_path
):
    document = calibration_to_dict(calibrate(SimulatedSensor(tool, NOISE).samples(rotations, rng)))
    for key in ("covariance", "std_errors", "diagnostics"):
        document.pop(key)
    path = tmp_path / "old.json"
    path.write_text(json.dumps(document))
    loaded = load_calibration(path)
    assert loaded.covariance is None and loaded.diagnostics is None and loaded.std_errors is None
    assert "±" not in loaded.summary()


def _write_samples_csv(path, arm, configurations, wrenches, pose_ids):
    header = [*arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz", "pose"]
    rows = [[*q, *w, int(p)] for q, w, p in zip(configurations, wrenches, pose_ids)]
    write_csv(path, header, rows)


def test_cli_calibrate_ml_prints_errors_and_diagnostics(arm, tool, tmp_path, capsys):
    rng = np.random.default_rng(3)
    configurations = np.repeat(arm.random_configurations(12, rng, margin=0.3), 5, axis=0)
    wrenches = SimulatedSensor(tool, NOISE).read(arm.rotation_sensor_to_base(configurations), rng)
    csv = tmp_path / "samples.csv"
    _write_samples_csv(csv, arm, configurations, wrenches, np.repeat(np.arange(12), 5))
    out = tmp_path / "calib.json"
    assert main(["calibrate", str(csv), "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert "method ml" in text and "±" in text
    assert "noise per reading (from the spread of repeated readings)" in text
    assert "condition number" in text and "goodness of fit" in text
    assert load_calibration(out).diagnostics.noise_source == "spread"
    assert (
        main(
            [
                "calibrate",
                str(csv),
                "--noise-force",
                "0.03",
                "--noise-torque",
                "0.0015",
                "--loss",
                "huber",
            ]
        )
        == 0
    )
    text = capsys.readouterr().out
    assert (
        "noise per reading (given): force [0.0300, 0.0300, 0.0300] N" in text
        and "loss huber" in text
    )
    assert main(["calibrate", str(csv), "--method", "linear"]) == 0
    assert "±" not in capsys.readouterr().out


@pytest.mark.parametrize(
    "extra, message",
    [
        (["--noise-force", "0.03"], "give both --noise-force"),
        (["--method", "linear", "--drop-outliers"], "(--method ml) only"),
    ],
)
def test_cli_calibrate_refuses_inconsistent_options(arm, tool, tmp_path, capsys, extra, message):
    rng = np.random.default_rng(4)
    configurations = arm.random_configurations(6, rng, margin=0.3)
    csv = tmp_path / "samples.csv"
    _write_samples_csv(
        csv,
        arm,
        configurations,
        tool.predict(arm.rotation_sensor_to_base(configurations)),
        np.arange(6),
    )
    assert main(["calibrate", str(csv), *extra]) == 2
    assert message in capsys.readouterr().err


def test_cli_paper_keeps_the_linear_reproduction_and_adds_ml(capsys):
    assert main(["paper"]) == 0
    text = capsys.readouterr().out
    linear_part, ml_part = text.split("maximum-likelihood fit")
    assert "method linear" in linear_part and "NO" not in linear_part.split("quantity")[1]
    assert "method ml" in ml_part and "tool_weight     G  = 3.154 ± 0.022 N" in ml_part


def test_noise_from_residuals_is_unbiased_thanks_to_the_leverage_correction(tool, rotations):
    """Without the correction for the 12 fitted parameters the variance would come out 6P/(6P-12) =
    1.2x small.
    """
    rng = np.random.default_rng(11)
    sensor = SimulatedSensor(tool, NOISE)
    variances = np.array(
        [
            fit_ml(sensor.samples(rotations, rng).pose_averages()).noise.channel_std ** 2
            for _ in range(200)
        ]
    )
    np.testing.assert_allclose(variances.mean(axis=0) / NOISE.channel_std**2, 1.0, atol=0.06)
