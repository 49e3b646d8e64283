"""The static sensor model of METHOD.md §1–3: what a wrist F/T sensor reads.

For a sensor orientation ``R_BS`` (sensor to base) the reading without contact is

    F = F0 + Gs,        M = M0 + P × Gs,        Gs = R_BS^T · a

with ``a = gravity_in_base`` the tool's weight vector in the base frame [N],
``F0``/``M0`` the sensor bias [N]/[N·m] and ``P`` the tool's centre of mass in
the sensor frame [m]. The twelve parameters, in this order, form the vector
``θ = [a, F0, M0, P]`` used by the estimators and the Fisher information.

This is the one place the model is written: :class:`SensorModel` (validated), and
:func:`predict`, :func:`tool_gravity` and :func:`parameter_jacobian` on validated arrays,
which every fit, compensator, check and view calls. Two fast paths of the contact wrench
``raw − predict`` sit beside them for the hot loops: :class:`FloatModel` (one reading on
Python floats, the control tick) and :func:`contact_batch` (blocked columns, logs); tests
check both against :func:`predict` to 1e-12.
"""

from dataclasses import dataclass

import numpy as np

from ..kinematics.rotations import gravity_in_base_from_tilt, tilt_from_gravity_in_base
from ..validation import as_positive, as_rotation_batch, as_vector

STANDARD_GRAVITY = 9.80665
"""Standard acceleration of gravity [m/s²] used to turn weight into mass."""

GRAVITY_RANGE = (1.0, 30.0)
"""Plausible acceleration of gravity [m/s²] (the Moon 1.6, Jupiter 24.8): beyond, a unit mistake."""


def check_gravity(value, name: str = "g") -> float:
    """``value`` [m/s²] as a float within :data:`GRAVITY_RANGE`, else :class:`InvalidInput`: the
    one rule for ``g`` (the options, the model, the CLI's ``--g`` and the simulators use it)."""
    from ..validation import as_in_range

    return as_in_range(value, name, *GRAVITY_RANGE, "m/s²")


PARAMETER_NAMES = (
    "gravity_in_base",
    "force_offset",
    "torque_offset",
    "center_of_mass",
)
"""Names of the parameter blocks of ``θ``, three components each."""

COMPONENT_NAMES = tuple(f"{block}[{axis}]" for block in PARAMETER_NAMES for axis in "xyz")
"""Names of the twelve entries of ``θ``."""

WRENCH_CHANNELS = ("fx", "fy", "fz", "mx", "my", "mz")
"""Wrench component order used everywhere in ftkin."""


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product of ``(N, 3)`` (or broadcastable) arrays, written out.

    Faster than ``np.cross`` for small inputs and explicit about broadcasting.
    """
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1]
    out[..., 1] = a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2]
    out[..., 2] = a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]
    return out


def skew(v: np.ndarray) -> np.ndarray:
    """Skew-symmetric matrices ``[v]×`` with ``[v]× w = v × w``; ``(..., 3) -> (..., 3, 3)``."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


