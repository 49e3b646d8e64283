"""The ftkin command line: calibrate → file → compensate; demo; one-line errors."""

from __future__ import annotations

import csv
import importlib.util
import json
import re

import numpy as np
import pytest

from ftkin import load_calibration
from ftkin.cli import main
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


@pytest.fixture
def calibration_csv(arm, rng, truth, tmp_path):
    """Noise-free readings at 8 poses, 3 rows each, joint columns q1..q6."""
    configurations = np.repeat(arm.random_configurations(8, rng, margin=0.3), 3, axis=0)
    wrenches = truth.predict(arm.rotation_sensor_to_base(configurations))
    pose = np.repeat(np.arange(1, 9), 3)
    header = ["pose"] + [f"q{i + 1}" for i in range(arm.nq)] + WRENCH
    rows = [
        [int(p), *map(float, q), *map(float, w)] for p, q, w in zip(pose, configurations, wrenches)
    ]
    return write_csv(tmp_path / "samples.csv", header, rows)


def test_calibrate_then_compensate_returns_the_contact(
    arm, rng, truth, calibration_csv, tmp_path, capsys
):
    calib = tmp_path / "calib.json"
    assert main(["calibrate", str(calibration_csv), "-o", str(calib), "--method", "linear"]) == 0
    out = capsys.readouterr().out
    assert "8 poses, 24 readings" in out and f"wrote {calib}" in out
    assert "tool_weight" in out and "N·m" in out
    result = load_calibration(calib)
    np.testing.assert_allclose(result.to_vector(), truth.to_vector(), atol=1e-9)
    assert json.loads(calib.read_text())["pose_count"] == 8

    # a log with contacts, extra columns in between and after, joint names as columns
    configurations = arm.random_configurations(10, rng)
    contact = rng.normal(scale=[3, 3, 3, 0.2, 0.2, 0.2], size=(10, 6))
    raw = truth.predict(arm.rotation_sensor_to_base(configurations)) + contact
    header = ["time", *arm.joint_names, *WRENCH, "label"]
    rows = [
        [0.001 * i, *map(float, q), *map(float, w), f"tick {i}"]
        for i, (q, w) in enumerate(zip(configurations, raw))
    ]
    log = write_csv(tmp_path / "log.csv", header, rows)
    output = tmp_path / "out.csv"
    assert main(["compensate", str(calib), str(log), "-o", str(output)]) == 0
    assert f"wrote 10 compensated rows to {output}" in capsys.readouterr().out

    with open(output, newline="") as stream:
        table = list(csv.reader(stream))
    assert table[0] == header
    body = table[1:]
    assert len(body) == 10
    recovered = np.array([[float(row[header.index(name)]) for name in WRENCH] for row in body])
    np.testing.assert_allclose(recovered, contact, atol=1e-9)
    for i, row in enumerate(body):
        assert row[0] == repr(0.001 * i) and row[-1] == f"tick {i}"
        np.testing.assert_array_equal([float(v) for v in row[1:7]], configurations[i])


def test_calibrate_with_quaternion_csv_and_explicit_urdf(arm, rng, truth, tmp_path, capsys):
    from ftkin.kinematics.rotations import matrix_to_quaternion

    rotations = arm.rotation_sensor_to_base(arm.random_configurations(6, rng, margin=0.3))
    rows = np.hstack([matrix_to_quaternion(rotations), truth.predict(rotations)]).tolist()
    path = write_csv(tmp_path / "quat.csv", ["qw", "qx", "qy", "qz", *WRENCH], rows)
    assert main(["calibrate", str(path), "--method", "linear"]) == 0
    out = capsys.readouterr().out
    match = re.search(r"G\s+=\s+([\d.]+) N", out)
    assert float(match.group(1)) == pytest.approx(truth.tool_weight, abs=1e-3)


