"""``ftkin simulate samples|log|recording|bag`` round trips: what is written, ftkin reads back.

Each file is simulated from known parameters; the matching reader and estimator
must recover them within their standard errors (5σ), independently of how the
file was written.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftkin.calibration.fit_registry import calibrate
from ftkin.cli import main
from ftkin.io.calibration_file import load_calibration
from ftkin.io.csv_table import read_table
from ftkin.io.samples_csv import configurations_from_table, load_samples
from ftkin.sim.inputs import PUSH, SimulatedInputs, samples_table
from ftkin.sim.sensor import paper_like_truth


def _within(result, truth, sigmas: float = 5.0) -> None:
    for name in ("force_offset", "torque_offset", "center_of_mass", "gravity_in_base"):
        error = np.abs(getattr(result, name) - getattr(truth, name))
        bound = sigmas * result.std_errors[name]
        assert np.all(error < bound), (name, error, bound)


def test_samples_table_recovers_truth(arm, rng):
    inputs = SimulatedInputs()
    configurations = arm.random_configurations(12, rng, margin=0.3)
    header, rows = samples_table(inputs, arm, configurations, rng, readings_per_pose=20)
    assert header[0] == "pose" and header[-6:] == ["fx", "fy", "fz", "mx", "my", "mz"]
    assert all(isinstance(row[0], int) for row in rows)
    values = np.asarray([row[1:] for row in rows], dtype=float)
    np.testing.assert_allclose(values[::20, : arm.nq], configurations, rtol=0, atol=0)
    from ftkin.calibration.samples import Samples

    rotations = arm.rotation_sensor_to_base(values[:, : arm.nq])
    samples = Samples(values[:, arm.nq :], rotations, np.repeat(np.arange(12), 20))
    _within(calibrate(samples), paper_like_truth())


def test_cli_samples_from_plan_then_calibrate(tmp_path, capsys):
    poses, samples, calib = tmp_path / "poses.csv", tmp_path / "s.csv", tmp_path / "c.json"
    assert main(["plan", "--n", "8", "-o", str(poses)]) == 0
    assert main(["simulate", "samples", "--poses", str(poses), "-o", str(samples)]) == 0
    assert main(["calibrate", str(samples), "-o", str(calib)]) == 0
    loaded = load_samples(samples)
    assert len(np.unique(loaded.samples.pose_ids)) == 8
    from ftkin.kinematics.arm import Arm

    planned = configurations_from_table(read_table(poses), Arm.default())
    written = configurations_from_table(read_table(samples), Arm.default())
    np.testing.assert_allclose(written, planned, rtol=1e-15, atol=0)
    _within(load_calibration(calib), paper_like_truth())
    assert "truth: tool 0.3217 kg" in capsys.readouterr().out


def test_cli_mount_and_sign_are_recovered(tmp_path):
    samples, calib = tmp_path / "s.csv", tmp_path / "c.json"
    argv = ["simulate", "samples", "--n", "15", "--readings-per-pose", "20", "-o", str(samples)]
    assert main([*argv, "--mount-rpy-deg", "3", "-2", "35", "--sensor-sign", "-1"]) == 0
    assert (
        main(
            ["calibrate", str(samples), "--estimate-mount", "full", "--sensor-sign", "-1"]
            + ["-o", str(calib)]
        )
        == 0
    )
    result = load_calibration(calib)
    np.testing.assert_allclose(result.mount_rpy_deg, [3.0, -2.0, 35.0], atol=0.2)
    _within(result, paper_like_truth())


def test_cli_drift_has_times_and_is_found(tmp_path):
    samples, calib = tmp_path / "s.csv", tmp_path / "c.json"
    assert main(["simulate", "samples", "--with-drift", "--n", "30", "-o", str(samples)]) == 0
    loaded = load_samples(samples)
    times = loaded.samples.times
    assert times is not None and times.max() > 200.0  # 30 poses, 10 s apart [s]
    assert main(["calibrate", str(samples), "--drift", "auto", "-o", str(calib)]) == 0
    result = load_calibration(calib)
    assert result.drift is not None and result.drift.model != "none"
    np.testing.assert_allclose(result.tool_mass, paper_like_truth().tool_mass, rtol=2e-3)


def test_cli_tool_options_and_noise_scale(tmp_path):
    samples, calib = tmp_path / "s.csv", tmp_path / "c.json"
    argv = ["simulate", "samples", "--tool-mass", "1.5", "--com", "0.01", "-0.02", "0.08"]
    assert main([*argv, "--noise-scale", "0.5", "-o", str(samples)]) == 0
    assert main(["calibrate", str(samples), "-o", str(calib)]) == 0
    result = load_calibration(calib)
    np.testing.assert_allclose(result.tool_mass, 1.5, rtol=1e-3)
    np.testing.assert_allclose(result.center_of_mass, [0.01, -0.02, 0.08], atol=5e-4)


def test_cli_log_compensated_gives_the_push_back(tmp_path):
    samples, calib, log, out = (tmp_path / name for name in ("s.csv", "c.json", "l.csv", "o.csv"))
    assert main(["simulate", "samples", "--readings-per-pose", "50", "-o", str(samples)]) == 0
    assert main(["calibrate", str(samples), "-o", str(calib)]) == 0
    assert main(["simulate", "log", "--seed", "3", "-o", str(log)]) == 0
    assert main(["compensate", str(calib), str(log), "-o", str(out)]) == 0
    table = read_table(out)
    channels = ["fx", "fy", "fz", "mx", "my", "mz"]
    contact = table.floats(channels)
    true = table.floats([f"true_{c}" for c in channels])
    assert np.any(np.all(true == PUSH, axis=1)) and np.any(np.all(true == 0, axis=1))
    # noise of one reading 0.02 N / 0.002 N·m: mean error over the rows well under it, none > 6σ
    error = contact - true
    assert np.all(np.abs(error.mean(axis=0)) < [0.01] * 3 + [0.001] * 3)
    assert np.all(np.abs(error) < [0.12] * 3 + [0.012] * 3)


def test_cli_bag_then_calibrate_and_extract(tmp_path):
    pytest.importorskip("rosbags")
    bag, calib, extracted = tmp_path / "session", tmp_path / "c.json", tmp_path / "e.csv"
    assert main(["simulate", "bag", "--n", "8", "-o", str(bag)]) == 0
    assert (bag / "metadata.yaml").is_file()
    assert main(["calibrate", str(bag), "-o", str(calib)]) == 0
    _within(load_calibration(calib), paper_like_truth())
    assert main(["extract", str(bag), "-o", str(extracted)]) == 0
    assert len(np.unique(load_samples(extracted).samples.pose_ids)) == 8
    assert main(["simulate", "bag", "-o", str(bag)]) == 2  # never over an existing folder


def test_cli_recording_then_dynamic_calibration(tmp_path):
    pytest.importorskip("mujoco")
    trajectory, recording, calib = tmp_path / "t.csv", tmp_path / "r.csv", tmp_path / "c.json"
    assert main(["plan", "--excitation", "--duration", "6", "-o", str(trajectory)]) == 0
    assert (
        main(["simulate", "recording", "--trajectory", str(trajectory), "-o", str(recording)]) == 0
    )
    assert main(["calibrate", "--dynamic", str(recording), "-o", str(calib)]) == 0
    result = load_calibration(calib)
    truth = paper_like_truth()
    np.testing.assert_allclose(result.tool_mass, truth.tool_mass, rtol=2e-3)
    np.testing.assert_allclose(result.center_of_mass, truth.center_of_mass, atol=2e-4)
    np.testing.assert_allclose(
        np.diag(result.inertia_about_com_in_sensor), [2e-3, 2e-3, 1e-3], atol=5e-5
    )
    document = json.loads(calib.read_text())
    assert document["version"] == 2


def test_bad_inputs_are_refused(tmp_path, capsys):
    out = str(tmp_path / "x.csv")
    assert main(["simulate", "samples", "--mount-rpy-deg", "1", "2", "-o", out]) == 2
    assert main(["simulate", "samples", "--com", "1", "-o", out]) == 2
    poses = tmp_path / "p.csv"
    poses.write_text("alpha,beta,gamma\n0,0,0\n")
    assert main(["simulate", "samples", "--poses", str(poses), "-o", out]) == 2
    assert "expected 6 joint columns" in capsys.readouterr().err
    assert main(["simulate", "samples", "--noise-scale", "0", "-o", out]) == 2
    assert main(["simulate", "samples", "--poses", str(poses), "-o", str(poses)]) == 2
    with pytest.raises(Exception, match="rotation"):
        SimulatedInputs(mount_rotation=np.ones((3, 3)))


def test_a_mirrored_mount_is_refused():
    from ftkin.exceptions import InvalidInput

    with pytest.raises(InvalidInput, match="mount_rotation"):
        SimulatedInputs(mount_rotation=np.diag([1.0, 1.0, -1.0]))
