"""The IMU model of a wrist sensor, written once: the reading from the sensor's own accelerometer
and gyro, with no arm model.

Frames: S the F/T sensor's axes, I the IMU's axes. ``R_SI`` (``imu_rotation``) maps IMU-frame
vectors to S; ``r`` (``imu_position``) is the IMU's origin in S [m].

The accelerometer reads the specific force ``f_I`` (``+g`` upward at rest, [m/s²], IMU frame)
with a bias ``b`` [m/s²] and scale errors ``s`` [-]; the gyro reads ``ω_I`` [rad/s]::

    a = (1 + s) ∘ f_I + b,        w = ω_I

In S, with ``ω = R_SI w`` and ``α = ω̇`` [rad/s²], the specific force at the sensor origin is::

    f_S = R_SI (a − b) ⊘ (1 + s) − α × r − ω × (ω × r)

and the reading without contact (the load on the sensor, ftkin's sign) is, with the body
regressor ``Y`` of :mod:`ftkin.calibration.regressor` and the tool's inertial parameters θ::

    raw = [F0, M0] − Y([0, ω], [f_S, α]) θ

At rest (``ω = α = 0``) this is ``F = F0 − m f_S``, ``M = M0 − m c × f_S``: a tool hanging
below an upright sensor (``f_S = [0, 0, +g]``) pulls it down by ``m g``.

:func:`specific_force_in_sensor` and :func:`predict_imu` are the formula (validated arrays);
:class:`ImuFloatModel` is the control tick's fast path beside it (Python floats, the model folded
into a few constant matrices), tested against :func:`predict_imu` to 1e-12.
"""

import numpy as np

from .model import cross_rows
from .regressor import body_regressor

ACCEL_BIAS_NAMES = ("accel_bias[x]", "accel_bias[y]", "accel_bias[z]")
ACCEL_SCALE_NAMES = ("accel_scale[x]", "accel_scale[y]", "accel_scale[z]")
IMU_ROTATION_NAMES = ("imu_rotation[x]", "imu_rotation[y]", "imu_rotation[z]")
"""Increments of ``R_SI`` [rad] about the sensor's axes."""
IMU_POSITION_NAMES = ("imu_position[x]", "imu_position[y]", "imu_position[z]")


def corrected_specific_force(accel: np.ndarray, bias, scale) -> np.ndarray:
    """``(a − b) ⊘ (1 + s)`` ``(N, 3)``: the accelerometer's reading corrected, IMU frame
    [m/s²].
    """
    return (accel - np.asarray(bias, dtype=float)) / (1.0 + np.asarray(scale, dtype=float))


def specific_force_in_sensor(
    accel: np.ndarray,
    imu_rotation: np.ndarray,
    bias=(0.0, 0.0, 0.0),
    scale=(0.0, 0.0, 0.0),
    imu_position=None,
    angular_velocity: np.ndarray | None = None,
    angular_acceleration: np.ndarray | None = None,
) -> np.ndarray:
    """``f_S`` ``(N, 3)`` [m/s²]: the specific force at the sensor origin, sensor axes.

    Args:
        accel: ``(N, 3)`` accelerometer readings [m/s², IMU frame].
        imu_rotation: ``R_SI`` ``(3, 3)``.
        bias, scale: ``b`` [m/s²] and ``s`` [-] ``(3,)``.
        imu_position: ``r`` ``(3,)`` [m, sensor frame], or None (the lever arm ignored).
        angular_velocity, angular_acceleration: ``ω``, ``α`` ``(N, 3)`` in **sensor** axes
            [rad/s, rad/s²] (needed with ``imu_position``).
    """
    out = corrected_specific_force(accel, bias, scale) @ np.asarray(imu_rotation).T
    if imu_position is not None and angular_velocity is not None:
        r = np.broadcast_to(np.asarray(imu_position, dtype=float), out.shape)
        out -= cross_rows(angular_acceleration, r)
        out -= cross_rows(angular_velocity, cross_rows(angular_velocity, r))
    return out


def imu_regressor(
    specific_force: np.ndarray,
    angular_velocity: np.ndarray | None = None,
    angular_acceleration: np.ndarray | None = None,
) -> np.ndarray:
    """``(N, 6, 10)`` ``Y([0, ω], [f_S, α])``: the wrench that holds the tool, per θ.

    ``specific_force`` is ``f_S`` ``(N, 3)`` [m/s², sensor axes]; ``ω``, ``α`` ``(N, 3)`` in sensor
    axes (None: at rest). With the frame's linear velocity set to zero, the body regressor's
    classical acceleration ``a_lin + ω × v_lin`` is ``f_S`` itself.
    """
    zeros = np.zeros_like(specific_force)
    omega = zeros if angular_velocity is None else angular_velocity
    alpha = zeros if angular_acceleration is None else angular_acceleration
    return body_regressor(
        np.concatenate([zeros, omega], axis=1), np.concatenate([specific_force, alpha], axis=1)
    )


