"""A drift model added from this file alone: an exponential warm-up.

It registers under ``warmup`` and then ``calibrate``, ``Compensator``, the
calibration file and ``ftkin calibrate --drift`` all use it, with no change to
ftkin. The numbers are checked against the simulated truth (an independent
computation: the simulator's own warm-up formula).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from ftkin import (
    Compensator,
    InvalidInput,
    SensorNoise,
    SimulatedSensor,
    calibrate,
    load_calibration,
    save_calibration,
)
from ftkin.calibration import DriftModel, register_drift_model
from ftkin.calibration.drift import DRIFT_MODELS, auto_candidates, drift_choices, parse_drift
from ftkin.cli import main
from ftkin.io.csv_table import write_csv
from ftkin.sim import SensorDrift
from ftkin.sim.sensor import recording_times

SPAN, POSES, READINGS = 1200.0, 30, 3  # recording [s], poses, readings per pose
RATIO = 4.0  # recording span over the warm-up's time constant [-]
NOISE = SensorNoise(0.03, 0.0015)  # per reading [N], [N·m]
WARMUP = np.array([0.5, -0.4, 0.3, 0.01, -0.008, 0.006])  # amplitude [N, N·m]


# --------------------------------------------------------------- the new model (its module)
@dataclass(frozen=True)
class WarmupDrift(DriftModel):
    """``b(t) = b(T) + c (e^{−r} − e^{−r (τ + 1)})``, ``τ = (t − T)/span``: a warm-up from the
    first pose with a time constant ``span / r``.
    """

    ratio: float = RATIO

    def basis(self, tau):
        return (np.exp(-self.ratio) - np.exp(-self.ratio * (np.asarray(tau) + 1.0)))[:, None]


def warmup(argument):
    ratio = RATIO if argument is None else float(argument)
    return WarmupDrift("warmup" if argument is None else f"warmup:{argument}", 1, ratio=ratio)


@pytest.fixture
def registered():
    register_drift_model("warmup", warmup, usage="warmup[:R]")  # its registration
    yield
    DRIFT_MODELS.pop("warmup")


# --------------------------------------------------------------------------------- data
@pytest.fixture(scope="module")
def recording(arm, tool):
    rng = np.random.default_rng(8)
    configurations = arm.random_configurations(POSES, rng, margin=0.3)
    times = recording_times(POSES, READINGS, SPAN, 0.01)
    drift = SensorDrift(warmup=WARMUP, warmup_time_constant=SPAN / RATIO)
    sensor = SimulatedSensor(tool, NOISE, drift)
    samples = sensor.samples_at_configurations(arm, configurations, rng, READINGS, times=times)
    return samples, tool.bias + drift.deterministic(times)


def test_the_registry_knows_it_only_while_registered(registered):
    assert "warmup[:R]" in drift_choices() and "warmup" not in auto_candidates()
    assert parse_drift("warmup:2").ratio == 2.0
    assert parse_drift("random-walk+warmup").walk and parse_drift("random-walk+warmup").columns == 1
    with pytest.raises(InvalidInput, match="taken"):
        register_drift_model("warmup", warmup)


def test_the_registry_refuses_what_it_does_not_know():
    with pytest.raises(InvalidInput, match="unknown drift model 'warmup'"):
        parse_drift("warmup")
    for spec, match in (
        ("poly", "needs its degree"),
        ("poly:x", "needs its degree"),
        ("none+poly:1", "at most one walk"),
        ("poly:1+poly:2", "at most one walk"),
        ("random-walk:3", "takes no argument"),
        ("auto", "unknown drift model"),
    ):
        with pytest.raises(InvalidInput, match=match):
            parse_drift(spec)


def test_calibrate_fits_the_new_model(registered, recording, tool):
    samples, true_bias = recording
    result = calibrate(samples, drift="warmup")
    assert result.drift.model == "warmup" and result.drift.coefficients.shape == (1, 6)
    estimated = result.bias_at(samples.times)
    std = np.column_stack(
        [np.interp(samples.times, result.drift.times, s) for s in result.drift.bias_std.T]
    )
    assert np.all(np.abs(estimated - true_bias) < 4.5 * std)
    # the coefficient is the warm-up amplitude (time constant span/4 ≈ the simulator's 300 s)
    np.testing.assert_allclose(result.drift.coefficients[0], WARMUP, atol=0.1, rtol=0.3)
    errors = result.to_vector() - tool.to_vector()
    errors[3:9] = result.bias - true_bias[-1]
    assert np.all(np.abs(errors) < 4.5 * np.sqrt(np.diag(result.covariance)))
    # the walk around the new trend works too (the sum is parsed from the registry)
    assert calibrate(samples, drift="random-walk+warmup").drift.model == "random-walk+warmup"


def test_compensator_uses_the_new_model_at_reading_times(registered, recording, arm):
    samples, true_bias = recording
    result = calibrate(samples, drift="warmup")
    compensator = Compensator(result, arm)
    contact = compensator.compensate_batch(samples.rotations, samples.wrenches, samples.times)
    fixed = compensator.compensate_batch(samples.rotations, samples.wrenches)
    # truth: no contact; with the trajectory only noise and estimation error are left
    assert np.sqrt(np.mean(contact[:, :3] ** 2)) < 0.05
    assert np.sqrt(np.mean(fixed[:, :3] ** 2)) > 3 * np.sqrt(np.mean(contact[:, :3] ** 2))
    np.testing.assert_allclose(result.bias_at(samples.times[-1]), result.bias, rtol=1e-12)


def test_the_calibration_file_round_trips_the_new_model(registered, recording, tmp_path):
    result = calibrate(recording[0], drift="warmup:3")
    save_calibration(result, tmp_path / "c.json")
    loaded = load_calibration(tmp_path / "c.json")
    assert loaded.drift.model == "warmup:3" and loaded.drift.kind.ratio == 3.0
    probe = np.linspace(-10.0, SPAN + 10.0, 31)
    np.testing.assert_allclose(loaded.bias_at(probe), result.bias_at(probe), rtol=1e-12)


def test_the_cli_takes_the_new_model(registered, recording, tmp_path, capsys):
    samples = recording[0]
    header = ["t", "pose", *[f"q{i + 1}" for i in range(6)], "fx", "fy", "fz", "mx", "my", "mz"]
    rows = [
        [t, int(p), *q, *w]
        for t, p, q, w in zip(
            samples.times, samples.pose_ids, samples.joint_positions, samples.wrenches
        )
    ]
    write_csv(tmp_path / "s.csv", header, rows)
    output = tmp_path / "c.json"
    assert main(["calibrate", str(tmp_path / "s.csv"), "--drift", "warmup", "-o", str(output)]) == 0
    assert "bias drift: warmup (given)" in capsys.readouterr().out
    assert load_calibration(output).drift.model == "warmup"
    assert main(["calibrate", str(tmp_path / "s.csv"), "--drift", "wobble"]) == 2
    assert "unknown drift model 'wobble'" in capsys.readouterr().err


# ------------------------------------------------- a model with a fit of its own (the hook)
@dataclass(frozen=True)
class WarmupSearch(DriftModel):
    """The warm-up with its time constant unknown: it overrides ``fit`` with a search over the
    ratio (a nonlinear parameter of its own), each candidate fitted by the generic fit.
    """

    def fit(self, poses, start, selected_by="given"):
        from ftkin.calibration.drift_fit import fit_drift_model

        fits = [fit_drift_model(warmup(text), poses, start, selected_by) for text in SEARCHED]
        return max(fits, key=lambda fit: fit.log_likelihood)


SEARCHED = ("1", "4", "16")  # ratios [-]: the truth (RATIO) and a factor 4 either side


def test_a_model_with_a_fit_of_its_own_is_fitted_by_it(registered, recording):
    """The base ``DriftModel.fit`` returns None (the generic fit serves it); an override is used.

    The search picks the simulator's time constant (span / 4) among span, span / 4 and span / 16,
    and the file's model is the one it chose.
    """
    register_drift_model("warmup-search", lambda argument: WarmupSearch("warmup-search", 1))
    try:
        assert DriftModel().fit(None, None) is None
        result = calibrate(recording[0], drift="warmup-search")
    finally:
        DRIFT_MODELS.pop("warmup-search")
    assert result.drift.model == "warmup:4" and result.drift.kind.ratio == RATIO