@dataclass(frozen=True)
class SensorModel:
    """Bias and tool gravity of a wrist F/T sensor (the calibration parameters).

    Attributes:
        force_offset: Sensor force bias ``F0`` in the sensor frame [N].
        torque_offset: Sensor torque bias ``M0`` in the sensor frame [N·m].
        gravity_in_base: Tool weight vector ``a`` in the base frame [N]
            (points down; it differs from ``[0, 0, -G]`` by the base tilt).
        center_of_mass: Tool centre of mass ``P`` in the sensor frame [m].
        g: Acceleration of gravity used to report the mass [m/s²].
    """

    force_offset: np.ndarray
    torque_offset: np.ndarray
    gravity_in_base: np.ndarray
    center_of_mass: np.ndarray
    g: float = STANDARD_GRAVITY

    def __post_init__(self):
        for name in ("force_offset", "torque_offset", "gravity_in_base", "center_of_mass"):
            vector = as_vector(
                getattr(self, name), 3, name
            ).copy()  # frozen: a copy, never the caller's array
            vector.setflags(write=False)
            object.__setattr__(self, name, vector)
        object.__setattr__(self, "g", check_gravity(self.g))

    @classmethod
    def from_tool(
        cls,
        tool_mass: float,
        center_of_mass,
        force_offset=(0.0, 0.0, 0.0),
        torque_offset=(0.0, 0.0, 0.0),
        base_tilt=(0.0, 0.0),
        g: float = STANDARD_GRAVITY,
    ) -> "SensorModel":
        """Build from a tool mass [kg], COM [m, sensor frame], biases and base tilt (U, V) [rad]."""
        weight = as_positive(tool_mass, "tool_mass") * check_gravity(g)  # [N]
        gravity = gravity_in_base_from_tilt(weight, float(base_tilt[0]), float(base_tilt[1]))
        return cls(force_offset, torque_offset, gravity, center_of_mass, g)

    @property
    def tool_weight(self) -> float:
        """Tool weight ``G = |a|`` [N] (computed without overflow for huge finite values)."""
        scale = float(np.abs(self.gravity_in_base).max())
        return scale * float(np.linalg.norm(self.gravity_in_base / scale)) if scale > 0.0 else 0.0

    def __repr__(self) -> str:
        round_ = lambda values: [round(float(v), 6) for v in values]  # noqa: E731
        return (
            f"{type(self).__name__}(tool_weight={self.tool_weight:.6g} N, "
            f"center_of_mass={round_(self.center_of_mass)} m, "
            f"force_offset={round_(self.force_offset)} N, "
            f"torque_offset={round_(self.torque_offset)} N·m, "
            f"base_tilt_deg={[round(v, 4) for v in self.base_tilt_deg]}, g={self.g:g} m/s²)"
        )

    @property
    def tool_mass(self) -> float:
        """Tool mass ``G / g`` [kg]."""
        return self.tool_weight / self.g

    @property
    def base_tilt(self) -> tuple[float, float]:
        """Base tilt ``(U, V)`` [rad]: ``R_WB = Rx(U) Ry(V)``."""
        return tilt_from_gravity_in_base(self.gravity_in_base)

    @property
    def base_tilt_deg(self) -> tuple[float, float]:
        """Base tilt ``(U, V)`` [deg]."""
        return tuple(float(np.rad2deg(angle)) for angle in self.base_tilt)

    @property
    def bias(self) -> np.ndarray:
        """Sensor bias as a wrench ``[F0, M0]`` [N, N·m]."""
        return np.concatenate([self.force_offset, self.torque_offset])

    def to_vector(self) -> np.ndarray:
        """Parameter vector ``θ = [a, F0, M0, P]`` (12,)."""
        return np.concatenate(
            [self.gravity_in_base, self.force_offset, self.torque_offset, self.center_of_mass]
        )

    @classmethod
    def from_vector(cls, theta, g: float = STANDARD_GRAVITY) -> "SensorModel":
        """Inverse of :meth:`to_vector`."""
        theta = as_vector(theta, 12, "theta")
        return cls(theta[3:6], theta[6:9], theta[0:3], theta[9:12], g)

    def tool_gravity_wrench(self, rotation_sensor_to_base) -> np.ndarray:
        """Tool gravity wrench ``[Gs, P × Gs]`` in the sensor frame [N, N·m].

        Args:
            rotation_sensor_to_base: ``(3, 3)`` or ``(N, 3, 3)`` ``R_BS``.

        Returns:
            ``(6,)`` or ``(N, 6)``.
        """
        rotations, single = as_rotation_batch(rotation_sensor_to_base)
        out = tool_gravity(rotations, self.gravity_in_base, self.center_of_mass)
        return out[0] if single else out

    def predict(self, rotation_sensor_to_base) -> np.ndarray:
        """Reading without contact, ``bias + tool gravity`` [N, N·m]; ``(6,)`` or ``(N, 6)``."""
        rotations, single = as_rotation_batch(rotation_sensor_to_base)
        out = predict(rotations, self.to_vector())
        return out[0] if single else out

    def parameter_jacobian(self, rotation_sensor_to_base) -> np.ndarray:
        """Derivative of :meth:`predict` with respect to ``θ``, ``(N, 6, 12)``."""
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        return parameter_jacobian(rotations, self.gravity_in_base, self.center_of_mass)


# The model on validated arrays: ``rotations`` ``(N, 3, 3)`` ``R_BS``, ``θ = [a, F0, M0, P]``.
# Every estimator, compensator and view calls these (or the fast paths below, tested against them).


def gravity_in_sensor(rotations: np.ndarray, gravity_in_base: np.ndarray) -> np.ndarray:
    """``Gs = R_BSᵀ a`` ``(N, 3)``: a base-frame vector [any unit] in each sensor frame."""
    return np.einsum("nji,j->ni", rotations, gravity_in_base)


def tool_gravity(
    rotations: np.ndarray, gravity_in_base: np.ndarray, center_of_mass: np.ndarray
) -> np.ndarray:
    """``[Gs, P × Gs]`` ``(N, 6)`` [N, N·m]: the tool's weight and its torque about the sensor."""
    weight = gravity_in_sensor(rotations, gravity_in_base)
    return np.concatenate([weight, cross_rows(center_of_mass, weight)], axis=1)