def point_mass_parameters(mass: float, center_of_mass) -> np.ndarray:
    """θ ``(10,)`` of a point mass [kg] at ``c`` [m]: ``[m, m c, 0…]`` (a static calibration's)."""
    return np.concatenate([[mass], mass * np.asarray(center_of_mass, dtype=float), np.zeros(6)])


def predict_imu(
    bias_wrench,
    theta: np.ndarray,
    specific_force: np.ndarray,
    angular_velocity: np.ndarray | None = None,
    angular_acceleration: np.ndarray | None = None,
) -> np.ndarray:
    """``(N, 6)`` reading without contact ``[F0, M0] − Y([0, ω], [f_S, α]) θ`` [N, N·m].

    ``f_S``, ``ω``, ``α`` as :func:`imu_regressor` (sensor axes); θ ``(10,)``.
    """
    regressor = imu_regressor(specific_force, angular_velocity, angular_acceleration)
    return np.asarray(bias_wrench, dtype=float) - regressor @ theta


class ImuFloatModel:
    """``raw − predict_imu`` for one reading on Python floats: the IMU control tick's fast path.

    The formula of :func:`predict_imu` with :func:`specific_force_in_sensor`, its constants folded
    (``K = R_SI diag(1/(1+s))``, ``k = K b``)::

        f_S = K a − k − α × r − ω × (ω × r),     ω = R_SI w,  α = R_SI ẇ
        F' = F − F0 + m f_S + α × h + ω × (ω × h)                    (h = m c)
        M' = M − M0 + h × f_S + I α + ω × (I ω)                      (I about the sensor origin)

    At rest it is ``raw − c + A a`` with one ``(6, 3)`` matrix ``A`` and offset ``c``
    (:meth:`contact`). :meth:`set` replaces the parameters; a bound method held elsewhere sees them.
    """

    __slots__ = ("_static", "_moving")

    def __init__(self, imu_rotation, bias, scale, bias_wrench, theta, imu_position=None):
        self.set(imu_rotation, bias, scale, bias_wrench, theta, imu_position)

    def set(self, imu_rotation, bias, scale, bias_wrench, theta, imu_position=None) -> None:
        """Use ``R_SI`` (3, 3), ``b`` [m/s²], ``s`` [-], ``[F0, M0]`` [N, N·m], θ (10,) and ``r``
        [m] (None: zero).
        """
        rotation = np.asarray(imu_rotation, dtype=float)
        gain = rotation / (1.0 + np.asarray(scale, dtype=float))[None, :]  # K = R diag(1/(1+s))
        offset = gain @ np.asarray(bias, dtype=float)  # k = K b
        theta = np.asarray(theta, dtype=float)
        mass, first = float(theta[0]), theta[1:4]
        skew_h = np.array(
            [[0.0, -first[2], first[1]], [first[2], 0.0, -first[0]], [-first[1], first[0], 0.0]]
        )
        static_matrix = np.concatenate([mass * gain, skew_h @ gain])  # A (6, 3)
        static_offset = np.asarray(bias_wrench, dtype=float) + np.concatenate(
            [mass * offset, skew_h @ offset]
        )
        self._static = (
            tuple(static_matrix.reshape(-1).tolist()),
            tuple(static_offset.tolist()),
        )
        inertia = np.array([[theta[4], theta[5], theta[7]], [theta[5], theta[6], theta[8]]])
        inertia = np.vstack([inertia, [theta[7], theta[8], theta[9]]])
        position = np.zeros(3) if imu_position is None else np.asarray(imu_position, dtype=float)
        # The lever arm folded in: α × r and ω × (ω × r) enter the force with h − m r, and the
        # torque as h × (α × r) = ((h·r) 1 − r hᵀ) α and h × (ω (ω·r) − r |ω|²).
        lever_inertia = inertia - float(first @ position) * np.eye(3) + np.outer(position, first)
        self._moving = (
            tuple(rotation.reshape(-1).tolist()),
            tuple((first - mass * position).tolist()),
            tuple(lever_inertia.reshape(-1).tolist()),
            tuple(theta[[4, 5, 6, 7, 8, 9]].tolist()),
            tuple(first.tolist()),
            tuple(position.tolist()),
            tuple(np.cross(first, position).tolist()),
        )

    def contact(self, raw, accel) -> tuple[float, ...]:
        """Six raw floats [N, N·m] and three accelerometer floats [m/s², IMU frame] → the six
        contact floats, the tool at rest (``raw − c + A a``).
        """
        (
            (a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16, a17),
            (
                c0,
                c1,
                c2,
                c3,
                c4,
                c5,
            ),
        ) = self._static
        w0, w1, w2, w3, w4, w5 = raw
        x, y, z = accel
        return (
            w0 - c0 + a0 * x + a1 * y + a2 * z,
            w1 - c1 + a3 * x + a4 * y + a5 * z,
            w2 - c2 + a6 * x + a7 * y + a8 * z,
            w3 - c3 + a9 * x + a10 * y + a11 * z,
            w4 - c4 + a12 * x + a13 * y + a14 * z,
            w5 - c5 + a15 * x + a16 * y + a17 * z,
        )

    def contact_moving(self, raw, accel, gyro, gyro_rate) -> tuple[float, ...]:
        """:meth:`contact` with the gyro's ``w`` [rad/s] and its rate ``ẇ`` [rad/s²] (IMU frame):
        the lever arm and the tool's rotational inertia included.
        """
        rotation, (dx, dy, dz), lever_inertia, inertia, (hx, hy, hz), (rx, ry, rz), hr = (
            self._moving
        )
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = rotation
        gx, gy, gz = gyro
        wx = r00 * gx + r01 * gy + r02 * gz  # ω = R_SI w
        wy = r10 * gx + r11 * gy + r12 * gz
        wz = r20 * gx + r21 * gy + r22 * gz
        gx, gy, gz = gyro_rate
        bx = r00 * gx + r01 * gy + r02 * gz  # α = R_SI ẇ
        by = r10 * gx + r11 * gy + r12 * gz
        bz = r20 * gx + r21 * gy + r22 * gz
        (
            (a0, a1, a2, a3, a4, a5, a6, a7, a8, a9, a10, a11, a12, a13, a14, a15, a16, a17),
            (
                k0,
                k1,
                k2,
                k3,
                k4,
                k5,
            ),
        ) = self._static
        w0, w1, w2, w3, w4, w5 = raw
        x, y, z = accel
        c0 = w0 - k0 + a0 * x + a1 * y + a2 * z  # gravity and the linear acceleration
        c1 = w1 - k1 + a3 * x + a4 * y + a5 * z
        c2 = w2 - k2 + a6 * x + a7 * y + a8 * z
        c3 = w3 - k3 + a9 * x + a10 * y + a11 * z
        c4 = w4 - k4 + a12 * x + a13 * y + a14 * z
        c5 = w5 - k5 + a15 * x + a16 * y + a17 * z
        ux, uy, uz = wy * dz - wz * dy, wz * dx - wx * dz, wx * dy - wy * dx  # ω × d, d = h − m r
        l00, l01, l02, l10, l11, l12, l20, l21, l22 = lever_inertia
        xx, xy, yy, xz, yz, zz = inertia
        jx = xx * wx + xy * wy + xz * wz  # I ω
        jy = xy * wx + yy * wy + yz * wz
        jz = xz * wx + yz * wy + zz * wz
        along = wx * rx + wy * ry + wz * rz  # ω·r
        spin = wx * wx + wy * wy + wz * wz  # |ω|²
        sx, sy, sz = hr
        return (
            c0 + (by * dz - bz * dy) + (wy * uz - wz * uy),  # + α × d + ω × (ω × d)
            c1 + (bz * dx - bx * dz) + (wz * ux - wx * uz),
            c2 + (bx * dy - by * dx) + (wx * uy - wy * ux),
            c3  # + I' α + ω × (I ω) − (h × ω)(ω·r) + (h × r)|ω|²
            + (l00 * bx + l01 * by + l02 * bz)
            + (wy * jz - wz * jy)
            - (hy * wz - hz * wy) * along
            + sx * spin,
            c4
            + (l10 * bx + l11 * by + l12 * bz)
            + (wz * jx - wx * jz)
            - (hz * wx - hx * wz) * along
            + sy * spin,
            c5
            + (l20 * bx + l21 * by + l22 * bz)
            + (wx * jy - wy * jx)
            - (hx * wy - hy * wx) * along
            + sz * spin,
        )
