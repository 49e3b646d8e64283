"""The calibration file: bit-exact round trip, atomic writes, clear errors."""

from __future__ import annotations

import dataclasses
import json
import os
import re

import numpy as np
import pytest

import ftkin
from ftkin import Compensator, calibrate, load_calibration, save_calibration
from ftkin.calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
)
from ftkin.io.calibration_file import FORMAT_NAME, FORMAT_VERSION
from ftkin.sim.sensor import SimulatedSensor

ARRAY_FIELDS = (
    "force_offset",
    "torque_offset",
    "gravity_in_base",
    "center_of_mass",
    "pose_ids",
    "pose_wrenches",
    "residuals",
)


@pytest.fixture(scope="module")
def result(arm, truth):
    rng = np.random.default_rng(99)
    configurations = arm.random_configurations(7, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, configurations, rng, 4
    )
    calibrated = calibrate(samples, method="linear", g=9.8)
    information = fisher_information(
        calibrated, arm.rotation_sensor_to_base(configurations), SensorNoise.paper(), 4
    )
    return dataclasses.replace(calibrated, covariance=covariance_from_information(information))


@pytest.fixture
def saved(result, tmp_path):
    path = tmp_path / "calib.json"
    save_calibration(result, path)
    return path


def _edit(path, change):
    document = json.loads(path.read_text())
    change(document)
    path.write_text(json.dumps(document))
    return path


def test_round_trip_is_bit_exact(result, saved, arm, rng):
    loaded = load_calibration(saved)
    for name in ARRAY_FIELDS:
        np.testing.assert_array_equal(getattr(loaded, name), getattr(result, name), err_msg=name)
    np.testing.assert_array_equal(loaded.covariance, result.covariance)
    assert loaded.g == result.g == 9.8
    assert loaded.tool_weight == result.tool_weight and loaded.tool_mass == result.tool_mass
    assert loaded.base_tilt == result.base_tilt
    assert (loaded.method, loaded.sample_count, loaded.urdf, loaded.sensor_frame) == (
        result.method,
        result.sample_count,
        result.urdf,
        result.sensor_frame,
    )
    assert loaded.pose_count == result.pose_count
    for key, value in result.std_errors.items():
        np.testing.assert_array_equal(loaded.std_errors[key], value)
    # compensation with the loaded file is identical, not just close
    configurations = arm.random_configurations(20, rng)
    rotations = arm.rotation_sensor_to_base(configurations)
    raw = rng.normal(size=(20, 6))
    ours, theirs = Compensator(loaded, arm), Compensator(result, arm)
    np.testing.assert_array_equal(
        ours.compensate_batch(rotations, raw), theirs.compensate_batch(rotations, raw)
    )
    np.testing.assert_array_equal(
        ours.compensate(configurations[0], raw[0]), theirs.compensate(configurations[0], raw[0])
    )


def test_file_documents_units_and_provenance(result, saved):
    document = json.loads(saved.read_text())
    assert document["format"] == FORMAT_NAME and document["version"] == FORMAT_VERSION
    for key in (
        "force_offset",
        "torque_offset",
        "gravity_in_base",
        "tool_weight",
        "tool_mass",
        "center_of_mass",
        "base_tilt_deg",
        "g",
    ):
        assert key in document and key in document["units"], key
    assert document["base_tilt_deg"] == list(result.base_tilt_deg)
    assert document["tool_mass"] == result.tool_weight / 9.8
    assert (
        document["method"] == "linear"
        and document["pose_count"] == 7
        and document["sample_count"] == 28
    )
    assert document["urdf"].endswith("ftkin_c4.urdf") and document["sensor_frame"] == "ft_sensor"
    assert len(document["residual_rms"]) == 6


def test_model_without_poses_saves_and_loads(tmp_path, truth):
    # regression: residual_rms of a result without poses is NaN and json refused to write it
    bare = ftkin.CalibrationResult(
        force_offset=truth.force_offset,
        torque_offset=truth.torque_offset,
        gravity_in_base=truth.gravity_in_base,
        center_of_mass=truth.center_of_mass,
    )
    path = save_calibration(bare, tmp_path / "bare.json")
    loaded = load_calibration(path)
    np.testing.assert_array_equal(loaded.to_vector(), truth.to_vector())
    assert loaded.pose_count == 0


# ----------------------------------------------------------------- atomic
def test_failed_replace_leaves_old_file_intact(result, saved, monkeypatch, truth):
    before = saved.read_bytes()
    other = dataclasses.replace(result, method="other")

    def broken_replace(source, target):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(ftkin.FtkinError, match=f"cannot write {saved}.*No space left"):
        save_calibration(other, saved)
    assert saved.read_bytes() == before
    assert sorted(p.name for p in saved.parent.iterdir()) == [
        "calib.json"
    ]  # no stray temporary file


def test_failure_midway_through_writing_leaves_old_file_intact(result, saved, monkeypatch):
    before = saved.read_bytes()

    def broken_fsync(descriptor):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(os, "fsync", broken_fsync)
    with pytest.raises(ftkin.FtkinError, match="Input/output error"):
        save_calibration(dataclasses.replace(result, method="other"), saved)
    assert saved.read_bytes() == before
    assert load_calibration(saved).method == "linear"
    assert sorted(p.name for p in saved.parent.iterdir()) == ["calib.json"]


