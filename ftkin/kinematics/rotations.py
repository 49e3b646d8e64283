"""Orientation conversions, all to the canonical ``(N, 3, 3)`` form ``R_BS``.

``R_BS`` (``rotation_sensor_to_base``) maps a vector expressed in the sensor
frame S into the robot base frame B: ``v_B = R_BS @ v_S``.

Also the base tilt of METHOD.md §2: the world-to-base rotation
``R_WB = Rx(U) Ry(V)`` and its link to gravity expressed in the base frame,
``a = [G cosU sinV, -G sinU, -G cosU cosV]``.
"""

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_batch, as_real, as_rotation_batch, as_vector


def euler_zyx_to_matrix(angles_rad) -> np.ndarray:
    """Intrinsic Z-Y-X Euler angles to rotation matrices, ``R = Rz(α) Ry(β) Rx(γ)``.

    Args:
        angles_rad: ``(3,)`` or ``(N, 3)`` array of ``[α, β, γ]`` [rad].

    Returns:
        ``(3, 3)`` or ``(N, 3, 3)`` rotation matrices.
    """
    angles, single = as_batch(angles_rad, 3, "euler angles [alpha, beta, gamma]")
    (c1, c2, c3), (s1, s2, s3) = np.cos(angles).T, np.sin(angles).T
    out = np.stack(
        [
            *(c1 * c2, c1 * s2 * s3 - s1 * c3, c1 * s2 * c3 + s1 * s3),
            *(s1 * c2, s1 * s2 * s3 + c1 * c3, s1 * s2 * c3 - c1 * s3),
            *(-s2, c2 * s3, c2 * c3),
        ],
        axis=-1,
    ).reshape(-1, 3, 3)
    return out[0] if single else out


def euler_zyx_deg_to_matrix(angles_deg) -> np.ndarray:
    """The paper's commanded Euler angles ``[α, β, γ]`` [deg] to ``R_BS``.

    This is the convention of the EPSON controller used in the paper
    (intrinsic Z-Y-X, ``Rz(α) Ry(β) Rx(γ)``), in degrees as its Table 1 gives.
    """
    angles, single = as_batch(angles_deg, 3, "euler angles [alpha, beta, gamma] (deg)")
    return euler_zyx_to_matrix(np.deg2rad(angles[0] if single else angles))


def matrix_to_euler_zyx(rotation) -> np.ndarray:
    """Inverse of :func:`euler_zyx_to_matrix`, ``[α, β, γ]`` [rad], β in [-π/2, π/2].

    Raises:
        InvalidInput: not a ``(3, 3)`` / ``(N, 3, 3)`` finite rotation matrix.
    """
    r, single = as_rotation_batch(rotation, "rotation")
    r = r[0] if single else r
    return np.stack(
        [
            np.arctan2(r[..., 1, 0], r[..., 0, 0]),  # α
            np.arcsin(np.clip(-r[..., 2, 0], -1.0, 1.0)),  # β
            np.arctan2(r[..., 2, 1], r[..., 2, 2]),  # γ
        ],
        axis=-1,
    )


def quaternion_to_matrix(quaternion_wxyz, atol: float = 1e-3) -> np.ndarray:
    """Unit quaternions ``[w, x, y, z]`` (sensor orientation in base) to ``R_BS``.

    Args:
        quaternion_wxyz: ``(4,)`` or ``(N, 4)``, scalar first. Norms must be
            within ``atol`` of 1 (they are then normalized), so that a
            quaternion written in ``[x, y, z, w]`` order or a typo is caught
            only by luck; the order is the caller's responsibility.
        atol: Allowed deviation of the norm from 1.
    """
    quats, single = as_batch(quaternion_wxyz, 4, "quaternion [qw, qx, qy, qz]")
    norms = np.linalg.norm(quats, axis=1)
    bad = np.flatnonzero(np.abs(norms - 1.0) > atol)
    if bad.size:
        i = int(bad[0])
        raise InvalidInput(
            f"quaternion [qw, qx, qy, qz] #{i} has norm {norms[i]:.6f}; expected a unit quaternion"
        )
    w, x, y, z = (quats / norms[:, None]).T
    out = np.stack(
        [
            *(1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)),
            *(2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)),
            *(2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)),
        ],
        axis=-1,
    ).reshape(-1, 3, 3)
    return out[0] if single else out


