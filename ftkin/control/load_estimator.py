"""The load in the hand, identified recursively from the contact wrench (METHOD.md eq. 23).

A load held below the tool adds its weight to the contact wrench (raw − bias − tool gravity,
sensor frame, :class:`~ftkin.control.compensation.Compensator`). Held still::

    f = m g_s,   τ = c × f = (m c) × g_s,   g_s = R_BSᵀ γ   (γ: gravity in base [m/s²])

linear in ``θ = [m, m c]`` [kg, kg·m]. While the arm moves, the ten inertial parameters
``[m, m c, I]`` (Pinocchio's order, inertia about the sensor origin) enter through the body
regressor of :mod:`ftkin.calibration.regressor` (the tool's own inertial wrench must then be gone
from the contact, e.g. by a :class:`~ftkin.control.dynamic_compensation.DynamicCompensator`)::

    load wrench = −Y(v, a + g_up) θ,   g_up = −g_s

The estimate is kept in information form: each reading adds ``AᵀWA`` and ``AᵀWy`` (``W`` the
inverse variance of one reading per channel), an O(1) update of a few floats for a still reading
(:func:`add_still_floats`, the control tick's path); the solve and the standard errors are on
demand (:meth:`LoadEstimator.estimate`).

What each motion determines:

* held still at one orientation: the mass, and the COM across gravity (``m c`` along ``g_s``
  leaves no moment): the COM component along gravity is undetermined, reported with an infinite
  standard error and the value NaN, never as a number;
* turned about two axes (gravity seen along two directions in the sensor frame): the whole COM;
* moved (angular velocity and acceleration): the inertia (:meth:`LoadEstimator.add_motion`).

Standard errors assume independent readings of the given noise; a window or a reset at each event
is the caller's (:class:`~ftkin.control.load_events.LoadTracker` restarts it at a grasp).
"""

import math
from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.regressor import body_regressor
from ..exceptions import InvalidInput
from ..validation import as_rotation_batch, as_vector, as_wrench

SUM_COUNT = 13
"""Length of the still-reading sums: ``[n, s_mm, S00, S11, S22, S01, S02, S12, b_m, b_c (3),
yᵀWy]`` (``s_mm``, ``b_m`` the mass's information and right side, ``S`` (symmetric) and ``b_c``
those of ``m c``, ``yᵀWy`` for the chi-square)."""

UNDETERMINED_RCOND = 1e-9
"""A direction of the (unit-diagonal) information below this fraction of its largest eigenvalue is
undetermined."""

UNDETERMINED_COMPONENT = 1e-3
"""A COM component is undetermined when an undetermined direction has more than this share of it
(a direction along gravity at one orientation)."""


def empty_sums() -> list[float]:
    """Still-reading sums with nothing in them (:data:`SUM_COUNT` zeros)."""
    return [0.0] * SUM_COUNT


def add_still_floats(sums: list, weights, gravity, wrench) -> None:
    """Add one still reading to ``sums`` (in place, floats only: the tick's path).

    Args:
        sums: :data:`SUM_COUNT` floats (:func:`empty_sums`).
        weights: Six ``1/σ²`` per channel [1/N², 1/(N·m)²].
        gravity: ``g_s`` (3 floats), gravity's acceleration in the sensor frame [m/s²] (down).
        wrench: Six floats, the load's wrench ``y`` [N, N·m] (the contact after the tool).
    """
    w0, w1, w2, w3, w4, w5 = weights
    gx, gy, gz = gravity
    y0, y1, y2, y3, y4, y5 = wrench
    u, v, z = w3 * y3, w4 * y4, w5 * y5  # W τ
    sums[0] += 1.0
    sums[1] += w0 * gx * gx + w1 * gy * gy + w2 * gz * gz
    sums[2] += w4 * gz * gz + w5 * gy * gy  # S = skew(g)ᵀ W skew(g)
    sums[3] += w3 * gz * gz + w5 * gx * gx
    sums[4] += w3 * gy * gy + w4 * gx * gx
    sums[5] -= w5 * gx * gy
    sums[6] -= w4 * gx * gz
    sums[7] -= w3 * gy * gz
    sums[8] += w0 * gx * y0 + w1 * gy * y1 + w2 * gz * y2
    sums[9] += gy * z - gz * v  # b_c = g × (W τ)
    sums[10] += gz * u - gx * z
    sums[11] += gx * v - gy * u
    sums[12] += w0 * y0 * y0 + w1 * y1 * y1 + w2 * y2 * y2 + u * y3 + v * y4 + z * y5


