"""Cartesian admittance control (METHOD.md §5): force error in, velocity out.

Sign convention. ftkin's compensated wrench ``F'`` is what the environment
exerts on the tool. The wrench the tool *applies* to the environment is
``-F'``, and that is the wrench METHOD.md's error refers to, so that positive
gains make the tool yield::

    ΔF = F_desired − (−F') = F_desired + F'

* position form ``ΔX = S·K1·ΔF``  (:meth:`Admittance.displacement`) [m, rad];
* velocity form ``ΔV = S·K2·ΔF``  (:meth:`Admittance.velocity`) [m/s, rad/s];
* combined ``ΔV = S·(K1·dΔF/dt + K2·ΔF)`` (:meth:`Admittance.update`), with
  the derivative low-pass filtered (first order, cutoff ``f_c`` [Hz],
  discretised exactly: ``α = 1 − exp(−2π f_c dt)``) and ``ΔV`` saturated
  (linear norm [m/s], angular norm [rad/s]; each part on its own, or the whole
  twist by one factor, which keeps its screw axis and pitch).

K1 has a stability limit on a stiff contact (the derivative of the contact's
damping force feeds back through a delay):
:func:`~ftkin.control.stability.max_stable_k1` computes it.

With ``F_desired = 0`` a held weight ``W`` gives ``ΔF = W`` along gravity and
the tool moves down at ``K2·W`` until a surface carries the weight.

K1 [m/N, rad/(N·m)] and K2 [m/(s·N), rad/(s·N·m)] are diagonal (6-vectors),
S is a 0/1 diagonal: 0 keeps that axis still. A deadband shrinks each force
(torque) error component towards zero by ``force_deadband`` [N]
(``torque_deadband`` [N·m]), continuously. ``frame`` names the axes (and the
point) in which ``ΔF`` and ``ΔV`` are expressed;
:class:`~ftkin.control.control_frame.ControlFrame` (importable from here too) does the
rotations and the lever arm.
"""

import math

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_vector, check_finite
from .control_frame import FRAMES, ControlFrame  # noqa: F401  (ControlFrame importable from here, as before)
from .stability import derivative_alpha

__all__ = ["FRAMES", "Admittance", "AdmittanceState"]


def _diagonal(value, name: str, nonnegative: bool = True) -> np.ndarray:
    """A 6-vector from a scalar, a 6-vector or a 6×6 diagonal matrix."""
    array = as_float_array(value, name)
    if array.shape == ():
        array = np.full(6, float(array))
    elif array.shape == (6, 6):
        if np.any(array - np.diag(np.diag(array))):
            raise InvalidInput(
                f"{name} must be diagonal; got off-diagonal entries in a (6, 6) matrix"
            )
        array = np.diag(array).copy()
    elif array.shape != (6,):
        raise InvalidInput(
            f"{name} must be a scalar, a 6-vector or a (6, 6) diagonal matrix, got shape "
            f"{array.shape}"
        )
    check_finite(array, name)
    if nonnegative and np.any(array < 0):
        raise InvalidInput(
            f"{name} must be non-negative (a negative gain pushes into the contact), got {array}"
        )
    return array.astype(np.float64, copy=True)


class AdmittanceState:
    """The filter memory of an :class:`Admittance` (explicit, resettable).

    Kept as Python floats (the control tick's path: ``errors``, ``derivatives``);
    :attr:`previous_error` and :attr:`filtered_derivative` read and write them as
    ``(6,)`` arrays (a read returns a new array).

    Attributes:
        started: False until the first update after a reset.
    """

    __slots__ = ("errors", "derivatives", "started")

    def __init__(self, previous_error=None, filtered_derivative=None, started: bool = False):
        self.errors = [0.0] * 6 if previous_error is None else _six_floats(previous_error)
        self.derivatives = (
            [0.0] * 6 if filtered_derivative is None else _six_floats(filtered_derivative)
        )
        self.started = bool(started)

    @property
    def previous_error(self) -> np.ndarray:
        """ΔF at the previous update ``(6,)`` [N, N·m]."""
        return np.array(self.errors)

    @previous_error.setter
    def previous_error(self, value) -> None:
        self.errors = _six_floats(value)

    @property
    def filtered_derivative(self) -> np.ndarray:
        """Low-passed dΔF/dt ``(6,)`` [N/s, N·m/s]."""
        return np.array(self.derivatives)

    @filtered_derivative.setter
    def filtered_derivative(self, value) -> None:
        self.derivatives = _six_floats(value)

    def __repr__(self) -> str:
        return (
            f"AdmittanceState(previous_error={self.errors}, "
            f"filtered_derivative={self.derivatives}, started={self.started})"
        )


