"""Joint maximum-likelihood calibration, ``method="ml"`` (ftkin's default).

One weighted nonlinear least-squares fit of all six channels of all poses over
``θ = [a, F0, M0, P]``, started from the paper's two-step answer
(:mod:`ftkin.calibration.linear`). The readings of pose ``i`` are averaged first: with
``n_i`` readings of per-reading noise ``σ_c`` on channel ``c``, the mean
``ȳ_i`` has variance ``σ_c² / n_i``, so the whitened residual

    r_ic = sqrt(n_i) · (ȳ_ic − f_c(θ, R_i)) / σ_c

gives exactly the fit on every raw reading (the within-pose scatter is a
constant), at the cost of the number of poses rather than readings.

The noise ``σ`` comes, in this order of preference, from the user
(``noise=``), from the pooled spread of repeated readings per pose, or from the
residuals of the fit (force and torque channels pooled, corrected for the
degrees of freedom the parameters take).
"""

from dataclasses import dataclass, field, replace

import numpy as np

from .information import SensorNoise, covariance_from_information, noise_floor
from .linear import fit_linear
from .model import STANDARD_GRAVITY, SensorModel, parameter_jacobian, predict
from .mount import (
    MOUNT_AXES,
    check_mount_observable,
    mount_jacobian,
    mount_rotation,
    mount_start,
    split_information,
)
from .samples import PoseAverages

LOSSES = ("linear", "soft_l1", "huber")
"""Loss functions of the fit; ``soft_l1`` and ``huber`` down-weight outliers."""

ROBUST_LOSS_SCALE = 1.5
"""Whitened residual [σ] beyond which a robust loss stops growing quadratically."""

MIN_SPREAD_DOF = 5
"""Fewest degrees of freedom (``Σ (n_i − 1)``) for a noise estimate from repeated readings."""

RESIDUAL_NOISE_PASSES = 3
"""Most re-estimations of residual-based noise (each followed by a refit) until it settles to 1
%.
"""

_FORCE, _TORQUE = slice(0, 3), slice(3, 6)

RESIDUAL_NOISE_GROUPS = (_FORCE, _TORQUE)
"""Channels that share one noise level when it is estimated from the residuals:
forces and torques. (Per-channel levels from 12 poses are too noisy as weights:
they cost a quarter of the efficiency in ``benchmarks/bench_estimator.py``.)"""


