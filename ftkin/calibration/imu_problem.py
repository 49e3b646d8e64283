"""The whitened least squares of the static IMU calibration, and what it can determine.

Per pose ``i`` (readings averaged), with ``u_i`` the unit direction of the specific force in the
IMU frame (two nuisance parameters per pose, tangent increments ``e_i``;
:mod:`ftkin.calibration.imu_model`)::

    a_i = (1 + s) ∘ g u_i + b                 the accelerometer: |(a_i − b) ⊘ (1 + s)| = g
    F_i = F0 − m g R_SI u_i
    M_i = M0 − m c × (g R_SI u_i)

over ``x = [F0, M0, m, c, δ, b, s, e_1..e_P]`` with ``R_SI = R0 Exp(δ)``.
:class:`ImuStaticProblem` gives the residuals and their analytic Jacobian;
:func:`check_observable` refuses a pose set that leaves a direction of the parameters open,
naming them (the accelerometer bias with the offsets it trades against, a scale, ...).
"""

from dataclasses import dataclass, field, replace

import numpy as np

from .covariance import WeakestDirections, weakest_directions
from .imu_model import (
    ACCEL_BIAS_NAMES,
    ACCEL_SCALE_NAMES,
    IMU_ROTATION_NAMES,
    point_mass_parameters,
    predict_imu,
)
from .imu_problem_base import NineChannelProblem
from .model import skew
from .mount import exp_so3, right_jacobian_so3
from .observability import MIN_RELATIVE_SINGULAR_VALUE

WRENCH_NAMES = (
    "force_offset[x]",
    "force_offset[y]",
    "force_offset[z]",
    "torque_offset[x]",
    "torque_offset[y]",
    "torque_offset[z]",
    "tool_mass",
    "center_of_mass[x]",
    "center_of_mass[y]",
    "center_of_mass[z]",
)
"""Names of the wrench model's parameters ``[F0, M0, m, c]``."""

POSES_NEEDED = (
    "the accelerometer must see gravity along every IMU direction for |a − b| = g to fix the "
    "bias (else F0 absorbs m·R_SI·b): add static poses that turn the tool about at least two "
    "different horizontal axes, tilted 45° or more, and upside down if the scale is estimated"
)


def _layout(rotation_free: bool, scale_free: tuple[int, ...]) -> tuple[str, ...]:
    names = WRENCH_NAMES + (IMU_ROTATION_NAMES if rotation_free else ()) + ACCEL_BIAS_NAMES
    return names + tuple(ACCEL_SCALE_NAMES[k] for k in scale_free)