def predict(rotations: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``[F0 + Gs, M0 + P × Gs]`` ``(N, 6)`` [N, N·m]: the reading without contact at ``θ``."""
    return theta[3:9] + tool_gravity(rotations, theta[0:3], theta[9:12])  # [F0, M0] + [Gs, P × Gs]


def parameter_jacobian(
    rotations: np.ndarray, gravity_in_base: np.ndarray, center_of_mass: np.ndarray
) -> np.ndarray:
    """``(N, 6, 12)`` derivative of :func:`predict` with respect to ``θ = [a, F0, M0, P]``.

    Blocks: ``∂F/∂a = Rᵀ``, ``∂F/∂F0 = I``, ``∂M/∂a = [P]× Rᵀ``, ``∂M/∂M0 = I``,
    ``∂M/∂P = −[Gs]×``.
    """
    rotations_t = np.transpose(rotations, (0, 2, 1))
    jac = np.zeros((len(rotations), 6, 12))
    jac[:, 0:3, 0:3] = rotations_t
    jac[:, :, 3:9] = np.eye(6)
    jac[:, 3:6, 0:3] = skew(center_of_mass) @ rotations_t
    jac[:, 3:6, 9:12] = -skew(rotations_t @ gravity_in_base)
    return jac


# Fast paths of ``raw − predict`` (the contact wrench), for the benchmark rows of the control tick
# and the batch compensation. Tests check them against predict to 1e-12 relative.

_BLOCK = 8192
"""Samples per block of :func:`contact_batch` (its temporaries stay below the mmap threshold)."""


class FloatModel:
    """``raw − predict(R_BS)`` for one reading on Python floats: the control tick's fast path.

    The formula of :func:`predict`, written out (numpy's per-call overhead dominates on
    3-vectors)::

        Gs = R_BSᵀ a,   F' = F − F0 − Gs,   M' = M − M0 − P × Gs

    :meth:`set` replaces the parameters; a bound :meth:`contact` held elsewhere sees them.
    """

    __slots__ = ("_bias", "_com", "_gravity")

    def __init__(self, gravity_in_base, center_of_mass, bias):
        self.set(gravity_in_base, center_of_mass, bias)

    def set(self, gravity_in_base, center_of_mass, bias) -> None:
        """Use ``a`` (3,) [N], ``P`` (3,) [m] and the bias ``[F0, M0]`` (6,) [N, N·m]."""
        self._gravity = tuple(np.asarray(gravity_in_base, dtype=float).tolist())
        self._com = tuple(np.asarray(center_of_mass, dtype=float).tolist())
        self._bias = tuple(np.asarray(bias, dtype=float).tolist())

    def contact(self, rotation_rows, raw) -> tuple[float, ...]:
        """``R_BS.tolist()`` and six raw floats [N, N·m] → the six contact floats."""
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation_rows
        ax, ay, az = self._gravity
        px, py, pz = self._com
        b0, b1, b2, b3, b4, b5 = self._bias
        w0, w1, w2, w3, w4, w5 = raw
        gx = r00 * ax + r10 * ay + r20 * az  # Gs = R_BSᵀ a
        gy = r01 * ax + r11 * ay + r21 * az
        gz = r02 * ax + r12 * ay + r22 * az
        return (
            (w0 - b0) - gx,
            (w1 - b1) - gy,
            (w2 - b2) - gz,
            (w3 - b3) - (py * gz - pz * gy),  # M' = M − M0 − P × Gs
            (w4 - b4) - (pz * gx - px * gz),
            (w5 - b5) - (px * gy - py * gx),
        )


def contact_batch(
    raw: np.ndarray, gravity_in_sensor: np.ndarray, center_of_mass, bias: np.ndarray
) -> np.ndarray:
    """``raw − [F0 + Gs, M0 + P × Gs]`` ``(N, 6)``: :func:`predict` subtracted, column by column.

    ``gravity_in_sensor`` is ``Gs`` ``(N, 3)`` [N]; ``bias`` ``(6,)`` or one row per reading
    ``(N, 6)`` [N, N·m]. The ``(N,)`` column operations on blocks run as one vectorised loop each
    (an ``(N, 6)`` operation with a ``(6,)`` operand loops over rows of six).
    """
    out = np.empty_like(raw)
    px, py, pz = np.asarray(center_of_mass, dtype=float).tolist()
    per_sample, gravity = np.ndim(bias) == 2, gravity_in_sensor.T
    for start in range(0, len(out), _BLOCK):
        stop = start + _BLOCK
        block, readings = out[start:stop], raw[start:stop]
        offsets = bias[start:stop].T if per_sample else bias
        for column in range(6):
            np.subtract(readings[:, column], offsets[column], out=block[:, column])
        gx, gy, gz = gravity[:, start:stop]
        block[:, 0] -= gx
        block[:, 1] -= gy
        block[:, 2] -= gz
        block[:, 3] -= py * gz - pz * gy
        block[:, 4] -= pz * gx - px * gz
        block[:, 5] -= px * gy - py * gx
    return out