@dataclass(frozen=True)
class WeightedProblem:
    """The whitened least-squares problem on per-pose means (inspectable on its own).

    The parameters are ``x = [θ (12), δ (k)]``: ``θ = [a, F0, M0, P]`` and, when the mount is
    estimated, its increment ``δ`` (:mod:`ftkin.calibration.mount`; ``k = 0`` for mode
    ``"none"``). A bare 12-vector ``θ`` means ``δ = 0``. The prediction is the model's
    (:func:`~ftkin.calibration.model.predict`) at the real orientations ``R_BS_urdf · R_Mᵀ``.

    Attributes:
        rotations: ``(P, 3, 3)`` sensor orientations ``R_BS`` (the URDF's, with a mount).
        wrenches: ``(P, 6)`` mean raw reading per pose [N, N·m].
        counts: ``(P,)`` readings averaged at each pose.
        channel_std: ``(6,)`` per-reading noise ``σ`` [N, N·m].
        mount_base: ``R_M0`` ``(3, 3)``, the mount at ``δ = 0``.
        mode: ``"none"``, ``"yaw"`` (``k = 1``) or ``"full"`` (``k = 3``).
    """

    rotations: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    channel_std: np.ndarray
    mount_base: np.ndarray = field(default_factory=lambda: np.eye(3))
    mode: str = "none"

    @property
    def parameter_count(self) -> int:
        """``12 + k``."""
        return 12 + MOUNT_AXES[self.mode].shape[1]

    @property
    def weights(self) -> np.ndarray:
        """``(P, 6)`` whitening factors ``sqrt(n_i) / σ_c``."""
        return np.sqrt(self.counts)[:, None] / self.channel_std[None, :]

    def _full(self, x: np.ndarray) -> np.ndarray:
        return np.concatenate([x, np.zeros(self.parameter_count - len(x))])

    def mount(self, x: np.ndarray) -> np.ndarray:
        """``R_M`` at parameters ``x``."""
        return mount_rotation(self.mount_base, self.mode, self._full(x)[12:])

    def residuals(self, x: np.ndarray) -> np.ndarray:
        """``(P, 6)`` measured minus predicted [N, N·m] (unchecked, hot path)."""
        if self.mode == "none":
            return self.wrenches - predict(self.rotations, x)
        return self.wrenches - predict(self.rotations @ self.mount(x).T, x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(P, 6, 12 + k)`` derivative of the prediction (not whitened)."""
        if self.mode == "none":
            return parameter_jacobian(self.rotations, x[0:3], x[9:12])
        x = self._full(x)
        return mount_jacobian(self.rotations, x[0:3], x[9:12], self.mode, self.mount(x), x[12:])

    def whitened_residuals(self, x: np.ndarray) -> np.ndarray:
        """``(6P,)`` residuals in units of their standard deviation."""
        return (self.residuals(x) * self.weights).reshape(-1)

    def whitened_jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(6P, 12 + k)`` derivative of the whitened *prediction* (ftkin's one sign,
        :mod:`ftkin.calibration.covariance`; the residuals' is its negative)."""
        return (self.jacobian(x) * self.weights[:, :, None]).reshape(-1, self.parameter_count)

    def hat_blocks(self, x: np.ndarray) -> np.ndarray:
        """``(P, 6, 6)`` per-pose diagonal blocks of the hat matrix ``J (JᵀJ)⁺ Jᵀ`` of the whitened
        fit (mount columns included).

        Their diagonals are the leverages of the readings' channels.
        """
        jac = self.whitened_jacobian(x)
        blocks = jac.reshape(-1, 6, jac.shape[1])
        # (JᵀJ)⁺ from its eigen-decomposition: numpy's pinv(hermitian=True) (cut at 1e-15 of the
        # largest), without its overhead on a 12 × 12 matrix
        values, vectors = np.linalg.eigh(jac.T @ jac)
        kept = np.abs(values) > 1e-15 * np.abs(values).max()
        inverse = (vectors[:, kept] / values[kept]) @ vectors[:, kept].T
        return blocks @ inverse @ np.transpose(blocks, (0, 2, 1))

    def recentred(self, x: np.ndarray) -> "tuple[WeightedProblem, np.ndarray]":
        """The same problem with ``R_M0`` moved to ``x``'s mount, and ``θ`` (12,)."""
        return replace(self, mount_base=self.mount(x)), np.asarray(x[:12], dtype=float)


@dataclass(frozen=True)
class WhitenedFit:
    """A fit as :func:`~ftkin.calibration.fit_quality.diagnose` assesses it: :class:`MlFit`, or
    :class:`~ftkin.calibration.drift_fit.DriftFit` for a drift model.

    Attributes:
        model: The estimated parameters ``θ``.
        noise: Per-reading noise used [N, N·m].
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        noise_dof: Degrees of freedom of the noise estimate (``inf`` if given).
        information: ``(12, 12)`` Fisher information of ``θ`` (other parameters marginalized).
        whitened: ``(P, 6)`` whitened residuals at the fit, in pose order.
        hat: ``(P, 6, 6)`` per-pose blocks of the hat matrix at the fit, in pose order
            (:meth:`WeightedProblem.hat_blocks`).
        loss: Loss function used.
    """

    model: SensorModel
    noise: SensorNoise
    noise_source: str
    noise_dof: float
    information: np.ndarray
    whitened: np.ndarray
    hat: np.ndarray
    loss: str


@dataclass(frozen=True)
class MlFit(WhitenedFit):
    """What :func:`fit_ml` found (with the attributes of :class:`WhitenedFit`).

    Attributes:
        start: The two-step linear estimate the fit started from.
        problem: The whitened problem at the final noise levels (see :attr:`noise`).
        robust_weights: ``(P, 6)`` final weights of the robust loss (ones for ``"linear"``);
            the :attr:`information` includes them (with a mount, it is the marginal
            information of ``θ``, mount estimated).
        iterations: Function evaluations the solver used.
        mount_rotation: ``R_M`` ``(3, 3)``, URDF sensor frame → real sensor frame
            (identity unless estimated; :mod:`ftkin.calibration.mount`).
        mount_mode: ``"none"``, ``"yaw"`` or ``"full"``.
        mount_covariance: ``(k, k)`` covariance of the mount angles [rad²] about
            the real sensor's axes (``k`` = 1 for yaw, 3 for full), else None.
    """

    start: SensorModel
    problem: WeightedProblem
    robust_weights: np.ndarray
    iterations: int
    mount_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    mount_mode: str = "none"
    mount_covariance: np.ndarray | None = None

    @property
    def covariance(self) -> np.ndarray:
        """``(12, 12)`` covariance of ``θ`` from the noise used (before any goodness-of-fit
        scaling).
        """
        return covariance_from_information(self.information)


def noise_from_spread(poses: PoseAverages) -> tuple[np.ndarray, float] | None:
    """Pooled per-channel spread of repeated readings ``(6,)`` [N, N·m] and its dof, or None.

    None when fewer than :data:`MIN_SPREAD_DOF` repeated readings exist or a
    channel never varies (e.g. readings that were averaged or quantized).
    """
    repeated = poses.counts > 1
    dof = float(np.sum(poses.counts[repeated] - 1))
    if dof < MIN_SPREAD_DOF:
        return None
    std = np.sqrt(
        np.sum((poses.counts[repeated] - 1)[:, None] * poses.spread[repeated] ** 2, axis=0) / dof
    )
    scale = np.maximum(np.abs(poses.wrenches).max(axis=0), 1e-300)
    return (std, dof) if np.all(np.isfinite(std) & (std > 1e-12 * scale)) else None


def noise_from_residuals(
    problem: WeightedProblem, theta: np.ndarray, robust: bool = False, floor=None
) -> tuple[np.ndarray, float]:
    """Per-reading noise ``(6,)`` from the fit residuals, force and torque channels pooled.

    ``σ_g² = Σ n_i e_ic² / Σ (1 − h_ic)`` over the channels of group ``g``
    (``h`` the leverages at the problem's current weights), so the twelve
    fitted parameters do not make the estimate too small. With ``robust`` a
    median-based estimate ignores outlying poses. ``floor`` ``(6,)`` [N, N·m]: the
    lowest value (default :func:`~ftkin.calibration.information.noise_floor`).
    Returns also the smaller group's degrees of freedom.
    """
    leverage = np.clip(np.diagonal(problem.hat_blocks(theta), axis1=1, axis2=2), 0.0, 1.0 - 1e-9)
    scaled = problem.residuals(theta) * np.sqrt(problem.counts)[:, None]
    floor = noise_floor(problem.wrenches) if floor is None else np.asarray(floor, dtype=float)
    dof = 1.0 - leverage
    if robust:
        studentized = np.abs(scaled) / np.sqrt(dof)  # a median that ignores outlying poses
        median = [1.4826 * np.median(studentized[:, g]) for g in RESIDUAL_NOISE_GROUPS]
        std = np.maximum(np.repeat(median, 3), floor)
    else:
        std = pooled_noise(np.sum(scaled**2, axis=0), np.sum(dof, axis=0), floor)
    return std, min(float(np.sum(dof[:, g])) for g in RESIDUAL_NOISE_GROUPS)


def pooled_noise(
    squares: np.ndarray, dof: np.ndarray, floor: np.ndarray, groups=RESIDUAL_NOISE_GROUPS
) -> np.ndarray:
    """``(3 G,)`` noise ``σ_g = √(Σ n e² / Σ dof)`` per group of three channels (``groups``,
    default :data:`RESIDUAL_NOISE_GROUPS`; the IMU's fits add the accelerometer's), from ``Σ n e²``
    and the degrees of freedom per channel, at least ``floor`` [N, N·m, m/s²].
    """
    std = [np.sqrt(np.sum(squares[g]) / max(np.sum(dof[g]), 1e-12)) for g in groups]
    return np.maximum(np.repeat(std, 3), floor)


GAUSS_NEWTON_STEPS = 20
"""Most Gauss–Newton steps :func:`gauss_newton` takes before it leaves the fit to scipy."""

GAUSS_NEWTON_TOLERANCE = 1e-12
"""Relative step (in unit-column scaling) at which :func:`gauss_newton` has converged."""

COST_ROUNDING = 1e-12
"""Relative rise of the cost that :func:`gauss_newton` takes for rounding (at the minimum, the
cost of 12 poses varies by ~1e-14 from step to step); a larger rise is a diverging step."""


def gauss_newton(problem: WeightedProblem, start: np.ndarray) -> tuple[np.ndarray, int] | None:
    """Minimize the whitened residuals (the Gaussian likelihood) from ``start`` by undamped
    Gauss–Newton steps; ``(x, residual evaluations)``, or None (scipy's Levenberg–Marquardt
    then) when a step raises the cost by more than :data:`COST_ROUNDING` (relative) or it has not
    converged within :data:`GAUSS_NEWTON_STEPS`.

    The same minimum as ``least_squares(method="lm")`` without its per-call overhead (the fit of
    12 poses is a few steps from the linear start). Each step solves ``J δ = r`` by least squares
    (its normal equations) with ``J``'s columns at unit norm; converged when ``|δ| ≤``
    :data:`GAUSS_NEWTON_TOLERANCE` ``· |x|`` in that scaling (the steps shrink fast, ~1e-4, 1e-7,
    1e-10, 1e-13 from the linear start), so the minimum is found to rounding; ``least_squares``
    stops up to ~1e-7 (relative) earlier on its ``ftol``.
    """
    x = np.asarray(start, dtype=float)
    residuals = problem.whitened_residuals(x)
    cost, evaluations = float(residuals @ residuals), 1
    for _ in range(GAUSS_NEWTON_STEPS):
        jacobian = problem.whitened_jacobian(x)  # of the prediction: the residuals' is −J
        scale = np.linalg.norm(jacobian, axis=0)
        scale[scale == 0.0] = 1.0
        scaled = jacobian / scale  # unit columns: a normal matrix of condition ≤ 1e6 here
        try:  # (the observability checks refused poses with a relative singular value < 1e-3)
            scaled_step = np.linalg.solve(scaled.T @ scaled, scaled.T @ residuals)
        except np.linalg.LinAlgError:  # singular: scipy decides
            return None
        x_new = x + scaled_step / scale
        residuals_new = problem.whitened_residuals(x_new)
        cost_new, evaluations = float(residuals_new @ residuals_new), evaluations + 1
        small = np.linalg.norm(scaled_step) <= GAUSS_NEWTON_TOLERANCE * np.linalg.norm(x * scale)
        if not cost_new <= cost * (1.0 + COST_ROUNDING):  # diverging, or NaN: scipy decides
            return None
        if small:
            return (x_new, evaluations) if cost_new <= cost else (x, evaluations)
        x, residuals, cost = x_new, residuals_new, cost_new
    return None


def _solve(problem: WeightedProblem, start: np.ndarray, loss: str) -> tuple[np.ndarray, int]:
    """Minimize the (robust) whitened residuals from ``start``; ``θ`` and the function evaluations
    used: :func:`gauss_newton` for the Gaussian likelihood, scipy's ``least_squares`` for a
    robust loss or when Gauss–Newton does not converge.
    """
    if loss == "linear":
        solved = gauss_newton(problem, start)
        if solved is not None:
            return solved
    from scipy.optimize import (
        least_squares,
    )  # here, not at import: scipy.optimize takes ~0.3 s to import

    robust = (
        {"method": "lm"}
        if loss == "linear"
        else {"method": "trf", "loss": loss, "f_scale": ROBUST_LOSS_SCALE}
    )
    solution = least_squares(
        problem.whitened_residuals,
        start,
        jac=lambda theta: -problem.whitened_jacobian(theta),
        x_scale="jac",
        xtol=1e-13,
        ftol=1e-13,
        gtol=1e-13,
        **robust,
    )
    return solution.x, int(solution.nfev)


def _noise(poses: PoseAverages, problem, theta0, noise, loss: str, floor):
    """``(channel_std (6,), dof, source)``: the noise given, else from the spread of repeated
    readings, else from the residuals at the start ``theta0`` (refined after the fit).
    """
    if noise is not None:
        return noise.channel_std, np.inf, "given"
    spread = noise_from_spread(poses)
    if spread is not None:
        return (*spread, "spread")
    # rough levels (no leverage correction) to weight the channels for the leverages
    rms = np.sqrt(np.mean(problem.residuals(theta0) ** 2 * problem.counts[:, None], axis=0))
    rough = np.maximum(
        np.repeat([rms[_FORCE].mean(), rms[_TORQUE].mean()], 3),
        1e-12 * np.maximum(1.0, np.abs(poses.wrenches).max(axis=0)),
    )
    problem = replace(problem, channel_std=rough)
    return (*noise_from_residuals(problem, theta0, loss != "linear", floor), "residuals")


def fit_ml(
    poses: PoseAverages,
    g: float = STANDARD_GRAVITY,
    noise: SensorNoise | None = None,
    loss: str = "linear",
    estimate_mount: str = "none",
    floor=None,
    start: SensorModel | None = None,
) -> MlFit:
    """Maximum-likelihood fit of all channels on per-pose mean readings.

    Args:
        poses: Readings averaged per pose (with counts and spread).
        g: Gravity for the reported mass [m/s²].
        noise: Per-reading noise; None estimates it (spread, else residuals).
        loss: One of :data:`LOSSES`.
        estimate_mount: ``"none"``, ``"yaw"`` or ``"full"``: also fit the mount
            ``R_M`` (``poses.rotations`` are then the URDF's ``R_BS``).
        floor: ``(6,)`` lowest noise a residual estimate may take [N, N·m] (default:
            :func:`~ftkin.calibration.information.noise_floor`).
        start: ``estimate_mount="none"`` only: the two-step linear fit of these ``poses`` and
            ``g`` when it is at hand (``ConventionCheck.linear_fit``,
            :mod:`ftkin.calibration.conventions`); None fits it.

    The options are :class:`~ftkin.calibration.fit_options.CalibrationOptions`' (checked there).

    Raises:
        UnobservableParameters: the poses cannot determine the parameters (or the mount).
    """
    if estimate_mount == "none":
        mount0, start = np.eye(3), fit_linear(poses, g) if start is None else start
    else:
        mount0, start = mount_start(poses, g)
    problem = WeightedProblem(
        poses.rotations,
        poses.wrenches,
        np.asarray(poses.counts, dtype=float),
        np.ones(6),
        mount0,
        estimate_mount,
    )
    theta0 = np.concatenate([start.to_vector(), np.zeros(problem.parameter_count - 12)])
    channel_std, dof, source = _noise(poses, problem, theta0, noise, loss, floor)
    problem = replace(problem, channel_std=channel_std)
    if estimate_mount != "none":
        check_mount_observable(problem, theta0)
    theta, evaluations = _solve(problem, theta0, loss)
    for _ in range(RESIDUAL_NOISE_PASSES if source == "residuals" else 0):
        channel_std, dof = noise_from_residuals(problem, theta, loss != "linear", floor)
        converged = np.allclose(channel_std, problem.channel_std, rtol=1e-2, atol=0.0)
        problem = replace(problem, channel_std=channel_std)
        if converged:
            break
        theta, more = _solve(problem, theta, loss)
        evaluations += more
    problem, theta = problem.recentred(theta)
    # θ's information at the solution, robust weights included (marginal with a mount)
    whitened = problem.whitened_residuals(theta).reshape(-1, 6)
    # IRLS weights ρ'(z) of scipy's losses at z = (r / scale)²: soft_l1, huber, or ones (linear)
    z = (whitened / ROBUST_LOSS_SCALE) ** 2
    robust_weights = 1.0 / np.sqrt(1.0 + z if loss == "soft_l1" else np.maximum(z, 1.0))
    if loss == "linear":
        robust_weights = np.ones_like(whitened)
    jac = problem.whitened_jacobian(theta) * np.sqrt(robust_weights).reshape(-1, 1)
    information, mount_covariance = jac.T @ jac, None
    if estimate_mount != "none":
        information, mount_covariance = split_information(information)
    return MlFit(
        model=SensorModel.from_vector(theta, g),
        start=start,
        problem=problem,
        noise=SensorNoise(problem.channel_std[_FORCE], problem.channel_std[_TORQUE]),
        noise_source=source,
        noise_dof=float(dof),
        loss=loss,
        robust_weights=robust_weights,
        information=information,
        iterations=evaluations,
        whitened=whitened,
        hat=problem.hat_blocks(theta),
        mount_rotation=problem.mount_base,
        mount_mode=estimate_mount,
        mount_covariance=mount_covariance,
    )