def merge_sums(into: list, other: list) -> None:
    """``into += other`` (two sums of :func:`empty_sums`'s layout)."""
    for i in range(SUM_COUNT):
        into[i] += other[i]


def solve_still_floats(sums: list) -> tuple[float, float, float, float]:
    """``(m, mc_x, mc_y, mc_z)`` [kg, kg·m] of still sums, in floats (the tick's solve).

    The mass is ``b_m / s_mm``; ``m c`` solves ``S (m c) = b_c`` with a ridge of 1e-9 of the trace:
    an undetermined direction (along gravity at one orientation) gets its least-norm value, zero,
    the others are unchanged to 1e-9. Zeros for empty sums.
    """
    s_mm = sums[1]
    mass = sums[8] / s_mm if s_mm > 0.0 else 0.0
    a, d, f, b, c, e = sums[2], sums[3], sums[4], sums[5], sums[6], sums[7]
    ridge = 1e-9 * (a + d + f)
    if not ridge > 0.0:
        return mass, 0.0, 0.0, 0.0
    a, d, f = a + ridge, d + ridge, f + ridge
    # [[a, b, c], [b, d, e], [c, e, f]]⁻¹ by cofactors
    k00, k01, k02 = d * f - e * e, c * e - b * f, b * e - c * d
    k11, k12, k22 = a * f - c * c, b * c - a * e, a * d - b * b
    det = a * k00 + b * k01 + c * k02
    if not (det > 0.0 and math.isfinite(det)):
        return mass, 0.0, 0.0, 0.0
    r0, r1, r2 = sums[9], sums[10], sums[11]
    return (
        mass,
        (k00 * r0 + k01 * r1 + k02 * r2) / det,
        (k01 * r0 + k11 * r1 + k12 * r2) / det,
        (k02 * r0 + k12 * r1 + k22 * r2) / det,
    )


def channel_weights(noise: SensorNoise) -> tuple[float, ...]:
    """Six ``1/σ²`` of one reading's noise per channel."""
    if not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin SensorNoise, got {type(noise).__name__}")
    return tuple((1.0 / noise.channel_std**2).tolist())


@dataclass(frozen=True)
class LoadEstimate:
    """A load's identified mass, centre of mass and (after motion) inertia, with standard errors.

    Attributes:
        mass: [kg].
        mass_std: Its standard error [kg] (inf before any reading).
        com_in_sensor: ``(3,)`` centre of mass in the sensor frame [m]; NaN where undetermined.
        com_std: ``(3,)`` its standard errors [m]; inf where undetermined.
        inertial_parameters: ``(10,)`` ``[m, m c, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]`` about the sensor
            origin, sensor axes [kg, kg·m, kg·m²] when the arm moved (:meth:`LoadEstimator.
            add_motion`), else None.
        inertia_std: ``(6,)`` standard errors of the inertia entries [kg·m²] (inf where
            undetermined) or None.
        reading_count: Readings in the estimate.
        chi_square: Sum of the whitened squared residuals of the fit.
        dof: Its degrees of freedom (6 per reading − determined parameters).
    """

    mass: float
    mass_std: float
    com_in_sensor: np.ndarray
    com_std: np.ndarray
    inertial_parameters: np.ndarray | None
    inertia_std: np.ndarray | None
    reading_count: int
    chi_square: float
    dof: int

    def __post_init__(self):
        for name in ("com_in_sensor", "com_std", "inertial_parameters", "inertia_std"):
            value = getattr(self, name)
            if value is not None:
                value = np.array(value, dtype=float)
                value.setflags(write=False)
                object.__setattr__(self, name, value)

    @property
    def com_determined(self) -> np.ndarray:
        """``(3,)`` bool: which COM components the readings determine."""
        return np.isfinite(self.com_std)

    def weight(self, g: float) -> float:
        """``m g`` [N] (the paper's ``G' = |F'|`` of a load held still)."""
        return self.mass * float(g)

    def summary(self) -> str:
        """One line: mass and COM with their standard errors (undetermined components named)."""
        com = ", ".join(
            f"{axis} {value * 1e3:.2f}±{std * 1e3:.2f} mm" if np.isfinite(std) else f"{axis} ?"
            for axis, value, std in zip("xyz", self.com_in_sensor, self.com_std)
        )
        return (
            f"load {self.mass:.5g}±{self.mass_std:.2g} kg, COM (sensor frame) {com}, "
            f"{self.reading_count} readings, χ²/dof {self.chi_square / max(self.dof, 1):.3g}"
        )


