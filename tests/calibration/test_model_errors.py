"""What a drift must not swallow and what a given noise must not hide: a sensor mounted otherwise
than the orientations say is a model error (the bias path follows the orientation, not time),
and a noise given far above the residuals is said.

The readings are the model's own prediction at the real orientations (a hand-written rotation
of the sensor frame by a known angle), with seeded Gaussian noise; the fit sees the rotations
the "URDF" gives, without that turn.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin import CalibrationOptions, Samples, SensorNoise, calibrate
from ftkin.calibration.imu_samples import ImuSamples

READINGS = 20
FORCE_STD, TORQUE_STD = 0.05, 0.002


def _timed_samples(arm, truth, rng, mount_yaw_deg, poses=20, drift_per_pose=None):
    """``poses`` static poses 5 s apart, READINGS readings each; the real sensor frame turned by
    ``mount_yaw_deg`` about its z axis against the rotations handed to the fit."""
    configurations = arm.random_configurations(poses, rng, margin=0.3)
    given = arm.rotation_sensor_to_base(configurations)
    turn = Rotation.from_euler("z", mount_yaw_deg, degrees=True).as_matrix()
    real = given @ turn.T  # R_BS_real = R_BS_given · R_Mᵀ
    wrenches = truth.predict(real)
    if drift_per_pose is not None:
        wrenches = wrenches + np.outer(np.arange(poses), drift_per_pose)
    repeated = np.repeat(wrenches, READINGS, axis=0)
    noise = rng.normal(size=repeated.shape) * ([FORCE_STD] * 3 + [TORQUE_STD] * 3)
    times = np.repeat(5.0 * np.arange(poses), READINGS) + np.tile(np.arange(READINGS) * 0.01, poses)
    return Samples(
        repeated + noise,
        np.repeat(given, READINGS, axis=0),
        pose_ids=np.repeat(np.arange(poses), READINGS),
        times=times,
    )


GIVEN_NOISE = SensorNoise(FORCE_STD, TORQUE_STD)


def test_an_unmodelled_mount_is_not_taken_for_a_drift(arm, truth, rng, caplog):
    """A sensor turned 5° about z: no walk may absorb it (it did, 'consistent with the noise'),
    the fit says it does not fit and names the mount."""
    samples = _timed_samples(arm, truth, rng, mount_yaw_deg=5.0)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(samples, CalibrationOptions(noise=GIVEN_NOISE))
    assert result.drift is None or "walk" not in result.drift.model
    assert "follows the sensor's orientation, not time" in caplog.text
    assert not result.diagnostics.fit_ok
    assert "--estimate-mount" in " ".join(result.diagnostics.warnings)


def test_a_real_drift_is_not_called_a_model_error(arm, truth, rng, caplog):
    """A bias that drifts with time (a steady 0.02 N per pose on fx, 0.001 N·m on mz) at the
    orientations given: the drift is kept and not called a model error."""
    drift = np.array([0.02, 0.0, -0.01, 0.0, 0.0, 0.001])
    samples = _timed_samples(arm, truth, rng, mount_yaw_deg=0.0, drift_per_pose=drift)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(samples, CalibrationOptions(noise=GIVEN_NOISE))
    assert "follows the sensor's orientation" not in caplog.text
    assert result.drift is not None and result.drift.model != "none"
    assert result.diagnostics.fit_ok


def test_a_noise_given_far_above_the_residuals_is_said(arm, truth, rng):
    samples = _timed_samples(arm, truth, rng, mount_yaw_deg=0.0, poses=12)
    samples = Samples(samples.wrenches, samples.rotations, pose_ids=samples.pose_ids)
    result = calibrate(samples, CalibrationOptions(noise=SensorNoise(2.0, 0.08)))  # 40× too big
    assert result.diagnostics.noise_too_large
    (warning,) = [w for w in result.diagnostics.warnings if "fit far better" in w]
    factor = float(warning.split("the noise given is about ")[1].split("×")[0])
    assert 25.0 < factor < 60.0  # 40× the real noise, within the chi-square's scatter
    assert "FITS FAR BETTER" in result.summary()
    right = calibrate(samples, CalibrationOptions(noise=GIVEN_NOISE))
    assert not right.diagnostics.noise_too_large


def test_an_imu_fit_that_does_not_fit_its_noise_is_said(rng):
    """The accelerometer one pose late against the wrench (two clocks): the IMU fit had no
    goodness-of-fit test (the mass 37 σ off, no warning). The same readings on one clock fit."""
    poses, readings, mass, g = 14, 30, 1.2, 9.80665
    up = Rotation.random(poses, random_state=4).apply([0.0, 0.0, g], inverse=True)  # sensor axes
    com = np.array([0.01, -0.02, 0.06])
    weight = -mass * up
    wrench = np.column_stack([weight, np.cross(com, weight)])
    count = poses * readings
    wrenches = np.repeat(wrench, readings, 0) + rng.normal(0, 0.02, (count, 6))
    ids = np.repeat(np.arange(poses), readings)
    on_time = np.repeat(up, readings, 0) + rng.normal(0, 0.01, (count, 3))
    late = np.repeat(np.roll(up, 1, axis=0), readings, 0) + rng.normal(0, 0.01, (count, 3))
    fitting = calibrate(ImuSamples.from_arrays(on_time, wrenches, ids))
    assert not any("do not fit" in w for w in fitting.imu_warnings)
    assert fitting.tool_mass == pytest.approx(mass, rel=2e-3)
    misfit = calibrate(ImuSamples.from_arrays(late, wrenches, ids))
    assert any("do not fit the IMU model within their noise" in w for w in misfit.imu_warnings)


def test_a_sensor_turned_180_degrees_is_named_as_such(tmp_path, capsys):
    """A sensor bolted on turned 180° about z: a mirror (--flip-axis z) fits the static data
    alike, with gravity pointing up; the turn, with gravity down, is what is named, and the mount
    it names recovers the tool."""
    from ftkin import SensorNoise, SimulatedSensor, load_robot
    from ftkin.cli import main
    from ftkin.io.csv_table import write_csv
    from ftkin.sim.sensor import paper_like_truth

    arm = load_robot("ur5e")
    rng = np.random.default_rng(11)
    q = arm.random_configurations(12, rng, margin=0.3)
    turn = Rotation.from_euler("z", 180.0, degrees=True).as_matrix()
    real = arm.rotation_sensor_to_base(q) @ turn.T
    truth = paper_like_truth()
    raw = SimulatedSensor(truth, SensorNoise.paper()).read(np.repeat(real, 20, axis=0), rng)
    path = tmp_path / "turned.csv"
    header = ["pose", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    ids = np.repeat(np.arange(12), 20)
    write_csv(path, header, np.column_stack([ids, np.repeat(q, 20, axis=0), raw]).tolist())
    assert main(["calibrate", str(path), "--robot", "ur5e"]) == 2
    err = capsys.readouterr().err
    assert "the sensor turned 180° about its z axis" in err and "--estimate-mount yaw" in err
    out = tmp_path / "c.json"
    assert (
        main(["calibrate", str(path), "--robot", "ur5e", "--estimate-mount", "yaw", "-o", str(out)])
        == 0
    )
    from ftkin import load_calibration

    fitted = load_calibration(out)
    assert fitted.tool_mass == pytest.approx(truth.tool_mass, rel=0.01)
    assert abs(abs(fitted.mount_rpy_deg[2]) - 180.0) < 1.0
