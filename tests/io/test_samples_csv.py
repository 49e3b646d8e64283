"""Samples CSV: the orientation conventions agree; errors name the file and line."""

from __future__ import annotations

import numpy as np
import pytest

import ftkin
from ftkin.io.csv_table import read_table, write_csv
from ftkin.io.samples_csv import load_samples
from ftkin.kinematics.rotations import matrix_to_euler_zyx, matrix_to_quaternion

WRENCH = ["fx", "fy", "fz", "mx", "my", "mz"]


@pytest.fixture
def poses(arm, rng, truth):
    configurations = arm.random_configurations(6, rng, margin=0.2)
    rotations = arm.rotation_sensor_to_base(configurations)
    wrenches = truth.predict(rotations) + rng.normal(scale=0.01, size=(6, 6))
    return configurations, rotations, wrenches


def _write(path, header, rows):
    write_csv(path, header, [[float(v) for v in row] for row in rows])
    return path


def test_four_orientation_conventions_agree(arm, poses, tmp_path):
    configurations, rotations, wrenches = poses
    euler_deg = np.rad2deg(matrix_to_euler_zyx(rotations))
    quaternions = matrix_to_quaternion(rotations)
    generic = [f"q{i + 1}" for i in range(arm.nq)]
    files = {
        "joint names": _write(
            tmp_path / "names.csv", arm.joint_names + WRENCH, np.hstack([configurations, wrenches])
        ),
        "q1..qn": _write(
            tmp_path / "generic.csv", WRENCH + generic, np.hstack([wrenches, configurations])
        ),
        "euler": _write(
            tmp_path / "euler.csv",
            ["alpha", "beta", "gamma"] + WRENCH,
            np.hstack([euler_deg, wrenches]),
        ),
        "quaternion": _write(
            tmp_path / "quat.csv",
            ["qw", "qx", "qy", "qz"] + WRENCH,
            np.hstack([quaternions, wrenches]),
        ),
    }
    kinds = {}
    for name, path in files.items():
        loaded = load_samples(path, arm)
        kinds[name] = loaded.orientation
        np.testing.assert_allclose(loaded.samples.rotations, rotations, atol=1e-12, err_msg=name)
        np.testing.assert_array_equal(loaded.samples.wrenches, wrenches)
    assert kinds == {
        "joint names": "joints",
        "q1..qn": "joints",
        "euler": "euler",
        "quaternion": "quaternion",
    }
    # joint columns keep the joint angles and the URDF for the calibration file
    loaded = load_samples(files["joint names"], arm)
    np.testing.assert_array_equal(loaded.samples.joint_positions, configurations)
    assert loaded.samples.urdf == str(arm.urdf_path) and loaded.samples.sensor_frame == "ft_sensor"


def test_joint_columns_without_arm_use_the_bundled_arm(arm, poses, tmp_path):
    configurations, rotations, wrenches = poses
    path = _write(
        tmp_path / "generic.csv",
        [f"q{i + 1}" for i in range(6)] + WRENCH,
        np.hstack([configurations, wrenches]),
    )
    np.testing.assert_allclose(load_samples(path).samples.rotations, rotations, atol=1e-15)


def test_pose_column_groups_readings(arm, poses, tmp_path):
    configurations, _, wrenches = poses
    configurations = np.repeat(
        configurations[::2], 2, axis=0
    )  # repeated readings of three static poses
    pose = np.array([4, 4, 9, 9, 2, 2])
    path = _write(
        tmp_path / "grouped.csv",
        ["pose"] + arm.joint_names + WRENCH,
        np.column_stack([pose, configurations, wrenches]),
    )
    samples = load_samples(path, arm).samples
    np.testing.assert_array_equal(samples.pose_ids, pose)
    averages = samples.pose_averages()
    np.testing.assert_array_equal(averages.pose_ids, [4, 9, 2])
    np.testing.assert_array_equal(averages.counts, [2, 2, 2])
    np.testing.assert_allclose(
        averages.wrenches,
        [wrenches[0:2].mean(0), wrenches[2:4].mean(0), wrenches[4:6].mean(0)],
        atol=1e-15,
    )


def test_comments_blank_lines_and_extra_columns(tmp_path):
    path = tmp_path / "commented.csv"
    path.write_text(
        "# a comment\n\nalpha,beta,gamma,fx,fy,fz,mx,my,mz,time\n# another\n"
        "90,0,-180,1,2,3,4,5,6,0.5\n\n 0, 10 ,20,1,2,3,4,5,6,0.6\n"
    )
    loaded = load_samples(path)
    assert loaded.table.lines == [5, 7]
    assert loaded.table.header[-1] == "time" and loaded.table.rows[1][-1] == "0.6"
    np.testing.assert_allclose(
        loaded.samples.rotations[1],
        ftkin.kinematics.euler_zyx_deg_to_matrix([0, 10, 20]),
        atol=1e-15,
    )


