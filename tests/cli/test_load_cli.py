"""ftkin compensate --track-load: the load's columns, the contact after tool and load, the advice
on a calibration without noise, a malformed gripper column."""

import csv
import re

import numpy as np
import pytest

from ftkin import SensorModel
from ftkin.calibration.result import CalibrationResult
from ftkin.cli import main
from ftkin.control.load_events import LABELS
from ftkin.io.calibration_file import save_calibration
from ftkin.io.csv_table import write_csv

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]
LOAD = ["load_mass", "load_mass_std", "load_com_x", "load_com_y", "load_com_z", "load_event"]
MASS, COM = 0.3245, np.array([0.012, -0.006, 0.07])  # Table 4's 3.180 N over 9.8 m/s²
NOISE_ARGS = ["--noise-force", "0.02", "--noise-torque", "0.002"]


@pytest.fixture(scope="module")
def recording(tmp_path_factory, arm):
    """A calibration file without noise and a 1 kHz log of still poses: empty, the load taken,
    held at three orientations, set down (readings by hand from the model, seeded noise)."""
    folder = tmp_path_factory.mktemp("load")
    tool = SensorModel.from_tool(0.5, [0.0, 0.01, 0.04], [1.0, -2.0, 0.5], [0.02, 0.01, -0.03])
    calibration = save_calibration(CalibrationResult.from_model(tool), folder / "calib.json")
    poses = np.array(
        [
            [0.1, -0.3, 1.2, 0.2, -0.8, 0.4],
            [0.1, -0.3, 1.2, 0.9, -0.8, 0.4],
            [0.1, -0.3, 1.2, 0.9, 0.1, 0.4],
        ]
    )
    plan = [(0, 0.0, 300), (0, MASS, 1100), (1, MASS, 500), (2, MASS, 500), (2, 0.0, 300)]
    q = np.vstack([np.tile(poses[p], (n, 1)) for p, _, n in plan])
    masses = np.concatenate([np.full(n, m) for _, m, n in plan])
    rotations = arm.rotation_sensor_to_base(q)
    gravity = tool.gravity_in_base / np.linalg.norm(tool.gravity_in_base) * tool.g
    force = masses[:, None] * np.einsum("nji,j->ni", rotations, gravity)  # m R_BSᵀ γ
    load = np.hstack([force, np.cross(COM, force)])
    rng = np.random.default_rng(17)
    raw = tool.predict(rotations) + load + rng.normal(size=load.shape) * ([0.02] * 3 + [0.002] * 3)
    header = ["t", *arm.joint_names, *WRENCH, "note"]
    rows = [
        [i * 1e-3, *map(float, qi), *map(float, w), f"row {i}"]
        for i, (qi, w) in enumerate(zip(q, raw))
    ]
    log = write_csv(folder / "log.csv", header, rows)
    return calibration, log, header, load, masses, folder


def _read(path):
    with open(path, newline="") as stream:
        table = list(csv.reader(stream))
    return table[0], table[1:]


def test_track_load_writes_the_load_columns_and_the_contact_after_it(recording, capsys):
    calibration, log, header, load, masses, folder = recording
    output = folder / "out.csv"
    argv = ["compensate", str(calibration), str(log), "-o", str(output), "--track-load"]
    assert main(argv + NOISE_ARGS) == 0
    printed = capsys.readouterr().out
    assert re.search(r"t 0\.3\d\d s: grasp", printed) and re.search(
        r"t 2\.4\d\d s: release", printed
    )
    written, body = _read(output)
    assert written == header + LOAD
    labels = [row[-1] for row in body]
    assert set(labels) <= set(LABELS) and labels.count("grasp") == 1 == labels.count("release")
    assert labels.index("grasp") - 300 <= 50 and labels.index("release") - 2400 <= 50
    column = {name: written.index(name) for name in written}
    mass = np.array([float(row[column["load_mass"]]) for row in body])
    assert abs(mass[300 + 1000] / MASS - 1) < 0.005  # within 0.5 % 1 s after the grasp
    com = np.array([[float(row[column[f"load_com_{a}"]]) for a in "xyz"] for row in body])
    assert np.all(np.isnan(com[:300])) and np.all(mass[:300] == 0)
    np.testing.assert_allclose(com[2390], COM, atol=0.002)  # after the wrist turned
    contact = np.array([[float(row[column[name]]) for name in WRENCH] for row in body])
    held = slice(500, 2390)
    assert np.all(np.abs(contact[held].mean(axis=0)) < [0.01] * 3 + [0.001] * 3)
    assert [row[column["note"]] for row in body[:2]] == ["row 0", "row 1"]
    # a rerun on its own output replaces the load columns instead of adding more
    again = folder / "again.csv"
    assert (
        main(
            ["compensate", str(calibration), str(output), "-o", str(again), "--track-load"]
            + NOISE_ARGS
        )
        == 0
    )
    assert _read(again)[0] == header + LOAD


def test_without_a_recorded_noise_it_is_estimated_from_the_log(recording, capsys):
    calibration, log, _, _, _, folder = recording
    argv = ["compensate", str(calibration), str(log), "-o", str(folder / "x.csv"), "--track-load"]
    assert main(argv) == 0
    printed = capsys.readouterr().out
    line = re.search(r"noise per reading \[(.*)\] N, \[(.*)\] N·m", printed)
    force, torque = (np.array(group.split(), dtype=float) for group in line.groups())
    np.testing.assert_allclose(force, 0.02, rtol=0.1)  # the log's seeded noise
    np.testing.assert_allclose(torque, 0.002, rtol=0.1)


def test_a_log_too_short_for_a_noise_is_told_what_to_add(recording, capsys):
    calibration, log, header, _, _, folder = recording
    with open(log, newline="") as stream:
        rows = list(csv.reader(stream))[1:3]
    short = write_csv(folder / "short.csv", header, rows)
    argv = ["compensate", str(calibration), str(short), "-o", str(folder / "s.csv"), "--track-load"]
    assert main(argv) == 2
    error = capsys.readouterr().err
    assert error.startswith("ftkin: error: ") and "Traceback" not in error
    assert "--noise-force N --noise-torque NM" in error and len(error.strip().splitlines()) == 1
    assert not (folder / "s.csv").exists()
    assert main(argv + NOISE_ARGS) == 0  # the advice, followed


def test_a_malformed_gripper_column_is_named(recording, capsys):
    calibration, log, header, _, _, folder = recording
    with open(log, newline="") as stream:
        rows = list(csv.reader(stream))[1:]
    rows = [row + ["1" if i != 7 else "yes"] for i, row in enumerate(rows)]
    bad = write_csv(folder / "gripper.csv", header + ["gripper"], rows)
    argv = ["compensate", str(calibration), str(bad), "-o", str(folder / "g.csv"), "--track-load"]
    assert main(argv + NOISE_ARGS) == 2
    error = capsys.readouterr().err
    assert "gripper.csv, line 9: column 'gripper': 'yes' is not 1 or 0" in error
