"""Samples CSV rules: separators, decimal commas, ROS names, did-you-mean, mixed conventions,
limits.
"""

from __future__ import annotations

import logging
import time

import numpy as np
import pytest

import ftkin
from ftkin.io.column_spelling import spelled_table
from ftkin.io.csv_table import Table, read_table, sniff_delimiter
from ftkin.io.samples_csv import load_samples
from ftkin.kinematics.rotations import matrix_to_euler_zyx

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


@pytest.fixture(scope="module")
def data(arm, truth):
    rng = np.random.default_rng(21)
    q = arm.random_configurations(6, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    return q, rotations, truth.predict(rotations)


def _text(header, rows, delimiter=",", decimal="."):
    lines = [delimiter.join(header)]
    for row in rows:
        lines.append(delimiter.join(repr(float(v)).replace(".", decimal) for v in row))
    return "\n".join(lines) + "\n"


def test_semicolon_and_tab_files_are_read_and_named(arm, data, tmp_path, caplog):
    q, _, wrenches = data
    header = [f"q{i + 1}" for i in range(6)] + WRENCH
    reference = load_samples(
        _write(tmp_path / "comma.csv", _text(header, np.hstack([q, wrenches])))
    )
    for delimiter, name in ((";", "semicolon"), ("\t", "tab")):
        path = _write(tmp_path / f"{name}.csv", _text(header, np.hstack([q, wrenches]), delimiter))
        with caplog.at_level(logging.WARNING):
            loaded = load_samples(path)
        assert f"read as a {name}-separated file" in caplog.text
        np.testing.assert_allclose(
            loaded.samples.wrenches, reference.samples.wrenches, rtol=1e-12, atol=1e-12
        )
        caplog.clear()
    assert sniff_delimiter("# comment, with commas\nfx;fy\n1;2\n") == ";"


def test_decimal_commas_are_named(data, tmp_path):
    q, _, wrenches = data
    header = [f"q{i + 1}" for i in range(6)] + WRENCH
    path = _write(
        tmp_path / "semicolon_comma.csv", _text(header, np.hstack([q, wrenches]), ";", ",")
    )
    with pytest.raises(
        ftkin.InvalidSamples, match=r"line 2: column 'q1': '-?\d+,\d+' has a decimal comma"
    ):
        load_samples(path)
    path = _write(tmp_path / "comma_comma.csv", "fx,fy\n1,5,2,25\n")
    with pytest.raises(
        ftkin.InvalidSamples,
        match="4 cells but the header has 2 columns; the numbers "
        "look like they have decimal commas",
    ):
        read_table(path)
    path = _write(
        tmp_path / "extra_cells.csv", "fx,fy\n1.5,2.25,3,4\n"
    )  # numbers with decimal points: just extra cells
    with pytest.raises(ftkin.InvalidSamples, match=r"4 cells but the header has 2 columns$"):
        read_table(path)


@pytest.mark.parametrize(
    "names",
    [
        ["force.x", "force.y", "force.z", "torque.x", "torque.y", "torque.z"],
        [
            "field.wrench.force.x",
            "field.wrench.force.y",
            "field.wrench.force.z",
            "field.wrench.torque.x",
            "field.wrench.torque.y",
            "field.wrench.torque.z",
        ],
        ["force_x", "force_y", "force_z", "torque_x", "torque_y", "torque_z"],
        ["fx", "fy", "fz", "tx", "ty", "tz"],
        ["Force.X", "Force.Y", "Force.Z", "Tx", "Ty", "Tz"],
    ],
)
def test_ros_style_wrench_names_are_accepted(data, tmp_path, names):
    q, _, wrenches = data
    path = _write(
        tmp_path / "ros.csv",
        _text([f"q{i + 1}" for i in range(6)] + names, np.hstack([q, wrenches])),
    )
    np.testing.assert_allclose(load_samples(path).samples.wrenches, wrenches, rtol=1e-15)
    own = Table("t.csv", ["fx", "mx", "tx"], [["1", "2", "3"]], [2], 1)
    assert spelled_table(own).header == ["fx", "mx", "tx"]  # ftkin's own names win


@pytest.mark.parametrize("other, right", [("Fx", "fx"), ("FX", "fx"), ("Mz", "mz"), ("Tz", "mz")])
def test_the_vendors_spellings_are_read(data, tmp_path, other, right):
    """ATI's and Bota's own names (Fx..Tz), in any case, are ftkin's wrench columns."""
    q, _, wrenches = data
    header = [f"q{i + 1}" for i in range(6)] + [other if n == right else n for n in WRENCH]
    path = _write(tmp_path / "case.csv", _text(header, np.hstack([q, wrenches])))
    np.testing.assert_allclose(load_samples(path).samples.wrenches, wrenches, rtol=1e-15)


@pytest.mark.parametrize("wrong, right", [("f_x", "fx"), ("Fx_N", "fx")])
def test_did_you_mean_maps_the_users_name_to_ftkins(data, tmp_path, wrong, right):
    q, _, wrenches = data
    header = [f"q{i + 1}" for i in range(6)] + [wrong if n == right else n for n in WRENCH]
    path = _write(tmp_path / "case.csv", _text(header, np.hstack([q, wrenches])))
    with pytest.raises(
        ftkin.InvalidSamples, match=rf"did you mean: rename column '{wrong}' to '{right}'\?"
    ):
        load_samples(path)


def test_mixed_conventions_refused_without_urdf(arm, data, tmp_path):
    q, rotations, wrenches = data
    euler = np.rad2deg(matrix_to_euler_zyx(rotations))
    for joints in (
        arm.joint_names,
        [f"q{i + 1}" for i in range(6)],
        [f"my_joint_{i}" for i in range(6)],
    ):
        header = ["alpha", "beta", "gamma", *joints, *WRENCH]
        path = _write(tmp_path / "mixed.csv", _text(header, np.hstack([euler, q, wrenches])))
        with pytest.raises(ftkin.InvalidSamples, match="mixed orientation conventions"):
            load_samples(path)  # no arm given
        with pytest.raises(ftkin.InvalidSamples, match="mixed orientation conventions"):
            load_samples(path, arm)


def test_joint_values_outside_limits_warn_once_per_column(arm, data, tmp_path, caplog):
    q, _, wrenches = data
    q = q.copy()
    upper = arm.upper_limits
    lower = arm.lower_limits
    q[0, 1] = min(upper[1] + 0.2, 6.2)
    q[1, 1] = min(upper[1] + 0.1, 6.2)
    q[2, 4] = max(lower[4] - 0.1, -6.2)
    path = _write(
        tmp_path / "limits.csv",
        _text([f"q{i + 1}" for i in range(6)] + WRENCH, np.hstack([q, wrenches])),
    )
    with caplog.at_level(logging.WARNING):
        load_samples(path, arm)
    warnings = [
        r.getMessage() for r in caplog.records if "outside the URDF limits" in r.getMessage()
    ]
    assert len(warnings) == 2
    assert (
        f"'joint2' has 2 value(s) outside the URDF limits [{lower[1]:g}, {upper[1]:g}] rad"
        in warnings[0]
    )  # warned by Samples.from_joint_positions, by the arm's joint names
    assert "'joint5' has 1 value(s)" in warnings[1]
    q[3, 0] = 90.0  # beyond 2π: still refused as degrees
    path = _write(
        tmp_path / "degrees.csv",
        _text([f"q{i + 1}" for i in range(6)] + WRENCH, np.hstack([q, wrenches])),
    )
    with pytest.raises(ftkin.InvalidSamples, match="look like degrees"):
        load_samples(path, arm)


def test_duplicate_header_check_is_linear(tmp_path):
    header = [f"c{i}" for i in range(100_000)] + ["c5", "c77"]
    path = _write(
        tmp_path / "wide.csv", ",".join(header) + "\n" + ",".join("0" for _ in header) + "\n"
    )
    start = time.perf_counter()
    with pytest.raises(ftkin.InvalidSamples, match=r"duplicated column\(s\) \['c5', 'c77'\]"):
        read_table(path)
    assert time.perf_counter() - start < 5.0  # quadratic: minutes


def _write(path, text):
    path.write_text(text)
    return path


@pytest.mark.parametrize("cell", ["0_3", "３", "٣", "1_000.5"])
def test_a_cell_is_a_number_as_loggers_write_one(tmp_path, cell):
    """Python's float reads '0_3' as 3 and other scripts' digits as digits; no logger writes
    them, so they are text, named with their line."""
    path = tmp_path / "s.csv"
    path.write_text(
        "qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n" + f"1,0,0,0,0,{cell},1,0,0,0\n", encoding="utf-8"
    )
    with pytest.raises(ftkin.InvalidSamples, match=f"column 'fy': '{cell}' is not a number"):
        read_table(path).floats(["fy"])


def test_a_flag_is_a_number_as_a_shell_writes_one(capsys):
    from ftkin.cli import main

    assert main(["plan", "-n", "3", "--noise-force", "0_02", "--noise-torque", "0.002"]) == 2
    assert "--noise-force: expected a number, got '0_02'" in capsys.readouterr().err
    assert main(["plan", "-n", "1_2"]) == 2


@pytest.mark.parametrize(
    "text",
    [
        "# a comment\n\nt,fx,fy\n0,1,2\n",
        "\ufefft;fx;fy\n0;1;2\n",
        "t\tfx\tfy\n0\t1\t2\n",
        '"t", fx ,"fy"\n0,1,2\n',
    ],
    ids=["comment", "bom-semicolon", "tab", "quoted"],
)
def test_the_header_read_alone_is_the_tables(tmp_path, text):
    """read_header (the first line only) is read_table's header (the whole file)."""
    from ftkin.io.csv_table import read_header

    path = tmp_path / "h.csv"
    path.write_text(text, encoding="utf-8")
    assert read_header(path) == read_table(path).header == ["t", "fx", "fy"]


def test_a_header_that_read_table_refuses_gets_its_error(tmp_path):
    from ftkin.io.csv_table import read_header

    path = tmp_path / "dup.csv"
    path.write_text("t,fx,fx\n0,1,2\n")
    with pytest.raises(ftkin.InvalidSamples, match="duplicated column"):
        read_header(path)
    with pytest.raises(ftkin.InvalidSamples, match="file not found"):
        read_header(tmp_path / "none.csv")
