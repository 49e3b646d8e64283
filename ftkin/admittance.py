"""Cartesian admittance control (METHOD.md §5): force error in, velocity out.

Sign convention. ftkin's compensated wrench ``F'`` is what the environment
exerts on the tool. The wrench the tool *applies* to the environment is
``-F'``, and that is the wrench METHOD.md's error refers to, so that positive
gains make the tool yield::

    ΔF = F_desired − (−F') = F_desired + F'

* position form ``ΔX = S·K1·ΔF``  (:meth:`Admittance.displacement`) [m, rad];
* velocity form ``ΔV = S·K2·ΔF``  (:meth:`Admittance.velocity`) [m/s, rad/s];
* combined ``ΔV = S·(K1·dΔF/dt + K2·ΔF)`` (:meth:`Admittance.update`), with
  the derivative low-pass filtered (first order, cutoff [Hz]) and ``ΔV``
  saturated (linear norm [m/s], angular norm [rad/s]).

With ``F_desired = 0`` a held weight ``W`` gives ``ΔF = W`` along gravity and
the tool moves down at ``K2·W`` until a surface carries the weight.

K1 [m/N, rad/(N·m)] and K2 [m/(s·N), rad/(s·N·m)] are diagonal (6-vectors),
S is a 0/1 diagonal: 0 keeps that axis still. A deadband shrinks each force
(torque) error component towards zero by ``force_deadband`` [N]
(``torque_deadband`` [N·m]), continuously. ``frame`` names the axes (and the
point) in which ``ΔF`` and ``ΔV`` are expressed; :class:`ControlFrame` does the
rotations and the lever arm.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .exceptions import InvalidInput
from .validation import as_float_array, as_vector, check_finite

FRAMES = ("sensor", "tool", "base")
"""Frames an admittance can work in (see :class:`ControlFrame`)."""


class ControlFrame:
    """Where ``ΔF`` and ``ΔV`` live, and the conversions from/to the sensor.

    * ``"sensor"``: sensor origin, sensor axes;
    * ``"tool"``: the tool point ``r`` (sensor frame) [m], tool axes (``R_ST``, tool to sensor);
    * ``"base"``: the control point ``r``, base axes.

    Wrench transport to the control point: ``M_p = M_s − r × F`` (moment about
    the new point), then a rotation of both parts. Twist transport back to the
    sensor origin for the sensor Jacobian: ``v_s = v_p − ω × r`` (base axes).

    Args:
        frame: One of :data:`FRAMES`.
        point_in_sensor: Control point in the sensor frame [m] (ignored for ``"sensor"``).
        rotation_tool_to_sensor: ``R_ST`` ``(3, 3)``, only used for ``"tool"``.
    """

    def __init__(self, frame: str = "sensor", point_in_sensor=(0.0, 0.0, 0.0), rotation_tool_to_sensor=None):
        if frame not in FRAMES:
            raise InvalidInput(f"frame must be one of {FRAMES}, got {frame!r}")
        self.frame = frame
        point = as_vector(point_in_sensor, 3, "control point in the sensor frame")
        self.point_in_sensor = np.zeros(3) if frame == "sensor" else point
        rotation = np.eye(3) if rotation_tool_to_sensor is None else as_float_array(rotation_tool_to_sensor, "R_ST")
        if rotation.shape != (3, 3) or not np.allclose(rotation.T @ rotation, np.eye(3), atol=1e-6) or np.linalg.det(rotation) < 0:
            raise InvalidInput(f"rotation_tool_to_sensor must be a (3, 3) rotation matrix, got {rotation!r}")
        self.rotation_tool_to_sensor = rotation if frame == "tool" else np.eye(3)
        self._r = self.point_in_sensor.tolist()
        self._rotation_rows = self.rotation_tool_to_sensor.tolist()
        self._inverse_rows = self.rotation_tool_to_sensor.T.tolist()

    def wrench_from_sensor(self, wrench_in_sensor: np.ndarray, rotation_sensor_to_base: np.ndarray) -> np.ndarray:
        """``(6,)`` wrench at the control point in this frame's axes, from the sensor's ``(6,)``."""
        fx, fy, fz, mx, my, mz = wrench_in_sensor.tolist()
        rx, ry, rz = self._r
        mx, my, mz = mx - (ry * fz - rz * fy), my - (rz * fx - rx * fz), mz - (rx * fy - ry * fx)
        if self.frame != "sensor":
            rows = rotation_sensor_to_base.tolist() if self.frame == "base" else self._inverse_rows
            fx, fy, fz = _rotate(rows, fx, fy, fz)
            mx, my, mz = _rotate(rows, mx, my, mz)
        return np.array([fx, fy, fz, mx, my, mz])

    def twist_to_sensor_origin(self, twist: np.ndarray, rotation_sensor_to_base: np.ndarray) -> np.ndarray:
        """Twist ``[v; ω]`` of the sensor origin in base axes, from a control-point twist in this frame's axes."""
        vx, vy, vz, wx, wy, wz = twist.tolist()
        rows = rotation_sensor_to_base.tolist()
        if self.frame != "base":
            if self.frame == "tool":
                vx, vy, vz = _rotate(self._rotation_rows, vx, vy, vz)
                wx, wy, wz = _rotate(self._rotation_rows, wx, wy, wz)
            vx, vy, vz = _rotate(rows, vx, vy, vz)
            wx, wy, wz = _rotate(rows, wx, wy, wz)
        px, py, pz = _rotate(rows, *self._r)
        return np.array([vx - (wy * pz - wz * py), vy - (wz * px - wx * pz), vz - (wx * py - wy * px), wx, wy, wz])