def _information_of(sums: list) -> tuple[np.ndarray, np.ndarray]:
    """``(4, 4)`` information and ``(4,)`` right side of still sums over ``[m, m c]``."""
    s_mm, a, d, f, b, c, e, b_m, r0, r1, r2 = sums[1:12]
    information = np.zeros((4, 4))
    information[0, 0] = s_mm
    information[1:, 1:] = [[a, b, c], [b, d, e], [c, e, f]]
    return information, np.array([b_m, r0, r1, r2])


def solve_information(information: np.ndarray, right: np.ndarray):
    """``(θ, covariance, determined)`` of ``information θ = right`` on the determined subspace.

    Directions whose unit-diagonal eigenvalue is below :data:`UNDETERMINED_RCOND` of the largest
    get θ's least-norm value (zero along them); ``determined`` ``(k,)`` marks parameters with
    less than :data:`UNDETERMINED_COMPONENT` of such a direction, the others get an infinite
    variance.
    """
    scale = np.sqrt(np.clip(np.diag(information), 0.0, None))
    size = len(right)
    theta, covariance = np.zeros(size), np.full((size, size), np.inf)
    if not np.any(scale > 0):
        return theta, covariance, np.zeros(size, dtype=bool)
    scale = np.where(scale > 0, scale, 1.0)
    values, vectors = np.linalg.eigh(information / np.outer(scale, scale))
    kept = values > UNDETERMINED_RCOND * values[-1]
    inverse = (vectors[:, kept] / values[kept]) @ vectors[:, kept].T / np.outer(scale, scale)
    theta = inverse @ right
    lost = vectors[:, ~kept]
    determined = np.sum(lost**2, axis=1) <= UNDETERMINED_COMPONENT**2
    covariance = np.where(np.outer(determined, determined), inverse, np.inf)
    return theta, covariance, determined


def estimate_from(sums: list, motion=None) -> LoadEstimate:
    """The :class:`LoadEstimate` of still sums (and of a motion's ``(information (10, 10), right
    (10,), yᵀWy, readings)``, when the arm moved)."""
    information, right = _information_of(sums)
    count, chi_base = int(sums[0]), sums[12]
    if motion is not None:
        full_information, full_right, motion_chi, motion_count = motion
        full_information = np.array(full_information, dtype=float)
        full_right = np.array(full_right, dtype=float)
        full_information[:4, :4] += information
        full_right[:4] += right
        information, right = full_information, full_right
        count, chi_base = count + motion_count, chi_base + motion_chi
    theta, covariance, determined = solve_information(information, right)
    mass = float(theta[0])
    variance = np.diag(covariance)
    mass_std = math.sqrt(variance[0]) if determined[0] else math.inf
    com, com_std = np.full(3, np.nan), np.full(3, np.inf)
    if determined[0] and mass > 0.0:
        # c = (m c) / m by the delta method: ∂c/∂m = −c/m, ∂c/∂(mc) = I/m
        jacobian = np.zeros((3, len(theta)))
        jacobian[:, 0] = -theta[1:4] / mass**2
        jacobian[:, 1:4] = np.eye(3) / mass
        block = covariance[np.ix_([0, 1, 2, 3], [0, 1, 2, 3])]
        finite = np.where(np.isfinite(block), block, 0.0)
        com_variance = np.diag(jacobian[:, :4] @ finite @ jacobian[:, :4].T)
        for i in range(3):
            if determined[1 + i]:
                com[i] = theta[1 + i] / mass
                com_std[i] = math.sqrt(max(com_variance[i], 0.0))
    chi_square = max(float(chi_base - theta @ right), 0.0)  # yᵀWy − θᵀAᵀWy at the optimum
    inertial, inertia_std = None, None
    if motion is not None:
        inertial = np.where(determined, theta, np.nan)
        inertia_std = np.sqrt(np.where(determined[4:], variance[4:], np.inf))
    return LoadEstimate(
        mass,
        mass_std,
        com,
        com_std,
        inertial,
        inertia_std,
        count,
        chi_square,
        max(6 * count - int(np.count_nonzero(determined)), 0),
    )


