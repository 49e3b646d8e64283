"""A calibration file that is inconsistent is refused, naming the key: never loaded while wrong."""

from __future__ import annotations

import json

import numpy as np
import pytest

import ftkin
from ftkin import calibrate, load_calibration, save_calibration
from ftkin.calibration.information import SensorNoise
from ftkin.sim.sensor import SimulatedSensor


@pytest.fixture(scope="module")
def document(arm, truth, tmp_path_factory):
    rng = np.random.default_rng(8)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, arm.random_configurations(8, rng, margin=0.3), rng, 3
    )
    path = tmp_path_factory.mktemp("rules") / "c.json"
    save_calibration(calibrate(samples), path)
    return json.loads(path.read_text())


def _refused(tmp_path, document, change, key, pattern, raw=None):
    changed = json.loads(json.dumps(document))
    if change is not None:
        change(changed)
    path = tmp_path / "edited.json"
    path.write_text(raw if raw is not None else json.dumps(changed))
    with pytest.raises(ftkin.CalibrationFileError, match=pattern) as info:
        load_calibration(path)
    assert info.value.key == key
    return str(info.value)


def test_the_unedited_file_loads(document, tmp_path):
    path = tmp_path / "ok.json"
    path.write_text(json.dumps(document))
    assert load_calibration(path).pose_count == 8


@pytest.mark.parametrize(
    "key, value",
    [
        ("force_offset", [True, 0.0, 0.0]),
        ("g", True),
        ("center_of_mass", [0.0, False, 0.0]),
        ("torque_offset", [[True], 0, 0]),
    ],
)
def test_booleans_are_not_numbers(document, tmp_path, key, value):
    _refused(tmp_path, document, lambda d: d.__setitem__(key, value), key, "boolean|finite number")


def test_derived_fields_must_agree(document, tmp_path):
    weight = document["tool_weight"]
    message = _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("tool_weight", weight * 1.01),
        "tool_weight",
        "disagrees",
    )
    assert f"{weight * 1.01}" in message and f"{weight}" in message  # both values named
    mass = document["tool_mass"]
    _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("tool_mass", mass * 2),
        "tool_mass",
        f"{mass * 2} kg disagrees",
    )
    tilt = document["base_tilt_deg"]
    _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("base_tilt_deg", [tilt[0] + 1.0, tilt[1]]),
        "base_tilt_deg",
        "disagrees with the tilt of gravity_in_base",
    )
    _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("pose_count", 3),
        "pose_count",
        "disagrees with the 8 pose ids",
    )


def test_covariance_must_be_symmetric_positive_semidefinite(document, tmp_path):
    covariance = np.array(document["covariance"])
    asymmetric = covariance.copy()
    asymmetric[0, 5] += 1e-3 * np.abs(covariance).max()
    _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("covariance", asymmetric.tolist()),
        "covariance",
        "not symmetric",
    )
    values, vectors = np.linalg.eigh(covariance)
    values[0] = -0.5 * values[-1]
    indefinite = vectors @ np.diag(values) @ vectors.T
    _refused(
        tmp_path,
        document,
        lambda d: d.__setitem__("covariance", indefinite.tolist()),
        "covariance",
        "not positive semi-definite",
    )


def test_duplicate_keys_are_refused(document, tmp_path):
    text = json.dumps(document)
    raw = text[:-1] + ', "g": 1.62}'  # the Moon's g, given twice at the top level
    _refused(tmp_path, document, None, "g", "duplicate key", raw=raw)
    nested = text.replace('"ids": ', '"ids": [], "ids": ', 1)
    _refused(tmp_path, document, None, "ids", "duplicate key", raw=nested)


@pytest.mark.parametrize("key", ["sample_count", "pose_count"])
def test_negative_counts_are_refused(document, tmp_path, key):
    _refused(tmp_path, document, lambda d: d.__setitem__(key, -3), key, "expected a count")


def test_non_finite_literals_name_the_key(document, tmp_path):
    _refused(
        tmp_path, document, lambda d: d.__setitem__("g", float("nan")), "g", "finite number"
    )  # written as NaN
    _refused(
        tmp_path,
        document,
        None,
        "g",
        "finite number",
        raw=json.dumps(document)[:-1].replace('"g": 9', '"g": 1e999, "_": 9') + "}",
    )


def test_booleans_in_diagnostics_are_not_numbers(document, tmp_path):
    _refused(
        tmp_path,
        document,
        lambda d: d["diagnostics"].__setitem__("chi_square", True),
        "diagnostics.chi_square",
        "expected a number, got true",
    )


def test_a_dotted_top_level_key_is_not_the_inertia_std_errors(document):
    # std_errors.inertia lives inside std_errors; a top-level key spelled so is not read
    from ftkin.io.calibration_file import calibration_from_dict

    changed = json.loads(json.dumps(document))
    changed["inertia"] = [[1e-3, 0.0, 0.0], [0.0, 1e-3, 0.0], [0.0, 0.0, 1e-3]]
    changed["std_errors.inertia"] = [[1.0, 2.0, 3.0], [4.0, 5.0, 6.0], [7.0, 8.0, 9.0]]
    result = calibration_from_dict(changed)
    assert result.inertia_std_errors is None
    changed["std_errors"]["inertia"] = np.full((3, 3), 1e-5).tolist()
    result = calibration_from_dict(changed)
    np.testing.assert_allclose(result.inertia_std_errors, 1e-5, rtol=1e-12)


def test_the_mount_fields_must_agree(document, tmp_path):
    """mount_rotation turned 90° about z (by hand) with mount_rpy_deg left at zero, or with the
    mode left at 'none', compensated with a 90° error in silence."""
    yaw90 = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]

    def turned(document, rpy):
        document["mount_rotation"] = yaw90
        document["mount_rpy_deg"] = rpy

    _refused(
        tmp_path,
        document,
        lambda d: turned(d, [0.0, 0.0, 0.0]),
        "mount_rpy_deg",
        r"disagrees with mount_rotation, whose roll-pitch-yaw is \[0.0, -?0.0, 90.0\]",
    )
    _refused(
        tmp_path,
        document,
        lambda d: turned(d, [0.0, 0.0, 90.0]),
        "mount_rotation",
        r"mount_mode 'none' but mount_rotation turns the sensor by 90°",
    )
    half = json.loads(json.dumps(document))  # a yaw of 180° is one of -180°: the same rotation
    half.update(
        mount_rotation=[[-1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]],
        mount_rpy_deg=[0.0, 0.0, -180.0],
        mount_mode="yaw",
        mount_covariance=[[1e-6]],
    )
    path = tmp_path / "half.json"
    path.write_text(json.dumps(half))
    assert load_calibration(path).mount_rotation[0, 0] == pytest.approx(-1.0, abs=1e-12)