def matrix_entries_to_matrix(entries_row_major, atol: float = 1e-3) -> np.ndarray:
    """Nine entries ``r11, r12, r13, r21, ..., r33`` of ``R_BS`` (row-major: ``r12`` is row 1,
    column 2) to ``(N, 3, 3)`` rotation matrices, re-orthonormalized (nearest rotation, by SVD).

    Args:
        entries_row_major: ``(9,)`` or ``(N, 9)``.
        atol: Largest allowed deviation of ``RᵀR`` from the identity (entries printed with a few
            digits pass; a scaled, sheared or mistyped matrix does not).

    Raises:
        InvalidInput: a matrix that is not a rotation (not orthonormal within ``atol``, or a
            reflection with determinant −1), naming its index.
    """
    entries, single = as_batch(entries_row_major, 9, "rotation matrix entries r11..r33")
    matrices = entries.reshape(-1, 3, 3)
    gram = np.einsum("nki,nkj->nij", matrices, matrices) - np.eye(3)
    error = np.abs(gram).max(axis=(1, 2))
    determinant = np.linalg.det(matrices)
    bad = np.flatnonzero((error > atol) | (determinant <= 0))
    if bad.size:
        i = int(bad[0])
        what = (
            f"determinant {determinant[i]:.4f} (a reflection: an axis reversed)"
            if determinant[i] <= 0
            else f"RᵀR off the identity by {error[i]:.3g}"
        )
        raise InvalidInput(
            f"rotation matrix r11..r33 #{i} is not a rotation: {what}; expected the row-major "
            "entries of R_BS (orthonormal, determinant +1)"
        )
    u, _, vt = np.linalg.svd(matrices)
    out = u @ vt
    return out[0] if single else out


def matrix_to_quaternion(rotation) -> np.ndarray:
    """Rotation matrices to unit quaternions ``[w, x, y, z]`` with ``w >= 0``.

    Raises:
        InvalidInput: not a ``(3, 3)`` / ``(N, 3, 3)`` finite rotation matrix.
    """
    from scipy.spatial.transform import Rotation  # at the file edge only: not with ftkin

    r, single = as_rotation_batch(rotation, "rotation")
    out = Rotation.from_matrix(r).as_quat()[:, [3, 0, 1, 2]]  # scipy >= 1.10: x, y, z, w
    out[out[:, 0] < 0] *= -1.0
    return out[0] if single else out


def gravity_in_base_from_tilt(weight: float, tilt_u: float, tilt_v: float) -> np.ndarray:
    """Tool gravity in the base frame ``a`` [N] from weight G [N] and tilt U, V [rad].

    ``a = [G cosU sinV, -G sinU, -G cosU cosV]`` (METHOD.md §3), i.e.
    ``R_WB^T [0, 0, -G]`` with ``R_WB = Rx(U) Ry(V)``.
    """
    weight, tilt_u, tilt_v = (
        as_real(value, name) for value, name in zip((weight, tilt_u, tilt_v), ("weight", "U", "V"))
    )
    cu, su, cv, sv = np.cos(tilt_u), np.sin(tilt_u), np.cos(tilt_v), np.sin(tilt_v)
    return weight * np.array([cu * sv, -su, -cu * cv])


def tilt_from_gravity_in_base(gravity_in_base) -> tuple[float, float]:
    """Base tilt ``(U, V)`` [rad] from gravity in the base frame.

    ``U = asin(-ay / G)``, ``V = atan2(ax, -az)`` (the paper's
    ``atan(-ax / az)`` for an upright base, and also right for an inverted one).
    """
    a = as_vector(gravity_in_base, 3, "gravity_in_base")
    weight = float(np.linalg.norm(a))
    if weight == 0.0:
        raise InvalidInput("gravity_in_base is zero: the tilt of the base is undefined")
    return float(np.arcsin(np.clip(-a[1] / weight, -1.0, 1.0))), float(np.arctan2(a[0], -a[2]))


def wrenches_base_to_sensor(rotations: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """``[R_BSᵀ F_B, R_BSᵀ M_B]`` ``(N, 6)`` [N, N·m]: base-axes wrenches in sensor axes.

    The moment stays about the same point (the sensor origin); the transport to another point
    is :class:`~ftkin.control.control_frame.ControlFrame`'s.
    """
    return np.einsum("nji,nkj->nki", rotations, wrenches.reshape(-1, 2, 3)).reshape(-1, 6)