def test_writing_into_missing_folder(result, tmp_path):
    with pytest.raises(ftkin.FtkinError, match="folder .*nowhere does not exist"):
        save_calibration(result, tmp_path / "nowhere" / "calib.json")


# ----------------------------------------------------------------- errors
def _assert_error(path, pattern, key=None):
    with pytest.raises(ftkin.CalibrationFileError, match=pattern) as info:
        load_calibration(path)
    assert info.value.path == str(path)
    assert str(path) in str(info.value)
    assert info.value.key == key
    if key is not None:
        assert repr(key) in str(info.value)


def test_missing_file(tmp_path):
    _assert_error(tmp_path / "absent.json", "file not found")


def test_empty_file(tmp_path):
    path = tmp_path / "empty.json"
    path.write_text("  \n")
    _assert_error(path, "file is empty")


def test_truncated_json_gives_line_and_column(saved):
    text = saved.read_text()
    saved.write_text(text[: len(text) // 2])
    lines = text[: len(text) // 2].splitlines()
    with pytest.raises(
        ftkin.CalibrationFileError, match=r"not valid JSON .*at line (\d+), column (\d+)"
    ) as info:
        load_calibration(saved)
    line = int(str(info.value).split("at line ")[1].split(",")[0])
    assert len(lines) - 1 <= line <= len(lines) + 1


def test_not_a_json_object(tmp_path):
    path = tmp_path / "list.json"
    path.write_text("[1, 2, 3]")
    _assert_error(path, "expected a JSON object, got list")


def test_another_format(tmp_path):
    path = tmp_path / "other.json"
    path.write_text(json.dumps({"format": "ros-params", "version": 1}))
    _assert_error(path, "not an ftkin calibration file .*'ros-params'", key="format")


def test_newer_version_asks_to_upgrade(saved):
    _edit(saved, lambda d: d.update(version=FORMAT_VERSION + 1))
    _assert_error(
        saved, f"newer ftkin .*version {FORMAT_VERSION + 1}.*upgrade ftkin", key="version"
    )


def test_non_integer_version(saved):
    _edit(saved, lambda d: d.update(version="1"))
    _assert_error(saved, "expected an integer version", key="version")


@pytest.mark.parametrize(
    "key", ["force_offset", "torque_offset", "gravity_in_base", "center_of_mass", "g"]
)
def test_missing_key(saved, key):
    _edit(saved, lambda d: d.pop(key))
    _assert_error(saved, "missing", key=key)


def test_nan_values(saved):
    text = saved.read_text()
    document = json.loads(text)
    first = document["torque_offset"][0]
    saved.write_text(text.replace(repr(first), "NaN", 1))
    _assert_error(saved, "NaN or infinite", key="torque_offset")


def test_infinite_g(saved):
    _edit(saved, lambda d: d.update(g=float("inf")))
    _assert_error(saved, "expected a finite number", key="g")


def test_wrong_shape(saved):
    _edit(saved, lambda d: d.update(center_of_mass=[0.0, 0.1]))
    _assert_error(saved, r"expected shape \(3,\), got \(2,\)", key="center_of_mass")


def test_text_instead_of_numbers(saved):
    _edit(saved, lambda d: d.update(force_offset=["a", "b", "c"]))
    _assert_error(saved, "expected numbers of shape", key="force_offset")


def test_inconsistent_tool_weight(saved):
    _edit(saved, lambda d: d.update(tool_weight=d["tool_weight"] * 1.01))
    _assert_error(saved, "disagrees with |gravity_in_base|", key="tool_weight")


def test_covariance_of_wrong_shape(saved):
    _edit(saved, lambda d: d.update(covariance=[[1.0, 0.0], [0.0, 1.0]]))
    _assert_error(saved, r"expected shape \(12, 12\)", key="covariance")


def test_pose_arrays_must_match_ids(saved):
    _edit(saved, lambda d: d["poses"].update(residuals=d["poses"]["residuals"][:-1]))
    _assert_error(saved, r"expected shape \(7, 6\), got \(6, 6\)", key="poses.residuals")


@pytest.mark.parametrize(
    "key, value, expected",
    [("method", 5, "str"), ("urdf", ["a.urdf"], "str"), ("sample_count", "x", "int")],
)
def test_provenance_of_the_wrong_type(saved, key, value, expected):
    _edit(saved, lambda d: d.update({key: value}))
    _assert_error(saved, re.escape(f"expected {expected} or null, got {value!r}"), key=key)


def test_saving_a_bare_sensor_model_is_refused(tmp_path, truth):
    with pytest.raises(
        ftkin.InvalidInput, match="result must be an ftkin.CalibrationResult .*got SensorModel"
    ):
        save_calibration(truth, tmp_path / "model.json")


def test_non_finite_residuals_are_refused_when_saving(result, tmp_path):
    # regression: json's ValueError escaped instead of an ftkin error
    residuals = np.array(result.residuals)
    residuals[0, 0] = np.nan
    broken = dataclasses.replace(result, residuals=residuals)
    path = tmp_path / "broken.json"
    with pytest.raises(ftkin.CalibrationFileError, match=f"{path}: cannot write.*nan"):
        save_calibration(broken, path)
    assert not path.exists()