def test_demo_prints_truth_beside_estimate(capsys):
    assert main(["demo", "--readings-per-pose", "20", "--n", "8", "--seed", "3"]) == 0
    out = capsys.readouterr().out
    assert re.search(
        r"parameter\s+truth\s+estimate\s+max \|error\|\s+max \|error\| / std error", out
    )
    for name in (
        "force_offset",
        "torque_offset",
        "center_of_mass",
        "gravity_in_base",
        "base_tilt_deg",
    ):
        assert re.search(rf"^\s+{name}\s+\[", out, flags=re.MULTILINE), name
    injected = [float(v) for v in re.search(r"injected\s+(.*)", out).group(1).split()]
    recovered = [float(v) for v in re.search(r"recovered\s+(.*)", out).group(1).split()]
    np.testing.assert_allclose(injected, [1.5, -0.8, -4.0, 0.05, 0.02, -0.01])
    # a few readings' worth of noise (0.02 N, 0.002 N·m each) plus the calibration error
    np.testing.assert_allclose(recovered, injected, atol=0.15)
    if (
        importlib.util.find_spec("mujoco") is not None
    ):  # the closed-loop segment: the object lands on the book gently
        peak = float(
            re.search(r"Closed loop in MuJoCo.*\n\s+peak contact force ([\d.]+) N", out).group(1)
        )
        assert 2.0 < peak < 3.0


def test_demo_writes_a_calibration_file(tmp_path, capsys):
    path = tmp_path / "demo.json"
    assert (
        main(
            ["demo", "--readings-per-pose", "5", "--n", "6", "--sim-seconds", "0", "-o", str(path)]
        )
        == 0
    )
    assert load_calibration(path).pose_count == 6


# ----------------------------------------------------------------- errors
def _assert_cli_error(argv, capsys, pattern):
    assert main(argv) == 2
    captured = capsys.readouterr()
    assert captured.err.startswith("ftkin: error: "), captured.err
    assert "Traceback" not in captured.err and len(captured.err.strip().splitlines()) == 1
    assert re.search(pattern, captured.err), captured.err


def test_missing_samples_file(tmp_path, capsys):
    _assert_cli_error(
        ["calibrate", str(tmp_path / "nope.csv")], capsys, r"nope.csv: file not found"
    )


def test_bad_samples_cell(tmp_path, capsys):
    path = tmp_path / "bad.csv"
    path.write_text("alpha,beta,gamma,fx,fy,fz,mx,my,mz\n0,0,0,1,2,x,4,5,6\n")
    _assert_cli_error(
        ["calibrate", str(path), "--method", "linear"],
        capsys,
        r"bad.csv, line 2: column 'fz': 'x' is not a number",
    )


def test_unobservable_poses(tmp_path, capsys):
    path = tmp_path / "same.csv"
    path.write_text("alpha,beta,gamma,fx,fy,fz,mx,my,mz\n" + "90,0,-180,1,2,3,4,5,6\n" * 4)
    _assert_cli_error(
        ["calibrate", str(path), "--method", "linear"], capsys, "cannot determine .*force_offset"
    )


def test_missing_urdf(tmp_path, capsys, calibration_csv):
    _assert_cli_error(
        ["calibrate", str(calibration_csv), "--urdf", str(tmp_path / "arm.urdf")],
        capsys,
        r"cannot load URDF .*arm.urdf: file not found",
    )


def test_unknown_sensor_frame(calibration_csv, capsys):
    from ftkin.kinematics import bundled_urdf_path

    _assert_cli_error(
        [
            "calibrate",
            str(calibration_csv),
            "--urdf",
            str(bundled_urdf_path()),
            "--sensor-frame",
            "fts",
        ],
        capsys,
        r"frame 'fts' not found .*ft_sensor",
    )


def test_compensate_with_broken_calibration_file(tmp_path, capsys, calibration_csv):
    calib = tmp_path / "calib.json"
    calib.write_text('{"format": "ftkin-calibration", "version": 1,')
    _assert_cli_error(
        ["compensate", str(calib), str(calibration_csv), "-o", str(tmp_path / "out.csv")],
        capsys,
        r"calib.json: not valid JSON .*line 1",
    )
    assert not (tmp_path / "out.csv").exists()


def test_output_into_missing_folder(calibration_csv, tmp_path, capsys):
    _assert_cli_error(
        [
            "calibrate",
            str(calibration_csv),
            "--method",
            "linear",
            "-o",
            str(tmp_path / "no" / "c.json"),
        ],
        capsys,
        "does not exist",
    )


def test_usage_errors_exit_2(capsys):
    assert main([]) == 2
    assert "calibrate" in capsys.readouterr().out
    assert main(["calibrate", "x.csv", "--g", "-1"]) == 2  # argparse's exit becomes the return code
    assert "must be a finite positive number" in capsys.readouterr().err
