"""Files in the spellings real sensors and loggers use: ATI's and Bota's Fx..Tz, units in the
header, the rotation matrix r11..r33, times in microseconds since the epoch, any other name
through --column. Each is checked against the same data written in ftkin's own columns, with
the unit factors written out by hand."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidInput, InvalidSamples
from ftkin.io.column_spelling import ColumnSpelling
from ftkin.io.csv_table import read_table, write_csv
from ftkin.io.samples_csv import load_samples
from ftkin.io.static_segments import SegmentParameters
from ftkin.sim.sensor import SimulatedSensor

LBF = 0.45359237 * 9.80665  # [N], by definition
LBF_IN = LBF * 0.0254  # [N·m]
EPOCH_US = 1.7644104e15  # 2025-11-29 in microseconds since 1970


@pytest.fixture(scope="module")
def recorded(arm, truth):
    rng = np.random.default_rng(51)
    q = arm.random_configurations(10, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    wrenches = SimulatedSensor(truth, SensorNoise.paper()).read(rotations, rng)
    return q, rotations, wrenches


def write(path, header, columns):
    write_csv(path, header, np.column_stack(columns).tolist())
    return path


def test_ati_names_and_units_in_the_header(arm, recorded, tmp_path):
    q, _, wrenches = recorded
    header = [*arm.joint_names, "Fx (lbf)", "Fy (lbf)", "Fz (lbf)"]
    header += ["Tx (lbf-in)", "Ty [lbf·in]", "Tz (in-lbf)", "Temperature (°C)"]
    in_pounds = np.column_stack([wrenches[:, :3] / LBF, wrenches[:, 3:] / LBF_IN])
    path = write(tmp_path / "ati.csv", header, [q, in_pounds, np.full(len(q), 25.0)])
    loaded = load_samples(path, arm)
    np.testing.assert_allclose(loaded.samples.wrenches, wrenches, rtol=1e-12, atol=1e-12)
    assert "Temperature (°C)" in loaded.table.header  # carried along untouched


@pytest.mark.parametrize(
    "force, torque, scale",
    [("N", "N-m", (1.0, 1.0)), ("kgf", "kgf-cm", (9.80665, 0.0980665)), ("N", "N·mm", (1, 1e-3))],
)
def test_bota_names_with_other_units(arm, recorded, tmp_path, force, torque, scale):
    q, _, wrenches = recorded
    header = [
        *arm.joint_names,
        *(f"F{a} [{force}]" for a in "xyz"),
        *(f"T{a} [{torque}]" for a in "xyz"),
    ]
    given = np.column_stack([wrenches[:, :3] / scale[0], wrenches[:, 3:] / scale[1]])
    path = write(tmp_path / "bota.csv", header, [q, given])
    np.testing.assert_allclose(load_samples(path, arm).samples.wrenches, wrenches, rtol=1e-12)


def test_an_unknown_unit_on_a_wrench_column_is_refused(arm, recorded, tmp_path):
    q, _, wrenches = recorded
    header = [*arm.joint_names, "fx (psi)", "fy", "fz", "mx", "my", "mz"]
    path = write(tmp_path / "psi.csv", header, [q, wrenches])
    with pytest.raises(InvalidSamples, match="line 1: column 'fx \\(psi\\)': unknown force unit"):
        load_samples(path, arm)


def test_rotation_matrix_columns_row_major(arm, recorded, tmp_path):
    _, rotations, wrenches = recorded
    names = [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
    entries = np.round(rotations.reshape(-1, 9), 6)  # printed with six digits
    path = write(
        tmp_path / "r.csv", [*names, "fx", "fy", "fz", "mx", "my", "mz"], [entries, wrenches]
    )
    loaded = load_samples(path)
    assert loaded.orientation == "matrix"
    np.testing.assert_allclose(loaded.samples.rotations, rotations, atol=2e-6)
    bad = entries.copy()
    bad[3, :3] *= 1.05  # a scaled row: not a rotation
    path = write(
        tmp_path / "bad.csv", [*names, "fx", "fy", "fz", "mx", "my", "mz"], [bad, wrenches]
    )
    with pytest.raises(InvalidSamples, match="line 5: rotation matrix r11..r33 is not a rotation"):
        load_samples(path)


def test_doctor_names_a_transposed_matrix(arm, recorded, tmp_path, capsys):
    _, rotations, wrenches = recorded
    names = [f"r{i}{j}" for i in (1, 2, 3) for j in (1, 2, 3)]
    transposed = np.transpose(rotations, (0, 2, 1)).reshape(-1, 9)  # R_SB written by mistake
    path = write(
        tmp_path / "t.csv", [*names, "fx", "fy", "fz", "mx", "my", "mz"], [transposed, wrenches]
    )
    assert main(["doctor", str(path)]) == 1
    assert "transposed" in capsys.readouterr().out


def test_times_in_microseconds_since_the_epoch(arm, recorded, tmp_path, capsys):
    q, _, wrenches = recorded
    times_us = EPOCH_US + 30e6 * np.arange(len(q))  # a reading every 30 s
    header = ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    path = write(tmp_path / "us.csv", header, [times_us, q, wrenches])
    with pytest.raises(InvalidSamples, match="not seconds.*--time-unit us"):
        load_samples(path, arm)
    assert main(["calibrate", str(path), "--drift", "none"]) == 2
    assert "--time-unit us" in capsys.readouterr().err
    loaded = load_samples(path, arm, SegmentParameters(), ColumnSpelling(time_unit="us"))
    np.testing.assert_allclose(np.diff(loaded.samples.times), 30.0, rtol=0, atol=1e-6)
    assert loaded.layout.poses == len(q)
    assert main(["calibrate", str(path), "--drift", "none", "--time-unit", "us"]) == 0
    assert "one reading per pose" in capsys.readouterr().out


def test_a_time_unit_that_contradicts_the_column_is_refused(arm, recorded, tmp_path):
    q, _, wrenches = recorded
    header = ["t_ms", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    path = write(tmp_path / "ms.csv", header, [1e3 * np.arange(len(q)), q, wrenches])
    np.testing.assert_allclose(load_samples(path, arm).samples.times, np.arange(len(q)))
    with pytest.raises(InvalidSamples, match="--time-unit us contradicts the time column 't_ms'"):
        load_samples(path, arm, spelling=ColumnSpelling(time_unit="us"))


def test_any_other_name_through_column(arm, recorded, tmp_path, capsys):
    q, _, wrenches = recorded
    logger_names = [
        "Force_X_raw",
        "Force_Y_raw",
        "Force_Z_raw",
        "Torque_X_raw",
        "Torque_Y_raw",
        "Torque_Z_raw",
    ]
    joints = [f"J{i}" for i in range(1, 7)]
    path = write(
        tmp_path / "logger.csv", [*joints, *logger_names, "note"], [q, wrenches, np.zeros(len(q))]
    )
    renames = [f"q{i}=J{i}" for i in range(1, 7)]
    renames += [
        f"{ours}={theirs}"
        for ours, theirs in zip(("fx", "fy", "fz", "mx", "my", "mz"), logger_names)
    ]
    spelling = ColumnSpelling(columns=renames)
    loaded = load_samples(path, arm, spelling=spelling)
    np.testing.assert_allclose(loaded.samples.wrenches, wrenches, rtol=1e-15)
    argv = ["calibrate", str(path), "-o", str(tmp_path / "c.json")]
    assert main([*argv, *(f"--column={pair}" for pair in renames)]) == 0
    out = tmp_path / "out.csv"
    argv = ["compensate", str(tmp_path / "c.json"), str(path), "-o", str(out)]
    assert main([*argv, *(f"--column={pair}" for pair in renames)]) == 0
    assert "note" in read_table(out).header  # an unknown column carried along
    assert main([*argv, "--column", "fx=Nope"]) == 2
    assert "no column 'Nope'" in capsys.readouterr().err


@pytest.mark.parametrize(
    "columns, message",
    [
        (["fx"], "NAME=COLUMN"),
        (["fx=A", "fx=B"], "given twice"),
        (["fx=A", "fy=A"], "to two names"),
        ("fx=A", "in a list"),
    ],
)
def test_bad_column_options(columns, message):
    with pytest.raises(InvalidInput, match=message):
        ColumnSpelling(columns=columns)


def test_fx_and_Fx_in_one_file_keep_ftkins_own_and_say_so(tmp_path, caplog):
    """Both could spell fx ("tx,ty,tz" beside mx..mz may be a translation): ftkin's own name is
    used, and the other named in a warning (it was carried along in silence)."""
    import logging

    from ftkin.io.column_spelling import spelled_table

    path = tmp_path / "both.csv"
    path.write_text("qw,qx,qy,qz,fx,Fx,fy,fz,mx,my,mz\n1,0,0,0,1,2,0,0,0,0,0\n")
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        table = spelled_table(read_table(path))
    assert table.header[4:6] == ["fx", "Fx"]
    assert "column 'Fx' could spell the wrench channel 'fx'" in caplog.text