def test_write_csv_round_trips_floats_exactly(tmp_path, rng):
    values = rng.normal(size=(4, 3)) * 10.0 ** rng.integers(-8, 8, size=(4, 3))
    path = write_csv(tmp_path / "out.csv", ["a", "b", "c"], values.tolist())
    table = read_table(path)
    np.testing.assert_array_equal(table.floats(["a", "b", "c"]), values)


# ---------------------------------------------------------------- errors
HEADER = "alpha,beta,gamma,fx,fy,fz,mx,my,mz"
ROW = "90,0,-180,1,2,3,4,5,6"


def _assert_error(tmp_path, text, pattern, line=None, arm=None, name="bad.csv"):
    path = tmp_path / name
    path.write_text(text)
    with pytest.raises(ftkin.InvalidSamples, match=pattern) as info:
        load_samples(path, arm)
    assert info.value.source == str(path)
    assert str(path) in str(info.value)
    if line is not None:
        assert info.value.line == line
        assert f"line {line}:" in str(info.value)
    return info.value


def test_missing_file(tmp_path):
    with pytest.raises(ftkin.InvalidSamples, match="absent.csv: file not found"):
        load_samples(tmp_path / "absent.csv")


def test_misspelled_wrench_column_suggests(tmp_path):
    # regression: a case-only difference was not suggested (difflib ratio too low for 2 letters)
    text = HEADER.replace("fz", "Fz_N") + "\n" + ROW + "\n"
    _assert_error(
        tmp_path,
        text,
        r"missing wrench column\(s\) \['fz'\] \(did you mean: rename column 'Fz_N' to 'fz'\?\)",
        line=1,
    )


def test_missing_orientation_columns(tmp_path):
    text = "fx,fy,fz,mx,my,mz,alpah,beta,gamma\n1,2,3,4,5,6,0,0,0\n"
    _assert_error(
        tmp_path,
        text,
        r"missing Euler angle column\(s\) \['alpha'\].*did you mean: rename column 'alpah' to "
        r"'alpha'",
        arm=None,
    )


def test_no_orientation_at_all(tmp_path, arm):
    text = "fx,fy,fz,mx,my,mz,time\n1,2,3,4,5,6,0\n"
    _assert_error(
        tmp_path,
        text,
        r"no orientation columns: expected the arm's joint names \['joint1'.*alpha,beta,gamma",
        arm=arm,
    )


def test_joint_columns_of_another_robot(tmp_path, arm):
    names = [
        "shoulder_pan_joint",
        "shoulder_lift_joint",
        "elbow_joint",
        "wrist_1_joint",
        "wrist_2_joint",
        "wrist_3_joint",
    ]
    text = ",".join(names) + ",fx,fy,fz,mx,my,mz\n" + ",".join(["0"] * 12) + "\n"
    _assert_error(
        tmp_path,
        text,
        r"columns \['shoulder_pan_joint'.* look like joint names but are not this arm's",
        arm=arm,
    )


def test_incomplete_quaternion(tmp_path):
    text = "qw,qx,qy,fx,fy,fz,mx,my,mz\n1,0,0,1,2,3,4,5,6\n"
    _assert_error(tmp_path, text, r"missing quaternion column\(s\) \['qz'\]")


def test_text_in_numeric_cell(tmp_path):
    text = HEADER + "\n" + ROW + "\n" + ROW.replace(",3,", ",three,") + "\n"
    _assert_error(tmp_path, text, "column 'fz': 'three' is not a number", line=3)


@pytest.mark.parametrize("cell", ["nan", "NaN", "inf", "-Infinity"])
def test_non_finite_cell(tmp_path, cell):
    text = "# comment\n" + HEADER + "\n" + ROW.replace(",5,", f",{cell},") + "\n"
    _assert_error(tmp_path, text, f"column 'my': '{cell}' is not finite", line=3)


def test_empty_cell(tmp_path):
    text = HEADER + "\n" + ROW.replace(",4,", ",,") + "\n"
    _assert_error(tmp_path, text, "column 'mx': '' is not a number", line=2)


def test_duplicated_columns(tmp_path):
    text = HEADER + ",fx\n" + ROW + ",1\n"
    _assert_error(tmp_path, text, r"duplicated column\(s\) \['fx'\]", line=1)


def test_mixed_orientation_conventions(tmp_path):
    text = HEADER + ",qw,qx,qy,qz\n" + ROW + ",1,0,0,0\n"
    _assert_error(
        tmp_path,
        text,
        "mixed orientation conventions: euler columns.*quaternion columns.*exactly one",
    )


def test_joint_names_and_generic_columns_mixed(tmp_path, arm):
    text = "joint1,q2,fx,fy,fz,mx,my,mz\n0,0,1,2,3,4,5,6\n"
    _assert_error(
        tmp_path,
        text,
        r"both URDF joint-name columns \['joint1'\] and generic columns \['q2'\]",
        arm=arm,
    )


