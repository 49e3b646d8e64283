"""Every key of a calibration file: ``null``, a string, a boolean or a list where a number belongs
(or a number where a string belongs) is refused with a CalibrationFileError naming the key, never an
internal error; an unknown or future format version names the versions this ftkin reads.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

import ftkin
from ftkin import Arm, calibrate, load_calibration, save_calibration
from ftkin.calibration.information import SensorNoise
from ftkin.io.calibration_file import FORMAT_VERSION, calibration_to_dict
from ftkin.kinematics.record import KinematicsRecord
from ftkin.sim.sensor import SimulatedSensor


@pytest.fixture(scope="module")
def document(arm, truth):
    """A calibration with drift, diagnostics, covariance and kinematics: every kind of key."""
    rng = np.random.default_rng(3)
    q = arm.random_configurations(10, rng, margin=0.3)
    times = 60.0 * np.arange(20)  # [s]
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(
        arm, q, rng, 2, times=times
    )
    result = calibrate(samples, drift="random-walk")
    from dataclasses import replace

    result = replace(result, kinematics=KinematicsRecord.from_arm(Arm.default()))
    return calibration_to_dict(result)


def leaves(document, prefix=()):
    """``(path, value)`` of every key, nested objects included."""
    for key, value in document.items():
        yield (*prefix, key), value
        if isinstance(value, dict):
            yield from leaves(value, (*prefix, key))


def is_numeric(value) -> bool:
    if isinstance(value, list):
        return bool(value) and all(map(is_numeric, value))
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def load_changed(tmp_path, document, path, value):
    changed = json.loads(json.dumps(document))
    parent = changed
    for key in path[:-1]:
        parent = parent[key]
    parent[path[-1]] = value
    file = tmp_path / "changed.json"
    file.write_text(json.dumps(changed))
    return load_calibration(file)


def test_every_key_refuses_the_wrong_json_type(document, tmp_path):
    checked = 0
    for path, original in leaves(document):
        if path[0] == "units" or not (is_numeric(original) or isinstance(original, str)):
            continue
        wrong = ["1.5", True, ["1.5"]] if is_numeric(original) else [1.5, ["x"]]
        if is_numeric(original) and isinstance(original, list):
            wrong.append([True] * len(original))
        for value in wrong:
            with pytest.raises(ftkin.CalibrationFileError) as info:
                load_changed(tmp_path, document, path, value)
            assert info.value.key is not None and path[0] in info.value.key, (path, value)
            checked += 1
    assert checked > 60


def test_null_is_a_missing_value_or_refused_naming_the_key(document, tmp_path):
    for path, _ in leaves(document):
        try:
            result = load_changed(tmp_path, document, path, None)
        except ftkin.CalibrationFileError as error:
            assert error.key is not None, path  # the key, or the one it disagrees with
        else:
            assert np.all(np.isfinite(result.to_vector())), path


@pytest.mark.parametrize("version", [FORMAT_VERSION + 1, 0, -3, "2", 2.0, True, None])
def test_unknown_or_future_versions_name_the_supported_ones(document, tmp_path, version):
    with pytest.raises(ftkin.CalibrationFileError, match=f"reads versions 1 to {FORMAT_VERSION}"):
        load_changed(tmp_path, document, ("version",), version)


@pytest.mark.parametrize("key", ["force_offset", "center_of_mass", "gravity_in_base"])
def test_null_inside_a_parameter_is_named(document, tmp_path, key):
    with pytest.raises(ftkin.CalibrationFileError, match="expected numbers of shape .*got null"):
        load_changed(tmp_path, document, (key,), [1.0, None, 2.0])


def test_strings_in_diagnostics_are_not_numbers(document, tmp_path):
    with pytest.raises(ftkin.CalibrationFileError, match="expected a number, got '0.5'") as info:
        load_changed(tmp_path, document, ("diagnostics", "p_value"), "0.5")
    assert info.value.key == "diagnostics.p_value"


def test_round_trip_keeps_every_key(document, tmp_path):
    file = tmp_path / "c.json"
    file.write_text(json.dumps(document))
    again = tmp_path / "again.json"
    save_calibration(load_calibration(file), again)
    assert json.loads(again.read_text()).keys() == document.keys()
    np.testing.assert_allclose(
        load_calibration(again).to_vector(), load_calibration(file).to_vector(), rtol=1e-12
    )