def _rotate(rows, x: float, y: float, z: float) -> tuple[float, float, float]:
    """``R @ (x, y, z)`` on Python floats, ``rows`` = ``R.tolist()``."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rows
    return r00 * x + r01 * y + r02 * z, r10 * x + r11 * y + r12 * z, r20 * x + r21 * y + r22 * z


def _diagonal(value, name: str, nonnegative: bool = True) -> np.ndarray:
    """A 6-vector from a scalar, a 6-vector or a 6×6 diagonal matrix."""
    array = as_float_array(value, name)
    if array.shape == ():
        array = np.full(6, float(array))
    elif array.shape == (6, 6):
        if np.any(array - np.diag(np.diag(array))):
            raise InvalidInput(f"{name} must be diagonal; got off-diagonal entries in a (6, 6) matrix")
        array = np.diag(array).copy()
    elif array.shape != (6,):
        raise InvalidInput(f"{name} must be a scalar, a 6-vector or a (6, 6) diagonal matrix, got shape {array.shape}")
    check_finite(array, name)
    if nonnegative and np.any(array < 0):
        raise InvalidInput(f"{name} must be non-negative (a negative gain pushes into the contact), got {array}")
    return array.astype(np.float64, copy=True)


@dataclass
class AdmittanceState:
    """The filter memory of an :class:`Admittance` (explicit, resettable).

    Attributes:
        previous_error: ΔF at the previous update [N, N·m].
        filtered_derivative: Low-passed dΔF/dt [N/s, N·m/s].
        started: False until the first update after a reset.
    """

    previous_error: np.ndarray = field(default_factory=lambda: np.zeros(6))
    filtered_derivative: np.ndarray = field(default_factory=lambda: np.zeros(6))
    started: bool = False


class Admittance:
    """The admittance law of METHOD.md §5 with its practical safeguards.

    Args:
        k1: Position gain K1 (scalar, 6-vector or 6×6 diagonal) [m/N, rad/(N·m)].
        k2: Velocity gain K2 [m/(s·N), rad/(s·N·m)].
        selection: Diagonal of S (0 or 1 per axis); default all ones.
        desired_wrench: Wrench to apply to the environment [N, N·m], in ``frame``.
        frame: ``"sensor"`` (sensor origin and axes), ``"tool"`` (tool point and
            axes) or ``"base"`` (control point, base axes).
        force_deadband: Force error ignored per component [N].
        torque_deadband: Torque error ignored per component [N·m].
        derivative_cutoff: Cutoff of the derivative's low-pass filter [Hz].
        max_linear_velocity: Saturation of ``|ΔV[:3]|`` [m/s].
        max_angular_velocity: Saturation of ``|ΔV[3:]|`` [rad/s].
        bumpless: If True the first update after a reset takes its error as the
            previous one (no derivative kick). If False the filter starts from
            ΔF = 0, so a force present at switch-on moves the tool by the
            position form's ``K1·ΔF`` (a weight taken up while the loop runs).
    """

    def __init__(self, k1=0.0, k2=0.0, *, selection=1.0, desired_wrench=0.0, frame: str = "sensor",
                 force_deadband: float = 0.0, torque_deadband: float = 0.0, derivative_cutoff: float = 10.0,
                 max_linear_velocity: float = 0.05, max_angular_velocity: float = 0.5, bumpless: bool = True):
        self.k1 = _diagonal(k1, "k1")
        self.k2 = _diagonal(k2, "k2")
        self.selection = _diagonal(selection, "selection")
        if np.any((self.selection != 0.0) & (self.selection != 1.0)):
            raise InvalidInput(f"selection must hold 0 or 1 per axis, got {self.selection}")
        self.desired_wrench = _diagonal(desired_wrench, "desired_wrench", nonnegative=False)
        if frame not in FRAMES:
            raise InvalidInput(f"frame must be one of {FRAMES}, got {frame!r}")
        self.frame = frame
        names = ("force_deadband", "torque_deadband", "derivative_cutoff", "max_linear_velocity", "max_angular_velocity")
        limits = as_vector([force_deadband, torque_deadband, derivative_cutoff, max_linear_velocity, max_angular_velocity],
                           5, "deadbands, cutoff and velocity limits")
        if np.any(limits[:2] < 0) or np.any(limits[2:] <= 0):
            raise InvalidInput("deadbands must be >= 0; derivative_cutoff and velocity limits must be > 0, "
                               f"got {dict(zip(names, limits.tolist()))}")
        self.deadband = np.repeat(limits[:2], 3)
        self.derivative_cutoff = float(limits[2])
        self.max_linear_velocity = float(limits[3])
        self.max_angular_velocity = float(limits[4])
        self.bumpless = bool(bumpless)
        self._time_constant = 1.0 / (2.0 * math.pi * self.derivative_cutoff)
        self._k1s = self.selection * self.k1
        self._k2s = self.selection * self.k2
        self.state = AdmittanceState()

    def reset(self) -> None:
        """Forget the filter memory (call when the loop (re)starts)."""
        self.state = AdmittanceState()

    # ------------------------------------------------------------ the law
    def force_error(self, contact_wrench) -> np.ndarray:
        """``ΔF = F_desired + F'`` with the deadband applied, ``(6,)`` [N, N·m], in ``frame``."""
        error = self.desired_wrench + contact_wrench
        return error - np.minimum(np.maximum(error, -self.deadband), self.deadband)

    def displacement(self, contact_wrench) -> np.ndarray:
        """Position form ``ΔX = S·K1·ΔF`` [m, rad] (stateless)."""
        return self._k1s * self.force_error(np.asarray(contact_wrench, dtype=float))

    def velocity(self, contact_wrench) -> np.ndarray:
        """Velocity form ``ΔV = S·K2·ΔF`` [m/s, rad/s] (stateless, saturated)."""
        return self.saturate(self._k2s * self.force_error(np.asarray(contact_wrench, dtype=float)))

    def update(self, contact_wrench: np.ndarray, dt: float) -> np.ndarray:
        """Combined law ``ΔV = S·(K1·dΔF/dt + K2·ΔF)``, saturated; advances the filter.

        Args:
            contact_wrench: ``F'`` ``(6,)`` float array in ``frame`` [N, N·m]
                (environment on the tool), already validated.
            dt: Time since the previous update [s], > 0.
        """
        state = self.state
        error = self.force_error(contact_wrench)
        if not state.started:
            state.started = True
            if self.bumpless:
                state.previous_error = error
        alpha = dt / (dt + self._time_constant)
        raw_derivative = (error - state.previous_error) / dt
        state.filtered_derivative = state.filtered_derivative + alpha * (raw_derivative - state.filtered_derivative)
        state.previous_error = error
        return self.saturate(self._k1s * state.filtered_derivative + self._k2s * error)

    def saturate(self, twist: np.ndarray) -> np.ndarray:
        """Scale the linear and angular parts of a twist to their norm limits (direction kept)."""
        v0, v1, v2, w0, w1, w2 = twist.tolist()
        linear = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        angular = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if linear <= self.max_linear_velocity and angular <= self.max_angular_velocity:
            return twist
        out = twist.copy()
        if linear > self.max_linear_velocity:
            out[:3] *= self.max_linear_velocity / linear
        if angular > self.max_angular_velocity:
            out[3:] *= self.max_angular_velocity / angular
        return out
