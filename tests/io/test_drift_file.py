"""Calibration file format 2: the bias trajectory round trip, old files, malformed drift; the
samples CSV 't' column.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from ftkin import (
    CalibrationFileError,
    SensorNoise,
    SimulatedSensor,
    calibrate,
    load_calibration,
    load_samples,
    save_calibration,
)
from ftkin.io.calibration_file import FORMAT_VERSION
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import recording_times

OLD = Path(__file__).parent / "data" / "calibration_v1.json"


def test_a_format_1_file_still_loads():
    stored = json.loads(OLD.read_text())
    assert stored["version"] == 1 and FORMAT_VERSION == 2
    result = load_calibration(OLD)
    assert result.drift is None
    np.testing.assert_allclose(result.force_offset, stored["force_offset"], rtol=1e-12, atol=0)
    np.testing.assert_allclose(result.covariance, stored["covariance"], rtol=1e-12, atol=1e-300)
    assert result.diagnostics is not None
    np.testing.assert_allclose(result.bias_at([0.0, 1e6]), np.tile(result.bias, (2, 1)), rtol=1e-12)


@pytest.fixture(scope="module")
def drifting(arm, truth):
    rng = np.random.default_rng(4)
    configurations = arm.random_configurations(16, rng, margin=0.3)
    times = recording_times(16, 3, 480.0, 0.02)
    drift = np.outer(times / 480.0, [0.2, -0.1, 0.1, 0.003, 0.0, 0.001])
    return SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, configurations, rng, 3, times=times, bias_drift=drift
    )


@pytest.mark.parametrize("drift", ["poly:2", "random-walk", "none"])
def test_the_bias_trajectory_round_trips_bit_for_bit(drifting, tmp_path, drift):
    result = calibrate(drifting, drift=drift)
    save_calibration(result, tmp_path / "c.json")
    loaded = load_calibration(tmp_path / "c.json")
    assert loaded.drift.model == result.drift.model
    for name in ("times", "bias", "bias_std", "recorded_span"):
        np.testing.assert_array_equal(getattr(loaded.drift, name), getattr(result.drift, name))
    probe = np.linspace(-10.0, 600.0, 23)
    # the stored numbers round-trip exactly (repr); the bias computed from them within 1e-12
    np.testing.assert_allclose(loaded.bias_at(probe), result.bias_at(probe), rtol=1e-12, atol=1e-15)
    assert loaded.drift.criteria == result.drift.criteria


def test_a_malformed_drift_names_its_key(drifting, tmp_path):
    save_calibration(calibrate(drifting, drift="poly:1"), tmp_path / "c.json")
    document = json.loads((tmp_path / "c.json").read_text())
    bias = document["drift"]["bias"]
    document["drift"]["bias"] = bias[:-1]
    (tmp_path / "c.json").write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="drift.bias"):
        load_calibration(tmp_path / "c.json")
    for wrong in (3, "x", [[1.0] * 6] * 3):  # not poly:1's coefficient rows of six numbers
        document["drift"]["bias"] = bias
        document["drift"]["coefficients"] = wrong
        (tmp_path / "c.json").write_text(json.dumps(document))
        with pytest.raises(CalibrationFileError, match="drift.coefficients"):
            load_calibration(tmp_path / "c.json")
    document["drift"] = {"model": "wobble"}
    (tmp_path / "c.json").write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="unknown drift model"):
        load_calibration(tmp_path / "c.json")


def test_the_csv_time_column_becomes_samples_times(drifting, tmp_path):
    header = ["t", "pose", *[f"q{i + 1}" for i in range(6)], "fx", "fy", "fz", "mx", "my", "mz"]
    rows = [
        [t, int(p), *q, *w]
        for t, p, q, w in zip(
            drifting.times, drifting.pose_ids, drifting.joint_positions, drifting.wrenches
        )
    ]
    write_csv(tmp_path / "s.csv", header, rows)
    loaded = load_samples(tmp_path / "s.csv").samples
    np.testing.assert_array_equal(loaded.times, drifting.times)
    write_csv(tmp_path / "n.csv", header[1:], [row[1:] for row in rows])
    assert load_samples(tmp_path / "n.csv").samples.times is None


@pytest.mark.parametrize(
    ("change", "match"),
    [
        ({"model": "banana"}, "unknown drift model"),
        ({"model": "auto"}, "unknown drift model"),
        ({"rate": [-1.0, float("nan")]}, "rate must be"),
        ({"time_scale": 0.0}, "time_scale must be"),
        ({"coefficients": np.zeros((1, 5))}, "coefficients must be"),
        ({"coefficients": 1.0}, "coefficients must be"),
        ({"coefficients": np.zeros((3, 6))}, "coefficients must be"),
        ({"selected_by": "me"}, "selected_by"),
    ],
)
def test_a_bias_drift_refuses_what_no_fit_gives(change, match):
    from ftkin.calibration.drift import BiasDrift
    from ftkin.exceptions import InvalidInput

    arguments = dict(
        model="poly:1",
        selected_by="given",
        times=[0.0, 1.0],
        bias=np.zeros((2, 6)),
        bias_std=np.zeros((2, 6)),
    )
    with pytest.raises(InvalidInput, match=match):
        BiasDrift(**{**arguments, **change})
