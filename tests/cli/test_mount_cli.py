"""CLI: --estimate-mount, --sensor-sign, --flip-axis, --base-mount; the file carries them to
compensate.
"""

from __future__ import annotations

import csv

import numpy as np
import pytest

from ftkin import load_calibration
from ftkin.calibration.conventions import reading_signs
from ftkin.calibration.mount import exp_so3
from ftkin.cli import main
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
MOUNT = exp_so3([0.0, 0.0, np.deg2rad(25.0)])


def _csv(path, arm, tool, configurations, signs, contact=None):
    wrenches = tool.predict(arm.rotation_sensor_to_base(configurations) @ MOUNT.T)
    if contact is not None:
        wrenches = wrenches + contact
    header = [f"q{i + 1}" for i in range(arm.nq)] + WRENCH
    rows = [[*map(float, q), *map(float, w)] for q, w in zip(configurations, wrenches * signs)]
    return write_csv(path, header, rows)


@pytest.fixture
def configurations(arm):
    return arm.random_configurations(10, np.random.default_rng(41), margin=0.3)


def test_mount_sign_round_trip_through_the_cli(arm, tool, configurations, tmp_path, capsys):
    samples = _csv(tmp_path / "samples.csv", arm, tool, configurations, reading_signs(-1))
    calib = tmp_path / "calib.json"
    assert main(["calibrate", str(samples), "--estimate-mount", "yaw", "-o", str(calib)]) == 2
    error = capsys.readouterr().err
    assert (
        "--sensor-sign -1" in error and "--base-mount ceiling" in error and "Traceback" not in error
    )
    assert (
        main(
            [
                "calibrate",
                str(samples),
                "--estimate-mount",
                "yaw",
                "--sensor-sign",
                "-1",
                "-o",
                str(calib),
            ]
        )
        == 0
    )
    assert "mount_rpy_deg" in capsys.readouterr().out
    result = load_calibration(calib)
    assert result.sensor_sign == -1 and result.mount_rpy_deg[2] == pytest.approx(25.0, abs=1e-6)

    contact = np.random.default_rng(42).normal(size=(len(configurations), 6))
    log = _csv(tmp_path / "log.csv", arm, tool, configurations, reading_signs(-1), contact)
    out = tmp_path / "contact.csv"
    assert main(["compensate", str(calib), str(log), "-o", str(out)]) == 0
    with open(out) as handle:
        rows = list(csv.DictReader(handle))
    np.testing.assert_allclose(
        [[float(row[c]) for c in WRENCH] for row in rows], contact, atol=1e-6
    )


def test_flip_axis_and_base_mount_flags(arm, tool, configurations, tmp_path, capsys):
    plain = tmp_path / "plain.csv"
    _csv(plain, arm, tool, configurations, reading_signs(1, "z"))
    assert main(["calibrate", str(plain), "--estimate-mount", "yaw"]) == 2
    assert "--flip-axis z" in capsys.readouterr().err
    assert main(["calibrate", str(plain), "--estimate-mount", "yaw", "--flip-axis", "z"]) == 0
    assert "z axis reversed" in capsys.readouterr().out
    assert main(["calibrate", str(plain), "--method", "linear", "--estimate-mount", "yaw"]) == 2
    assert "(--method ml) only" in capsys.readouterr().err


def test_evaluate_poses_plans_for_the_mount(arm, configurations, tmp_path, capsys):
    header = [f"q{i + 1}" for i in range(arm.nq)]
    poses = write_csv(tmp_path / "poses.csv", header, [list(map(float, q)) for q in configurations])
    assert main(["evaluate-poses", str(poses)]) == 0
    assert "mount" not in capsys.readouterr().out
    assert main(["evaluate-poses", str(poses), "--estimate-mount", "full"]) == 0
    lines = [
        line.split() for line in capsys.readouterr().out.splitlines() if line.startswith("mount[")
    ]
    assert [line[0] for line in lines] == ["mount[x]", "mount[y]", "mount[z]"]
    assert all(
        0.0 < float(line[1]) < 1.0 for line in lines
    )  # [deg] for 10 poses of the paper's tool
