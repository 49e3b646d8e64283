"""A pose set read from a table (ftkin.io.pose_table): one pose per pose id, in time order, against
rotations written by hand."""

from __future__ import annotations

import numpy as np

from ftkin.io.csv_table import read_table
from ftkin.io.pose_table import pose_set_from_table


def _rx(degrees: float) -> np.ndarray:
    """Rotation about x by ``degrees``: the ``gamma`` column alone (R = Rz(α) Ry(β) Rx(γ))."""
    c, s = np.cos(np.radians(degrees)), np.sin(np.radians(degrees))
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def test_one_pose_per_id_its_first_row_in_the_order_of_the_time_column(tmp_path):
    path = tmp_path / "poses.csv"
    # pose 1 is read twice (its second row, at another angle, is not the pose), then pose 0
    # earlier, then pose 2 later
    path.write_text("t,pose,alpha,beta,gamma\n30,1,0,0,90\n31,1,0,0,95\n10,0,0,0,0\n50,2,0,0,180\n")
    poses = pose_set_from_table(read_table(path))
    np.testing.assert_allclose(poses.times, [10.0, 30.0, 50.0])
    np.testing.assert_allclose(poses.rotations, [_rx(0), _rx(90), _rx(180)], atol=1e-12)
    untimed = tmp_path / "untimed.csv"
    untimed.write_text("pose,alpha,beta,gamma\n1,0,0,90\n1,0,0,95\n0,0,0,0\n2,0,0,180\n")
    poses = pose_set_from_table(read_table(untimed))
    assert poses.times is None  # the file's order
    np.testing.assert_allclose(poses.rotations, [_rx(90), _rx(0), _rx(180)], atol=1e-12)


def test_without_a_pose_column_every_row_is_a_pose_and_ties_keep_the_file_order(tmp_path):
    path = tmp_path / "poses.csv"
    path.write_text("t,alpha,beta,gamma\n5,0,0,45\n5,0,0,90\n1,0,0,0\n")
    poses = pose_set_from_table(read_table(path))
    np.testing.assert_allclose(poses.times, [1.0, 5.0, 5.0])
    np.testing.assert_allclose(poses.rotations, [_rx(0), _rx(45), _rx(90)], atol=1e-12)
