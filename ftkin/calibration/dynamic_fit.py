"""The dynamic identification problem and its solvers (used by
:func:`~ftkin.calibration.dynamic.calibrate_dynamic`).

Parameters ``x = [F0 (3), M0 (3), U, V, θ_free]``: the sensor bias [N, N·m], the
base tilt [rad] (gravity ``|g|`` is known, its direction is not) and the free
inertial parameters (all ten of θ, or the four static ones ``[m, m·c]``).
Prediction of one raw reading (:mod:`ftkin.calibration.regressor`)::

    raw = bias − (Y(v, a) + Y_g(R_BSᵀ γ(U, V))) θ

Residuals are whitened per channel by the noise ``σ_c``. Three stages:

1. linear weighted least squares at zero tilt (the regressor is then linear);
2. the unconstrained nonlinear fit over ``[bias, U, V, θ]``, which adds the tilt;
3. the maximum-likelihood fit under physical consistency over
   ``[bias, U, V, φ]`` with φ the log-Cholesky coordinates of θ
   (:mod:`ftkin.calibration.log_cholesky`); stage 2 when only ``[m, m·c]`` is free.
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import UnobservableParameters
from ..kinematics.rotations import gravity_in_base_from_tilt
from .covariance import RCOND, check_determined
from .information import noise_floor
from .log_cholesky import (
    INERTIAL_PARAMETER_NAMES,
    log_cholesky_jacobian,
    parameters_from_log_cholesky,
)
from .model import COMPONENT_NAMES, gravity_in_sensor
from .regressor import gravity_regressor

THETA_NAMES = ("mass", "first_moment[x]", "first_moment[y]", "first_moment[z]") + tuple(
    f"inertia_about_sensor[{name[1:].lower()}]" for name in INERTIAL_PARAMETER_NAMES[4:]
)
"""Names of the ten inertial parameters θ (inertia about the sensor origin)."""

STATIC_INDICES = (0, 1, 2, 3)
ALL_INDICES = tuple(range(10))
MIN_INERTIAL_EXCITATION = 1e-6
"""RMS of an inertia column of the regressor [rad/s²] below which the recording counts as static."""


def upward_gravity(
    g: float, tilt_u: float, tilt_v: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``γ`` (base frame, [m/s²], pointing up) and its derivatives with respect to ``U`` and
    ``V``.
    """
    cu, su, cv, sv = np.cos(tilt_u), np.sin(tilt_u), np.cos(tilt_v), np.sin(tilt_v)
    return (
        -gravity_in_base_from_tilt(g, tilt_u, tilt_v),
        -g * np.array([-su * sv, -cu, su * cv]),
        -g * np.array([cu * cv, 0.0, cu * sv]),
    )