def test_degrees_where_radians_expected(tmp_path, arm):
    rows = ["0,0,-30,0,-60,0,1,2,3,4,5,6", "0,0,-30,0,-60,0,1,2,3,4,5,6"]
    text = (
        "q1,q2,q3,q4,q5,q6,fx,fy,fz,mx,my,mz\n0,0,-0.5,0,-1,0,1,2,3,4,5,6\n"
        + "\n".join(rows)
        + "\n"
    )
    _assert_error(
        tmp_path,
        text,
        "joint column 'q3' holds -30, outside ±2π.*radians.*degrees",
        line=3,
        arm=arm,
    )


def test_empty_file(tmp_path):
    _assert_error(tmp_path, "", "file is empty; expected a header row")
    _assert_error(tmp_path, "# only a comment\n\n", "file is empty", name="comment.csv")


def test_header_only(tmp_path):
    _assert_error(tmp_path, HEADER + "\n", "no data rows after the header")


def test_row_with_wrong_cell_count(tmp_path):
    text = HEADER + "\n" + ROW + "\n" + ROW + ",7\n" + ROW + "\n"
    _assert_error(tmp_path, text, "10 cells but the header has 9 columns", line=3)


def test_joint_columns_that_do_not_match_the_arm(tmp_path, arm):
    text = "q1,q2,q3,q4,q5,fx,fy,fz,mx,my,mz\n0,0,0,0,0,1,2,3,4,5,6\n"
    _assert_error(
        tmp_path,
        text,
        r"joint columns \['q1', .*'q5'\] do not match the arm's 6 joints.*'q6'.*joint1",
        arm=arm,
    )
    text = "joint1,joint2,joint3,fx,fy,fz,mx,my,mz\n0,0,0,1,2,3,4,5,6\n"
    _assert_error(
        tmp_path,
        text,
        r"missing joint column\(s\) \['joint4', 'joint5', 'joint6'\]",
        arm=arm,
        name="named.csv",
    )


def test_non_integer_pose_id(tmp_path):
    # regression: the message showed np.float64(1.5)
    text = "pose," + HEADER + "\n1," + ROW + "\n1.5," + ROW + "\n"
    _assert_error(tmp_path, text, "pose id 1.5 is not an integer", line=3)


def test_non_unit_quaternion(tmp_path):
    text = "qw,qx,qy,qz,fx,fy,fz,mx,my,mz\n1,0,0,0,1,2,3,4,5,6\n0.5,0.5,0,0,1,2,3,4,5,6\n"
    _assert_error(
        tmp_path, text, r"line 3: quaternion \[qw, qx, qy, qz\] has norm 0.707107; expected a unit"
    )


def test_missing_column_points_at_the_header_line(tmp_path):
    # regression: the line was the one before the first data row, a comment here
    text = "# c1\n" + HEADER.replace("my", "Myy") + "\n# c2\n# c3\n" + ROW + "\n"
    _assert_error(
        tmp_path,
        text,
        r"missing wrench column\(s\) \['my'\] \(did you mean: rename column 'Myy' to 'my'",
        line=2,
    )


def test_excel_byte_order_mark_and_crlf(tmp_path):
    # regression: the UTF-8 byte-order mark stuck to the first column name
    path = tmp_path / "excel.csv"
    path.write_bytes(
        ("\ufeff" + HEADER + "\r\n" + ROW + "\r\n0,30,180,1,2,3,4,5,6\r\n").encode("utf-8")
    )
    loaded = load_samples(path)
    assert loaded.table.header[0] == "alpha"
    np.testing.assert_allclose(
        loaded.samples.rotations[1],
        ftkin.kinematics.euler_zyx_deg_to_matrix([0, 30, 180]),
        atol=1e-15,
    )


def test_an_arm_whose_joints_are_named_q1_to_qn(tmp_path, arm, rng, truth):
    """A URDF whose joints are named ``q1..q6``: its joint columns are both the URDF names and
    the generic ones, one set (they were refused as "both ... use one"). The readings are the
    simulator's truth at FK poses of the bundled arm, which has the same chain."""
    text = arm.urdf_path.read_text()
    for i in range(6, 0, -1):
        text = text.replace(f'"joint{i}"', f'"q{i}"')
    urdf = tmp_path / "q_named.urdf"
    urdf.write_text(text)
    renamed = ftkin.Arm.from_urdf(urdf, "ft_sensor")
    assert renamed.joint_names == [f"q{i}" for i in range(1, 7)]
    configurations = arm.random_configurations(8, rng, margin=0.2)
    wrenches = truth.predict(arm.rotation_sensor_to_base(configurations))
    path = _write(
        tmp_path / "q.csv",
        [*renamed.joint_names, *WRENCH],
        np.column_stack([configurations, wrenches]),
    )
    loaded = load_samples(path, renamed)
    np.testing.assert_allclose(
        loaded.samples.rotations, arm.rotation_sensor_to_base(configurations), atol=1e-12
    )