class LoadEstimator:
    """Recursive least squares of a load's parameters in information form.

    Args:
        noise: One reading's noise per channel (``W = diag(1/σ²)``), e.g. the calibration's
            (:meth:`~ftkin.control.load_events.LoadTracker.for_calibration` finds it).
        gravity_in_base: Gravity's acceleration in the base frame ``γ`` (3,) [m/s²], pointing
            down (default ``[0, 0, −9.80665]``).
    """

    def __init__(self, noise: SensorNoise, gravity_in_base=(0.0, 0.0, -9.80665)):
        self.weights = channel_weights(noise)
        self.noise = noise
        self.gravity_in_base = as_vector(gravity_in_base, 3, "gravity_in_base [m/s²]")
        if not np.linalg.norm(self.gravity_in_base) > 0:
            raise InvalidInput("gravity_in_base must not be zero (it is the load's acceleration)")
        self.reset()

    def reset(self) -> None:
        """Forget every reading (a new load)."""
        self.sums = empty_sums()
        self._motion = None

    def gravity_in_sensor(self, rotation_sensor_to_base) -> np.ndarray:
        """``g_s = R_BSᵀ γ`` (3,) [m/s²] of one ``R_BS`` ``(3, 3)``."""
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        if len(rotations) != 1:
            raise InvalidInput("takes one (3, 3) rotation R_BS")
        return rotations[0].T @ self.gravity_in_base

    def add_still(self, rotation_sensor_to_base, load_wrench) -> None:
        """Add one reading of the load held still.

        Args:
            rotation_sensor_to_base: ``R_BS`` ``(3, 3)``.
            load_wrench: ``(6,)`` the load's wrench in the sensor frame [N, N·m]: the contact wrench
                after the tool (``Compensator.compensate`` without a load part).
        """
        gravity = self.gravity_in_sensor(rotation_sensor_to_base).tolist()
        add_still_floats(
            self.sums, self.weights, gravity, as_wrench(load_wrench, "load_wrench").tolist()
        )

    def add_motion(self, rotation_sensor_to_base, velocity, acceleration, load_wrench) -> None:
        """Add one reading while the arm moves (the ten parameters, inertia included).

        Args:
            rotation_sensor_to_base: ``R_BS`` ``(3, 3)``.
            velocity: ``(6,)`` the sensor frame's spatial velocity ``[v, ω]`` in its own axes
                [m/s, rad/s] (:func:`~ftkin.calibration.regressor.sensor_motion`).
            acceleration: ``(6,)`` its spatial acceleration ``[a, ω̇]``, gravity excluded [m/s²,
                rad/s²].
            load_wrench: ``(6,)`` the contact wrench after the tool, its inertial wrench included
                (:class:`~ftkin.control.dynamic_compensation.DynamicCompensator`) [N, N·m].
        """
        upward = -self.gravity_in_sensor(rotation_sensor_to_base)
        velocity = as_vector(velocity, 6, "velocity [m/s, rad/s]")
        acceleration = as_vector(acceleration, 6, "acceleration [m/s², rad/s²]").copy()
        acceleration[:3] += upward
        regressor = -body_regressor(velocity, acceleration)[0]  # load wrench = −Y(v, a + g_up) θ
        wrench = as_wrench(load_wrench, "load_wrench")
        weights = np.asarray(self.weights)
        if self._motion is None:
            self._motion = [np.zeros((10, 10)), np.zeros(10), 0.0, 0]
        weighted = regressor.T * weights
        self._motion[0] += weighted @ regressor
        self._motion[1] += weighted @ wrench
        self._motion[2] += float(wrench @ (weights * wrench))
        self._motion[3] += 1

    def estimate(self) -> LoadEstimate:
        """The current :class:`LoadEstimate` (a solve of the accumulated information)."""
        return estimate_from(self.sums, self._motion)
