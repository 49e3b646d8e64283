"""Orientation conversions against scipy's independent implementation."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.kinematics.rotations import (
    euler_zyx_deg_to_matrix,
    euler_zyx_to_matrix,
    gravity_in_base_from_tilt,
    matrix_to_euler_zyx,
    matrix_to_quaternion,
    quaternion_to_matrix,
    tilt_from_gravity_in_base,
)


def _rx(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]])


def _ry(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])


def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def test_euler_zyx_deg_matches_scipy_intrinsic_zyx(rng):
    angles_deg = rng.uniform(-180.0, 180.0, size=(50, 3))
    expected = Rotation.from_euler("ZYX", angles_deg, degrees=True).as_matrix()
    np.testing.assert_allclose(euler_zyx_deg_to_matrix(angles_deg), expected, atol=1e-13)


def test_euler_zyx_matches_elementary_product(rng):
    for alpha, beta, gamma in rng.uniform(-np.pi, np.pi, size=(20, 3)):
        expected = _rz(alpha) @ _ry(beta) @ _rx(gamma)
        np.testing.assert_allclose(euler_zyx_to_matrix([alpha, beta, gamma]), expected, atol=1e-14)


def test_euler_single_and_batch_agree(rng):
    angles = rng.uniform(-180.0, 180.0, size=(5, 3))
    batch = euler_zyx_deg_to_matrix(angles)
    assert batch.shape == (5, 3, 3)
    for row, matrix in zip(angles, batch):
        single = euler_zyx_deg_to_matrix(row)
        assert single.shape == (3, 3)
        np.testing.assert_allclose(single, matrix, rtol=1e-12, atol=1e-15)


def test_paper_first_pose_is_tool_down():
    # alpha=90, beta=0, gamma=-180: Rz(90) Rx(180), sensor z points down.
    rotation = euler_zyx_deg_to_matrix([90.0, 0.0, -180.0])
    np.testing.assert_allclose(rotation @ [0, 0, 1], [0, 0, -1], atol=1e-15)
    np.testing.assert_allclose(rotation @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_matrix_to_euler_inverts(rng):
    angles = np.column_stack(
        [rng.uniform(-np.pi, np.pi, 40), rng.uniform(-1.5, 1.5, 40), rng.uniform(-np.pi, np.pi, 40)]
    )
    recovered = matrix_to_euler_zyx(euler_zyx_to_matrix(angles))
    np.testing.assert_allclose(recovered, angles, atol=1e-12)


def test_quaternion_to_matrix_matches_scipy(rng):
    quaternions = rng.standard_normal((50, 4))
    quaternions /= np.linalg.norm(quaternions, axis=1, keepdims=True)
    # scipy is scalar last
    expected = Rotation.from_quat(quaternions[:, [1, 2, 3, 0]]).as_matrix()
    np.testing.assert_allclose(quaternion_to_matrix(quaternions), expected, atol=1e-14)


def test_matrix_to_quaternion_matches_scipy_and_inverts(rng):
    rotations = Rotation.random(60, random_state=7)
    matrices = rotations.as_matrix()
    # include the trace <= 0 branches: half turns about each axis
    matrices = np.concatenate([matrices, [_rx(np.pi), _ry(np.pi), _rz(np.pi), _rx(3.0) @ _ry(2.9)]])
    quaternions = matrix_to_quaternion(matrices)
    assert np.all(quaternions[:, 0] >= 0)
    np.testing.assert_allclose(np.linalg.norm(quaternions, axis=1), 1.0, atol=1e-14)
    expected = Rotation.from_matrix(matrices).as_quat()[:, [3, 0, 1, 2]]
    expected *= np.where(expected[:, :1] < 0, -1.0, 1.0)
    # q and -q are the same rotation; compare up to sign when w == 0
    for ours, theirs in zip(quaternions, expected):
        assert min(np.abs(ours - theirs).max(), np.abs(ours + theirs).max()) < 1e-12
    np.testing.assert_allclose(quaternion_to_matrix(quaternions), matrices, atol=1e-13)


def test_matrix_to_quaternion_single():
    q = matrix_to_quaternion(_rz(0.3))
    assert q.shape == (4,)
    np.testing.assert_allclose(q, [np.cos(0.15), 0, 0, np.sin(0.15)], atol=1e-15)


def test_slightly_unnormalized_quaternion_is_normalized():
    q = np.array([1.0, 0.0, 0.0, 1.0]) / np.sqrt(2) * (1 + 5e-4)
    np.testing.assert_allclose(quaternion_to_matrix(q), _rx(0) @ _rz(np.pi / 2), atol=1e-15)


def test_tilt_gravity_round_trip(rng):
    for tilt_u, tilt_v in rng.uniform(-0.5, 0.5, size=(20, 2)):
        weight = rng.uniform(0.5, 50.0)
        gravity = gravity_in_base_from_tilt(weight, tilt_u, tilt_v)
        # independent: R_WB = Rx(U) Ry(V); gravity in base = R_WB^T [0, 0, -G]
        expected = (_rx(tilt_u) @ _ry(tilt_v)).T @ [0.0, 0.0, -weight]
        np.testing.assert_allclose(gravity, expected, atol=1e-13)
        recovered = tilt_from_gravity_in_base(gravity)
        np.testing.assert_allclose(recovered, (tilt_u, tilt_v), atol=1e-13)


def test_tilt_of_inverted_base_uses_atan2():
    # a ceiling-mounted base: U = 0, V = 179 deg; atan(-ax/az) would give -1 deg
    tilt_v = np.deg2rad(179.0)
    gravity = gravity_in_base_from_tilt(3.0, 0.0, tilt_v)
    assert gravity[2] > 0  # gravity points "up" in the base frame
    tilt_u, recovered_v = tilt_from_gravity_in_base(gravity)
    assert tilt_u == pytest.approx(0.0, abs=1e-14)
    assert recovered_v == pytest.approx(tilt_v, abs=1e-13)


def test_tilt_of_zero_gravity_is_refused():
    with pytest.raises(ftkin.InvalidInput, match="zero"):
        tilt_from_gravity_in_base([0.0, 0.0, 0.0])


@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        ([1.0, 2.0], r"shape \(3,\) or \(N, 3\)"),
        (np.zeros((2, 4)), r"shape \(3,\) or \(N, 3\)"),
        (np.zeros((2, 3, 1)), r"shape \(3,\) or \(N, 3\)"),
        ([0.0, np.nan, 0.0], "finite.*nan"),
        ([[0.0, 0.0, 0.0], [0.0, 0.0, np.inf]], r"finite.*inf.*\(1, 2\)"),
        (["a", "b", "c"], "numeric"),
    ],
)
def test_bad_euler_angles_are_refused(value, pattern):
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        euler_zyx_deg_to_matrix(value)


@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        ([1.0, 0.0, 0.0], r"shape \(4,\) or \(N, 4\)"),
        ([np.nan, 0.0, 0.0, 0.0], "finite"),
        ([1.0, 1.0, 0.0, 0.0], r"norm 1\.41.*expected a unit quaternion"),
        ([0.0, 0.0, 0.0, 0.0], "norm 0.000000.*unit quaternion"),
        ([[1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0]], "#1 has norm 2"),
    ],
)
def test_bad_quaternions_are_refused(value, pattern):
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        quaternion_to_matrix(value)


def test_invalid_input_is_a_value_error():
    # callers that catch ValueError still catch ftkin's input errors
    with pytest.raises(ValueError):
        quaternion_to_matrix([2.0, 0.0, 0.0, 0.0])


@pytest.mark.parametrize("convert", [matrix_to_euler_zyx, matrix_to_quaternion])
@pytest.mark.parametrize(
    ("value", "pattern"),
    [
        (np.zeros(3), r"shape \(3, 3\) or \(N, 3, 3\)"),
        (np.full((3, 3), np.nan), "finite"),
        (2.0 * np.eye(3), "not a rotation matrix"),
        (np.diag([1.0, 1.0, -1.0]), "determinant"),
    ],
)
def test_bad_matrices_are_refused_by_the_inverse_conversions(convert, value, pattern):
    # regression: these returned NaN or garbage, or raised IndexError
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        convert(value)


def test_matrix_to_quaternion_on_the_oldest_supported_scipy(monkeypatch):
    # pyproject allows scipy >= 1.10; as_quat(scalar_first=...) arrived in 1.14
    real = Rotation.as_quat

    def as_quat_of_scipy_1_10(self, canonical=False):
        return real(self, canonical)

    monkeypatch.setattr(Rotation, "as_quat", as_quat_of_scipy_1_10)
    np.testing.assert_allclose(
        matrix_to_quaternion(_rz(0.3)), [np.cos(0.15), 0, 0, np.sin(0.15)], atol=1e-15
    )