def tangent_bases(directions: np.ndarray) -> np.ndarray:
    """``(P, 3, 2)`` orthonormal bases of the planes perpendicular to unit ``directions``."""
    helper = np.where(np.abs(directions[:, [0]]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    first = np.cross(directions, helper)
    first /= np.linalg.norm(first, axis=1)[:, None]
    return np.stack([first, np.cross(directions, first)], axis=2)


@dataclass(frozen=True)
class ImuStaticProblem(NineChannelProblem):
    """The whitened least squares of the static IMU calibration (inspectable on its own; its
    whitening and residuals are :class:`~ftkin.calibration.imu_problem_base.NineChannelProblem`'s).

    Parameters ``x = [F0, M0, m, c, δ (if free), b, s_free, e (2P)]`` (:attr:`names`).

    Attributes:
        accel: ``(P, 3)`` mean accelerometer reading per pose [m/s²].
        wrenches: ``(P, 6)`` mean raw wrench per pose [N, N·m].
        counts: ``(P,)`` readings per pose.
        noise: ``(9,)`` per-reading noise ``[accel (3) m/s², force (3) N, torque (3) N·m]``.
        g: Magnitude of gravity [m/s²].
        rotation0: ``R0`` ``(3, 3)``: ``R_SI = R0 Exp(δ)`` (δ fixed at zero when not free).
        directions0: ``(P, 3)`` unit directions at ``e = 0``.
        rotation_free: Whether ``δ`` is estimated.
        scale_free: Which scale components are estimated.
        accel_count_factor: Independent accelerometer readings per reading
            (:attr:`~ftkin.calibration.imu_samples.ImuSamples.accel_count_factor`).
    """

    accel: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    noise: np.ndarray
    g: float
    rotation0: np.ndarray
    directions0: np.ndarray
    rotation_free: bool = True
    scale_free: tuple[int, ...] = ()
    accel_count_factor: float = 1.0
    tangents: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        object.__setattr__(self, "tangents", tangent_bases(self.directions0))

    @property
    def names(self) -> tuple[str, ...]:
        """The global parameters' names (the directions follow them)."""
        return _layout(self.rotation_free, self.scale_free)

    @property
    def global_count(self) -> int:
        return len(self.names)

    @property
    def parameter_count(self) -> int:
        return self.global_count + 2 * len(self.accel)

    def unpack(self, x: np.ndarray) -> dict:
        """The parameters of ``x`` by name: ``F0, M0, m, c, delta, b, s, e``."""
        i = 10
        delta = np.zeros(3)
        if self.rotation_free:
            delta, i = x[i : i + 3], i + 3
        bias, i = x[i : i + 3], i + 3
        scale = np.zeros(3)
        scale[list(self.scale_free)] = x[i : i + len(self.scale_free)]
        i += len(self.scale_free)
        return {
            "F0": x[0:3],
            "M0": x[3:6],
            "m": float(x[6]),
            "c": x[7:10],
            "delta": delta,
            "b": bias,
            "s": scale,
            "e": x[i:].reshape(-1, 2),
        }

    def rotation(self, x: np.ndarray) -> np.ndarray:
        """``R_SI`` at ``x``."""
        return self.rotation0 @ exp_so3(self.unpack(x)["delta"])

    def directions(self, e: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Unit directions ``(P, 3)`` at tangent increments ``e`` ``(P, 2)``, and the norms of
        ``u0 + T e`` before normalising.
        """
        raw = self.directions0 + np.einsum("pij,pj->pi", self.tangents, e)
        norms = np.linalg.norm(raw, axis=1)
        return raw / norms[:, None], norms

    def predict(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` predicted ``[a, F, M]`` per pose."""
        p = self.unpack(x)
        units, _ = self.directions(p["e"])
        force = self.g * units @ self.rotation(x).T  # f_S = g R_SI u
        accel = (1.0 + p["s"]) * self.g * units + p["b"]
        wrench = predict_imu(
            np.concatenate([p["F0"], p["M0"]]), point_mass_parameters(p["m"], p["c"]), force
        )
        return np.concatenate([accel, wrench], axis=1)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9, n)`` derivative of :meth:`predict` with respect to ``x``."""
        p = self.unpack(x)
        count, g = len(self.accel), self.g
        units, norms = self.directions(p["e"])
        rotation = self.rotation(x)
        force = g * units @ rotation.T  # v = g R u (P, 3)
        projector = np.eye(3) - units[:, :, None] * units[:, None, :]
        d_units = projector @ self.tangents / norms[:, None, None]  # (P, 3, 2)
        d_force_e = g * rotation @ d_units  # (P, 3, 2)
        mass, com = p["m"], p["c"]
        com_skew = skew(com)
        jac = np.zeros((count, 9, self.parameter_count))
        jac[:, 3:9, 0:6] = np.eye(6)  # F0, M0
        jac[:, 3:6, 6] = -force  # ∂F/∂m
        jac[:, 6:9, 6] = -np.cross(com, force)  # ∂M/∂m
        jac[:, 6:9, 7:10] = mass * skew(force)  # ∂M/∂c
        i = 10
        if self.rotation_free:
            d_force_delta = -g * rotation @ skew(units) @ right_jacobian_so3(p["delta"])
            jac[:, 3:6, i : i + 3] = -mass * d_force_delta
            jac[:, 6:9, i : i + 3] = -mass * com_skew @ d_force_delta
            i += 3
        jac[:, 0:3, i : i + 3] = np.eye(3)  # ∂a/∂b
        i += 3
        for k in self.scale_free:
            jac[:, k, i] = g * units[:, k]
            i += 1
        rows = np.arange(count)
        for j in range(2):
            column = i + 2 * rows + j
            jac[rows, 0:3, column] = (1.0 + p["s"]) * g * d_units[:, :, j]
            jac[rows, 3:6, column] = -mass * d_force_e[:, :, j]
            jac[rows, 6:9, column] = -mass * (com_skew @ d_force_e[:, :, j].T).T
        return jac

    def recentred(self, x: np.ndarray) -> "tuple[ImuStaticProblem, np.ndarray]":
        """The same problem with ``R0`` and the directions moved to ``x`` (``δ = 0``, ``e = 0``)."""
        p = self.unpack(x)
        units, _ = self.directions(p["e"])
        problem = replace(self, rotation0=self.rotation(x), directions0=units)
        out = np.array(x, dtype=float)
        if self.rotation_free:
            out[10:13] = 0.0
        out[self.global_count :] = 0.0
        return problem, out


def weakest_direction(problem: NineChannelProblem, x: np.ndarray) -> WeakestDirections:
    """The spectrum of the column-normalised whitened Jacobian and the global parameters its open
    directions (below :data:`~ftkin.calibration.observability.MIN_RELATIVE_SINGULAR_VALUE`, else
    the weakest) involve (:func:`~ftkin.calibration.covariance.weakest_directions`)."""
    return weakest_directions(
        problem.whitened_jacobian(x),
        problem.names,
        MIN_RELATIVE_SINGULAR_VALUE,
        named=problem.global_count,
    )


def check_observable(problem: ImuStaticProblem, x: np.ndarray) -> None:
    """Refuse a pose set that leaves a parameter open (see the module docstring).

    Raises:
        UnobservableParameters: naming the parameters of the weakest direction (the accelerometer
            bias with the offsets it trades against, a scale, the rotation, ...).
    """
    directions = weakest_direction(problem, x)
    if directions.relative >= MIN_RELATIVE_SINGULAR_VALUE:
        return
    raise directions.error(
        f"{POSES_NEEDED} (smallest relative singular value {directions.relative:.1e}, need at "
        f"least {MIN_RELATIVE_SINGULAR_VALUE:.0e})"
    )
