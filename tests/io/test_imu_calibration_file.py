"""The calibration file of a calibration from the IMU: the common keys and the ``imu`` entry hold
the known values, load gives them back, and a broken entry is named."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.calibration.imu_result import ImuCalibrationResult
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.log_cholesky import parameters_from_body
from ftkin.control.imu_compensation import ImuCompensator
from ftkin.exceptions import CalibrationFileError
from ftkin.io.calibration_file import load_calibration, save_calibration

G = 9.80665
IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
BIAS = np.array([0.76, -0.30, 0.20])
MASS, COM = 1.7, np.array([0.01, -0.02, 0.08])
F0, M0 = np.array([1.0, -2.0, 0.5]), np.array([0.05, -0.02, 0.01])


def readings(rotations_ws, rng, count=30):
    """Static readings from first principles (gravity −z in the world, +g read at rest)."""
    accel, wrenches, ids = [], [], []
    for i, rotation in enumerate(rotations_ws):
        up = rotation.T @ np.array([0.0, 0.0, G])
        weight = -MASS * up
        accel.append(IMU_ROTATION.T @ up + BIAS + rng.normal(0, 0.02, (count, 3)))
        wrench = np.concatenate([F0 + weight, M0 + np.cross(COM, weight)])
        wrenches.append(wrench + rng.normal(0, 1, (count, 6)) * ([0.05] * 3 + [0.003] * 3))
        ids += [i] * count
    return np.concatenate(accel), np.concatenate(wrenches), np.array(ids)


def test_static_file_holds_the_truth_and_loads_back(tmp_path, rng):
    accel, wrenches, ids = readings(Rotation.random(12, random_state=2).as_matrix(), rng)
    result = ftkin.calibrate(
        ImuSamples.from_arrays(accel, wrenches, ids), imu_position=[0.02, 0, 0.03]
    )
    path = save_calibration(result, tmp_path / "imu.json")
    document = json.loads(path.read_text())
    assert document["tool_mass"] == pytest.approx(MASS, rel=2e-3)
    np.testing.assert_allclose(document["center_of_mass"], COM, atol=5e-4)
    np.testing.assert_allclose(document["force_offset"], F0, atol=0.02)
    np.testing.assert_allclose(document["torque_offset"], M0, atol=2e-3)
    np.testing.assert_allclose(document["imu"]["accel_bias"], BIAS, atol=0.01)
    np.testing.assert_allclose(document["imu"]["imu_rotation"], IMU_ROTATION, atol=2e-3)
    np.testing.assert_allclose(document["imu"]["imu_position"], [0.02, 0, 0.03])
    assert document["imu"]["imu_position_source"] == "given"
    assert document["method"] == "imu"
    loaded = load_calibration(path)
    assert isinstance(loaded, ImuCalibrationResult)
    for name in ("imu_rotation", "accel_bias", "accel_scale", "parameter_covariance", "bias"):
        np.testing.assert_array_equal(getattr(loaded, name), getattr(result, name))
    assert loaded.parameter_names == result.parameter_names
    # the loaded calibration compensates fresh readings of the same tool to the noise
    accel, wrenches, _ = readings(Rotation.random(5, random_state=9).as_matrix(), rng, 1)
    contact = ImuCompensator(loaded).compensate_batch(wrenches, accel)
    assert np.abs(contact[:, :3]).max() < 0.3


def test_dynamic_file_keeps_inertia_and_position(tmp_path):
    inertia = np.diag([0.006, 0.005, 0.002])
    result = ImuCalibrationResult(
        force_offset=F0,
        torque_offset=M0,
        gravity_in_base=[0.0, 0.0, -MASS * G],
        center_of_mass=COM,
        method="imu-dynamic",
        sample_count=1000,
        inertia_about_com_in_sensor=inertia,
        inertial_parameters=parameters_from_body(MASS, COM, inertia),
        imu_rotation=IMU_ROTATION,
        accel_bias=BIAS,
        imu_position=[0.021, -0.012, 0.027],
        imu_position_source="estimated",
        motion_residual_rms=[0.05, 0.05, 0.05, 0.003, 0.003, 0.003],
    )
    path = save_calibration(result, tmp_path / "dynamic.json")
    document = json.loads(path.read_text())
    np.testing.assert_allclose(document["inertia"], inertia, rtol=1e-12)
    np.testing.assert_allclose(document["imu"]["imu_position"], [0.021, -0.012, 0.027])
    loaded = load_calibration(path)
    np.testing.assert_allclose(loaded.inertia_about_com_in_sensor, inertia, rtol=1e-12)
    np.testing.assert_allclose(loaded.imu_position, [0.021, -0.012, 0.027])
    assert loaded.imu_position_source == "estimated" and loaded.has_inertia
    np.testing.assert_allclose(loaded.dynamic_parameters, result.dynamic_parameters, rtol=1e-12)


def test_a_broken_imu_entry_is_named(tmp_path, rng):
    accel, wrenches, ids = readings(Rotation.random(8, random_state=3).as_matrix(), rng, 5)
    path = save_calibration(
        ftkin.calibrate(ImuSamples.from_arrays(accel, wrenches, ids)), tmp_path / "c.json"
    )
    document = json.loads(path.read_text())
    document["imu"]["imu_rotation"][0][0] = 2.0  # not a rotation
    broken = tmp_path / "broken.json"
    broken.write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="imu"):
        load_calibration(broken)
    document["imu"]["imu_rotation"] = "identity"
    broken.write_text(json.dumps(document))
    with pytest.raises(CalibrationFileError, match="imu.imu_rotation"):
        load_calibration(broken)