@dataclass(frozen=True)
class DynamicProblem:
    """Whitened least squares of the dynamic calibration, inspectable on its own.

    Attributes:
        wrenches: ``(N, 6)`` raw readings [N, N·m].
        rotations: ``(N, 3, 3)`` ``R_BS``.
        inertial_regressor: ``(N, 6, 10)`` ``Y(v, a)`` (gravity excluded).
        channel_std: ``(6,)`` noise per channel [N, N·m] (the whitening).
        g: Magnitude of gravity [m/s²].
        free: Indices of θ that are estimated (the others are zero).
    """

    wrenches: np.ndarray
    rotations: np.ndarray
    inertial_regressor: np.ndarray
    channel_std: np.ndarray
    g: float
    free: tuple[int, ...] = ALL_INDICES

    @property
    def names(self) -> tuple[str, ...]:
        """Names of ``x = [bias, tilt, θ_free]``."""
        bias_and_tilt = COMPONENT_NAMES[3:9] + ("base_tilt[u]", "base_tilt[v]")
        return bias_and_tilt + tuple(THETA_NAMES[i] for i in self.free)

    def theta(self, theta_free: np.ndarray) -> np.ndarray:
        """The full θ (10,) from its free entries."""
        theta = np.zeros(10)
        theta[list(self.free)] = theta_free
        return theta

    def predict(self, x: np.ndarray) -> np.ndarray:
        """``(N, 6)`` predicted raw readings at ``x`` (θ-space): ``bias − (Y + Y_g) θ``."""
        gamma = upward_gravity(self.g, x[6], x[7])[0]
        weight = gravity_regressor(gravity_in_sensor(self.rotations, gamma))
        return x[:6] - (self.inertial_regressor + weight) @ self.theta(x[8:])

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(N, 6, len(x))`` derivative of :meth:`predict` with respect to ``x`` (θ-space)."""
        theta = self.theta(x[8:])
        gamma, d_u, d_v = upward_gravity(self.g, x[6], x[7])
        out = np.zeros((len(self.wrenches), 6, len(x)))
        out[:, :, :6] = np.eye(6)
        for column, direction in ((6, d_u), (7, d_v)):
            out[:, :, column] = (
                -gravity_regressor(gravity_in_sensor(self.rotations, direction)) @ theta
            )
        weight = gravity_regressor(gravity_in_sensor(self.rotations, gamma))
        out[:, :, 8:] = -(self.inertial_regressor + weight)[:, :, list(self.free)]
        return out

    def whitened_residuals(self, x: np.ndarray, phi: bool = False) -> np.ndarray:
        """``(6N,)`` ``(measured − predicted) / σ`` at ``x`` (θ-space, or φ-space with ``phi``)."""
        return (
            (self.wrenches - self.predict(theta_space(x) if phi else x)) / self.channel_std
        ).ravel()

    def whitened_jacobian(self, x: np.ndarray, phi: bool = False) -> np.ndarray:
        """``(6N, len(x))`` derivative of the whitened prediction ``predict / σ`` (θ-space, or
        φ-space; ftkin's one sign, :mod:`ftkin.calibration.covariance`)."""
        jac = (self.jacobian(theta_space(x) if phi else x) / self.channel_std[:, None]).reshape(
            -1, len(x)
        )
        if phi:
            jac[:, 8:] = jac[:, 8:] @ log_cholesky_jacobian(x[8:])
        return jac


def theta_space(x_phi: np.ndarray) -> np.ndarray:
    """``[bias, U, V, θ]`` of the φ-space ``x = [bias, U, V, φ]`` (all ten θ free)."""
    return np.concatenate([x_phi[:8], parameters_from_log_cholesky(x_phi[8:])])


def check_observability(problem: DynamicProblem) -> None:
    """Refuse a recording that cannot determine the free parameters.

    Raises:
        UnobservableParameters: the recording is static while the inertia is
            free (its columns of the regressor vanish), or the normalized
            information at zero tilt is singular along some parameters
            (:func:`~ftkin.calibration.covariance.check_determined` at ``sqrt(RCOND)``).
    """
    x = np.zeros(8 + len(problem.free))
    x[8] = 1.0  # a unit mass: the tilt and moment columns need weight to act on
    jacobian = problem.whitened_jacobian(x)
    singular = (
        "the regressor is singular along a combination of them (too few distinct orientations "
        "or motions)"
    )
    inertia = [i for i in problem.free if i >= 4]
    if inertia:
        columns = problem.inertial_regressor[:, :, inertia]
        rms = np.sqrt(np.sum(columns**2, axis=(0, 1)) / len(problem.wrenches))
        if np.all(rms < MIN_INERTIAL_EXCITATION):
            # without the inertia the static parameters must be determined, or the advice to
            # calibrate without it would fail too (a recording at one orientation)
            static = [k for k in range(len(x)) if k < 8 or problem.free[k - 8] < 4]
            check_determined(
                jacobian[:, static], [problem.names[k] for k in static], singular, np.sqrt(RCOND)
            )
            raise UnobservableParameters(
                ["inertia_about_com_in_sensor"] + [THETA_NAMES[i] for i in inertia],
                "the recording has no angular velocity or acceleration (static data): the inertia "
                "cannot be identified; record a moving excitation (ftkin plan --excitation) or "
                "calibrate without the inertia (--no-inertia; estimate_inertia=False)",
            )
    check_determined(jacobian, problem.names, singular, np.sqrt(RCOND))


def fit_linear(problem: DynamicProblem) -> np.ndarray:
    """Stage 1: weighted linear least squares at zero tilt; returns ``x`` (θ-space, tilt zero)."""
    x0 = np.zeros(8 + len(problem.free))
    columns = [i for i in range(len(x0)) if i not in (6, 7)]
    target = (problem.wrenches / problem.channel_std).ravel()
    # At fixed tilt the whitened prediction is linear in [bias, θ]: J x.
    x0[columns] = np.linalg.lstsq(problem.whitened_jacobian(x0)[:, columns], target, rcond=None)[0]
    return x0


def fit_nonlinear(problem: DynamicProblem, x0: np.ndarray, phi: bool = False) -> np.ndarray:
    """Stage 2 (``phi`` False) or 3: nonlinear weighted least squares from ``x0``.

    Stage 2 runs over ``[bias, U, V, θ_free]``; stage 3 is the maximum likelihood over
    ``[bias, U, V, φ]`` (all ten θ free) and returns the φ-space ``x``.
    """
    from scipy.optimize import least_squares  # scipy loads where it is used

    return least_squares(
        problem.whitened_residuals,
        x0,
        jac=lambda x, phi: -problem.whitened_jacobian(x, phi),
        args=(phi,),
        method="lm",
        xtol=1e-14,
        ftol=1e-14,
        gtol=1e-14,
        max_nfev=2000 if phi else None,
    ).x


def noise_from_residuals(residuals: np.ndarray, parameter_count: int, wrenches) -> np.ndarray:
    """``(6,)`` noise per reading and channel [N, N·m] of a motion fit's ``residuals`` ``(N, 6)``:
    ``sqrt(Σ e² / (N − n/6))`` (the ``n`` fitted parameters' degrees of freedom shared by the six
    channels), at least :func:`~ftkin.calibration.information.noise_floor` of ``wrenches`` (exact
    data stays finite). The dynamic fits' (joints and IMU)."""
    dof = max(len(residuals) - parameter_count / 6.0, 1.0)
    std = np.sqrt(np.sum(residuals**2, axis=0) / dof)
    return np.maximum(std, noise_floor(wrenches))