def _six_floats(value) -> list[float]:
    return as_vector(value, 6, "admittance state").tolist()


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
        saturation: ``"separate"`` scales the linear and the angular part each to
            its limit (the direction of each is kept, their ratio is not);
            ``"common"`` scales the whole twist by the one factor that brings both
            within their limits (the screw axis and pitch ``ω·v/|ω|²`` are kept).
        bumpless: If True the first update after a reset takes its error as the
            previous one (no derivative kick). If False the filter starts from
            ΔF = 0, so a force present at switch-on moves the tool by the
            position form's ``K1·ΔF`` (a weight taken up while the loop runs).
    """

    def __init__(
        self,
        k1=0.0,
        k2=0.0,
        *,
        selection=1.0,
        desired_wrench=0.0,
        frame: str = "sensor",
        force_deadband: float = 0.0,
        torque_deadband: float = 0.0,
        derivative_cutoff: float = 10.0,
        max_linear_velocity: float = 0.05,
        max_angular_velocity: float = 0.5,
        bumpless: bool = True,
        saturation: str = "separate",
    ):
        self.k1, self.k2 = _diagonal(k1, "k1"), _diagonal(k2, "k2")
        self.selection = _diagonal(selection, "selection")
        if np.any((self.selection != 0.0) & (self.selection != 1.0)):
            raise InvalidInput(f"selection must hold 0 or 1 per axis, got {self.selection}")
        self.desired_wrench = _diagonal(desired_wrench, "desired_wrench", nonnegative=False)
        if frame not in FRAMES:
            raise InvalidInput(f"frame must be one of {FRAMES}, got {frame!r}")
        self.frame = frame
        limits = dict(
            force_deadband=force_deadband,
            torque_deadband=torque_deadband,
            derivative_cutoff=derivative_cutoff,
            max_linear_velocity=max_linear_velocity,
            max_angular_velocity=max_angular_velocity,
        )
        values = as_vector(list(limits.values()), 5, "deadbands, cutoff and velocity limits")
        if np.any(values[:2] < 0) or np.any(values[2:] <= 0):
            raise InvalidInput(
                "deadbands must be >= 0; derivative_cutoff and velocity limits must be > 0, "
                f"got {dict(zip(limits, values.tolist()))}"
            )
        self.deadband = np.repeat(values[:2], 3)
        self.derivative_cutoff, self.max_linear_velocity, self.max_angular_velocity = values[
            2:
        ].tolist()
        self.bumpless = bool(bumpless)
        if saturation not in ("separate", "common"):
            raise InvalidInput(f"saturation must be 'separate' or 'common', got {saturation!r}")
        self.common_saturation = saturation == "common"
        self._alpha_dt, self._alpha = math.nan, 0.0
        self._k1s, self._k2s = self.selection * self.k1, self.selection * self.k2
        self._k1s_floats, self._k2s_floats = self._k1s.tolist(), self._k2s.tolist()
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
            contact_wrench: ``F'`` ``(6,)`` in ``frame`` [N, N·m] (environment on the tool).
            dt: Time since the previous update [s], finite and > 0.
        """
        wrench = as_vector(contact_wrench, 6, "contact_wrench")
        if not (
            isinstance(dt, (int, float, np.floating, np.integer)) and math.isfinite(dt) and dt > 0
        ):
            raise InvalidInput(f"dt must be a finite time > 0 [s], got {dt!r}")
        return np.array(self.update_floats(wrench.tolist(), float(dt)))

    def update_floats(self, contact_wrench, dt: float) -> tuple[float, ...]:
        """:meth:`update` on six Python floats, returning six floats (the control tick's path).

        Every update, from :meth:`update` or from ``JointAdmittance.step``, runs
        here, so a per-tick feature of the law belongs in this method. The
        operations are those of the array form, component by component (same
        IEEE results), on floats because numpy's per-call overhead dominates
        on 6-vectors.
        """
        state = self.state
        bumpless_start = (
            not state.started and self.bumpless
        )  # the first error is its own previous one: no kick
        state.started = True
        if dt != self._alpha_dt:  # exact discretisation of the first-order low-pass, cached per dt
            self._alpha_dt, self._alpha = dt, derivative_alpha(dt, self.derivative_cutoff)
        alpha = self._alpha
        # Axis by axis, written out (a loop over zipped lists costs more than the arithmetic): ΔF =
        # F_desired + F'
        # with the deadband (e − clip(e, ±band), as branches), the filtered dΔF/dt, then
        # S·(K1·dΔF/dt + K2·ΔF).
        d0, d1, d2, d3, d4, d5 = self.desired_wrench.tolist()
        c0, c1, c2, c3, c4, c5 = contact_wrench
        b0, b1, b2, b3, b4, b5 = self.deadband.tolist()
        e0, e1, e2, e3, e4, e5 = d0 + c0, d1 + c1, d2 + c2, d3 + c3, d4 + c4, d5 + c5
        e0 = e0 - b0 if e0 > b0 else (e0 + b0 if e0 < -b0 else 0.0)
        e1 = e1 - b1 if e1 > b1 else (e1 + b1 if e1 < -b1 else 0.0)
        e2 = e2 - b2 if e2 > b2 else (e2 + b2 if e2 < -b2 else 0.0)
        e3 = e3 - b3 if e3 > b3 else (e3 + b3 if e3 < -b3 else 0.0)
        e4 = e4 - b4 if e4 > b4 else (e4 + b4 if e4 < -b4 else 0.0)
        e5 = e5 - b5 if e5 > b5 else (e5 + b5 if e5 < -b5 else 0.0)
        p0, p1, p2, p3, p4, p5 = (e0, e1, e2, e3, e4, e5) if bumpless_start else state.errors
        g0, g1, g2, g3, g4, g5 = state.derivatives
        g0 = g0 + alpha * ((e0 - p0) / dt - g0)
        g1 = g1 + alpha * ((e1 - p1) / dt - g1)
        g2 = g2 + alpha * ((e2 - p2) / dt - g2)
        g3 = g3 + alpha * ((e3 - p3) / dt - g3)
        g4 = g4 + alpha * ((e4 - p4) / dt - g4)
        g5 = g5 + alpha * ((e5 - p5) / dt - g5)
        state.errors, state.derivatives = [e0, e1, e2, e3, e4, e5], [g0, g1, g2, g3, g4, g5]
        k0, k1, k2, k3, k4, k5 = self._k1s_floats
        h0, h1, h2, h3, h4, h5 = self._k2s_floats
        return self.saturate_floats(
            (
                k0 * g0 + h0 * e0,
                k1 * g1 + h1 * e1,
                k2 * g2 + h2 * e2,
                k3 * g3 + h3 * e3,
                k4 * g4 + h4 * e4,
                k5 * g5 + h5 * e5,
            )
        )

    def saturate_floats(self, twist):
        """:meth:`saturate` on six floats: returns ``twist`` itself when within the limits, else six
        new floats.
        """
        v0, v1, v2, w0, w1, w2 = twist
        linear = math.sqrt(v0 * v0 + v1 * v1 + v2 * v2)
        angular = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
        if linear <= self.max_linear_velocity and angular <= self.max_angular_velocity:
            return twist
        if self.common_saturation:  # one factor for both parts: the screw (pitch, axis) is kept
            scale = min(
                self.max_linear_velocity / max(linear, self.max_linear_velocity),
                self.max_angular_velocity / max(angular, self.max_angular_velocity),
            )
            return v0 * scale, v1 * scale, v2 * scale, w0 * scale, w1 * scale, w2 * scale
        if linear > self.max_linear_velocity:
            scale = self.max_linear_velocity / linear
            v0, v1, v2 = v0 * scale, v1 * scale, v2 * scale
        if angular > self.max_angular_velocity:
            scale = self.max_angular_velocity / angular
            w0, w1, w2 = w0 * scale, w1 * scale, w2 * scale
        return v0, v1, v2, w0, w1, w2

    def saturate(self, twist: np.ndarray) -> np.ndarray:
        """Scale a twist to the norm limits: each part on its own, or all by one factor
        (``saturation="common"``).
        """
        values = twist.tolist()
        limited = self.saturate_floats(values)
        return twist if limited is values else np.array(limited)
