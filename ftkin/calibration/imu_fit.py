"""Static calibration from the sensor's IMU: ``F0``, ``M0``, mass, COM, ``R_SI``, accelerometer
bias and scale, from readings at static poses with no orientation at all.

Per pose ``i`` (readings averaged), with ``u_i`` the unit direction of the specific force in the
IMU frame (two nuisance parameters per pose; :mod:`ftkin.calibration.imu_model`)::

    a_i = (1 + s) ∘ g u_i + b                 the accelerometer: |(a_i − b) ⊘ (1 + s)| = g
    F_i = F0 − m g R_SI u_i
    M_i = M0 − m c × (g R_SI u_i)

Why the sphere: the wrench alone sees ``F0 − m R_SI (a − b)``, in which ``F0`` absorbs
``m R_SI b`` (and ``M0`` absorbs ``m c × R_SI b``). Only the accelerometer's own constraint, a
norm of ``g`` at every static pose, separates the bias from the sensor's offsets; the poses must
turn gravity into every direction of the IMU for it to do so. :func:`check_observable` refuses a
pose set that leaves a direction open, naming the parameters
(:mod:`ftkin.calibration.imu_problem`).

The fit (:func:`fit_imu_static`) is the joint maximum likelihood of all nine channels
(accelerometer, force, torque) over ``x = [F0, M0, m, c, δ, b, s, e_1..e_P]`` (``R_SI = R0
Exp(δ)``, ``e_i`` the directions' tangent increments), started from a closed form: a sphere fit of
the accelerometer gives ``b`` (and an isotropic ``s``), the Kabsch
rotation of the centred forces against the corrected directions gives ``R_SI`` and ``m``, and
linear least squares of the torques gives ``M0`` and ``c``. Standard errors come from the
Gauss–Newton covariance, as in the ``ml`` fit.
"""

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput, UnobservableParameters
from .covariance import covariance_in_sensor_axes, invert_information
from .fit_options import CalibrationOptions
from .goodness_of_fit import ACCEL_CHANNELS, WRENCH_CHANNELS, FitTest, fit_test
from .imu_model import (
    ACCEL_SCALE_NAMES,
    corrected_specific_force,
    point_mass_parameters,
    predict_imu,
)
from .imu_options import ImuCalibrationOptions
from .imu_problem import POSES_NEEDED, ImuStaticProblem, check_observable, weakest_direction
from .imu_problem_base import NineChannelProblem
from .imu_result import ImuCalibrationResult
from .imu_samples import ImuPoseAverages, ImuSamples
from .imu_start import start
from .information import noise_floor
from .ml import pooled_noise
from .observability import MIN_RELATIVE_SINGULAR_VALUE

logger = logging.getLogger(__name__)

MIN_IMU_POSES = 4
"""Fewest static poses: the sphere ``|a − b| = g`` needs four directions not in one plane."""

MIN_SCALE_POSES = 8
"""Fewest poses for ``estimate_scale="auto"`` to try the scale (six more parameters)."""

NOISE_PASSES = 3
"""Re-estimations of residual-based noise (each followed by a refit)."""


def _drop_open_scale(
    problem: NineChannelProblem, x, options: ImuCalibrationOptions, notes: list
) -> bool:
    """With ``estimate_scale="auto"``: True (and a note naming them) when the weakest direction
    at ``x`` is degenerate and involves scale components, which are then left out."""
    if options.estimate_scale != "auto" or not problem.scale_free:
        return False
    directions = weakest_direction(problem, x)
    scale_names = [name for name in directions.names if name.startswith("accel_scale")]
    if directions.relative >= MIN_RELATIVE_SINGULAR_VALUE or not scale_names:
        return False
    notes.append(
        f"{', '.join(scale_names)} not determined by these poses: taken as 0 (gravity never seen "
        "along both signs of that axis)"
    )
    return True


def _solve(problem: NineChannelProblem, x0: np.ndarray) -> np.ndarray:
    from scipy.optimize import least_squares  # scipy.optimize loads where it is used

    return least_squares(
        problem.whitened_residuals,
        x0,
        jac=lambda x: -problem.whitened_jacobian(x),
        method="lm",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
    ).x


def _noise_from_spread(poses: ImuPoseAverages) -> np.ndarray | None:
    """``(9,)`` pooled spread of repeated readings, or None with fewer than 5 degrees of freedom."""
    repeated = poses.counts > 1
    dof = float(np.sum(poses.counts[repeated] - 1))
    if dof < 5:
        return None
    spread = np.concatenate([poses.accel_spread, poses.wrench_spread], axis=1)[repeated]
    std = np.sqrt(np.sum((poses.counts[repeated] - 1)[:, None] * spread**2, axis=0) / dof)
    return std if np.all(std > 0.0) else None


_GROUPS = (slice(0, 3), slice(3, 6), slice(6, 9))


def _noise_from_residuals(problem: NineChannelProblem, x: np.ndarray, floor: np.ndarray):
    """``(9,)`` per-reading noise, accelerometer, force and torque each pooled, corrected by the
    leverages."""
    jac = problem.whitened_jacobian(x)
    hat = np.einsum("ij,ji->i", jac, np.linalg.pinv(jac.T @ jac, hermitian=True) @ jac.T)
    dof = np.clip(1.0 - hat, 1e-9, 1.0).reshape(-1, 9)
    squares = problem.residuals(x) ** 2 * problem.channel_counts
    return pooled_noise(np.sum(squares, axis=0), np.sum(dof, axis=0), floor, _GROUPS)


def _floor(poses: ImuPoseAverages, g: float) -> np.ndarray:
    return np.concatenate([np.full(3, 1e-7 * g), noise_floor(poses.wrenches)])


def starting_scale(options, pose_count: int, notes: list) -> tuple[int, ...]:
    """The accelerometer scale components to estimate (all, unless ``estimate_scale`` is
    ``"no"``, or ``"auto"`` with fewer than :data:`MIN_SCALE_POSES` poses: said in ``notes``)."""
    if options.estimate_scale == "auto" and pose_count < MIN_SCALE_POSES:
        notes.append(
            f"accelerometer scale not estimated ({pose_count} poses, fewer than "
            f"{MIN_SCALE_POSES}): taken as exact"
        )
        return ()
    return (0, 1, 2) if options.estimate_scale != "no" else ()


def starting_noise(poses: ImuPoseAverages, options, g: float):
    """``(noise (9,), source, from_residuals)``: the per-reading noise to start from (given, or
    the spread of repeated readings, else ones), where it came from (``"given"``, ``"spread"``,
    ``"residuals"``), and the function that re-estimates it from a fit's residuals (the given
    groups stay as given)."""
    fixed = np.repeat([options.accel_noise is not None, options.wrench_noise is not None], [3, 6])
    spread = None if fixed.all() else _noise_from_spread(poses)
    noise = np.ones(9) if spread is None else spread
    if options.accel_noise is not None:
        noise[0:3] = options.accel_noise
    if options.wrench_noise is not None:
        noise[3:9] = options.wrench_noise.channel_std
    source = "given" if fixed.all() else ("spread" if spread is not None else "residuals")

    def from_residuals(problem, x):
        return np.where(fixed, noise, _noise_from_residuals(problem, x, _floor(poses, g)))

    return noise, source, from_residuals


def solve_with_noise(
    problem: NineChannelProblem, x0, source: str, from_residuals, options, notes: list, check
):
    """``(problem, x)`` solved from ``x0``, the noise re-estimated with the fit when it comes
    from the residuals; None when a scale component the poses leave open was dropped (said in
    ``notes``: the caller starts again without it). ``check(problem, x)`` raises for a
    parameter the poses leave open (at the start and at the solution: the start's directions
    can hide a degeneracy that holds at the measured ones)."""
    if source == "residuals":  # rough weights before the check: unit noise mixes units
        problem = replace(problem, noise=from_residuals(problem, x0))
    if _drop_open_scale(problem, x0, options, notes):
        return None
    check(problem, x0)
    x = _solve(problem, x0)
    for _ in range(NOISE_PASSES if source == "residuals" else 0):
        estimate = from_residuals(problem, x)
        settled = np.allclose(estimate, problem.noise, rtol=1e-2, atol=0.0)
        problem = replace(problem, noise=estimate)
        if settled:
            break
        x = _solve(problem, x)
    problem, x = problem.recentred(x)
    if _drop_open_scale(problem, x, options, notes):
        return None
    check(problem, x)
    return problem, x


def covariance_at(problem: NineChannelProblem, x, count: int, needed: str) -> np.ndarray:
    """The covariance of every parameter at the solution ``x`` (the whitened information,
    :func:`~ftkin.calibration.covariance.invert_information`), or
    :class:`UnobservableParameters` naming the undetermined ones among the first ``count``
    parameters (``needed``: what poses would determine them)."""
    jac = problem.whitened_jacobian(x)
    return invert_information(
        jac.T @ jac,
        problem.names,
        f"the information at the solution is singular: {needed}",
        named=count,
    )


@dataclass(frozen=True)
class ImuStaticFit:
    """What :func:`fit_imu_static` found.

    Attributes:
        problem: The final problem (recentred: ``x`` has ``δ = 0``, ``e = 0``).
        x: The parameters at the solution.
        covariance: ``(n, n)`` covariance of the global parameters (directions marginalised).
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        notes: What the fit decided on its own (a scale left out, a misfit).
        fit_test: Its goodness of fit (:class:`~ftkin.calibration.goodness_of_fit.FitTest`).
    """

    problem: ImuStaticProblem
    x: np.ndarray
    covariance: np.ndarray
    noise_source: str
    notes: tuple[str, ...]
    fit_test: FitTest | None = None

    @property
    def parameters(self) -> dict:
        return self.problem.unpack(self.x)


def fit_imu_static(
    poses: ImuPoseAverages, g: float, options: ImuCalibrationOptions | None = None
) -> ImuStaticFit:
    """The joint maximum-likelihood fit of the static IMU calibration (module docstring).

    Raises:
        UnobservableParameters: fewer than :data:`MIN_IMU_POSES` poses, or poses that leave a
            parameter open (named).
        SuspectConvention: the data fit a mirrored accelerometer or wrench.
    """
    options = options or ImuCalibrationOptions()
    if len(poses) < MIN_IMU_POSES:
        raise UnobservableParameters(
            ["force_offset", "torque_offset", "tool_mass", "center_of_mass", "accel_bias"],
            f"{len(poses)} static pose(s); the IMU calibration needs at least {MIN_IMU_POSES} "
            f"(12 recommended): {POSES_NEEDED}",
        )
    notes = []
    scale_free = starting_scale(options, len(poses), notes)
    noise, source, from_residuals = starting_noise(poses, options, g)

    while True:  # at the start, then at the solution: a scale the poses leave open is dropped
        x0, rotation0, units = start(poses, g, options, scale_free)
        problem = ImuStaticProblem(
            poses.specific_force,
            poses.wrenches,
            np.asarray(poses.counts, dtype=float),
            noise,
            g,
            rotation0,
            units,
            options.imu_rotation is None,
            scale_free,
            poses.accel_count_factor,
        )
        x0 = np.concatenate([x0, np.zeros(2 * len(poses))])
        solved = solve_with_noise(
            problem, x0, source, from_residuals, options, notes, check_observable
        )
        if solved is None:  # a scale the poses leave open: dropped, and the fit started again
            scale_free = tuple(k for k in scale_free if ACCEL_SCALE_NAMES[k] not in notes[-1])
            continue
        problem, x = solved
        break
    covariance = covariance_at(problem, x, problem.global_count, POSES_NEEDED)
    count = problem.global_count
    test, factor = nine_channel_fit_test(
        "the static fit from the IMU", problem, x, source, spread_dof(poses), poses.pose_ids
    )
    if factor != 1.0:
        notes.append(misfit_note(test, factor))
    covariance = covariance * factor
    return ImuStaticFit(problem, x, covariance[:count, :count], source, tuple(notes), test)


def spread_dof(poses: ImuPoseAverages) -> float:
    """Degrees of freedom of the noise measured by the spread of repeated readings
    (:func:`_noise_from_spread`): ``Σ (n_i − 1)`` over the poses read more than once."""
    repeated = poses.counts > 1
    return float(np.sum(poses.counts[repeated] - 1))


def nine_channel_fit_test(
    fit_name: str, problem: NineChannelProblem, x, source: str, noise_dof: float, pose_ids
) -> tuple[FitTest, float]:
    """``(test, covariance scale)`` of a static IMU or fused fit at ``x``: the goodness of fit
    over the nine channels (:func:`~ftkin.calibration.goodness_of_fit.fit_test`) and ``χ²/ν``
    when it rejects the model (the standard errors then stay honest), else 1."""
    whitened = problem.whitened_residuals(x).reshape(-1, 9)
    test = fit_test(
        fit_name,
        whitened,
        problem.whitened_jacobian(x),
        channel_names=ACCEL_CHANNELS + WRENCH_CHANNELS,
        noise_source=source,
        noise_dof=np.inf if source == "given" else noise_dof,
        group_ids=pose_ids,
        parameter_count=len(x),
        log=False,  # the fits log their notes
        noise_advice="record several readings per pose (a pose column: their spread gives the "
        "noise) or give both noises (wrench_noise= and accel_noise=, Python) to have it tested",
    )
    return test, test.covariance_scale


def misfit_note(test: FitTest, factor: float) -> str:
    """The warning of an IMU or fused fit that does not fit: the test's and the IMU's causes."""
    return (
        f"{test.warning}. The readings do not fit the IMU model within their noise: the IMU's "
        "clock off the wrench's (files joined by time: check that their stamps share a clock and "
        "an origin), the IMU not rigid with the sensor, a contact or cable at some poses, or "
        f"noise underestimated; standard errors scaled by {np.sqrt(factor):.2f}"
    )


def theta_covariance(covariance: np.ndarray, g: float) -> np.ndarray:
    """``(12, 12)`` covariance over ``[a, F0, M0, P]`` with ``a = [0, 0, −m g]`` from the global
    covariance (its first ten rows ``[F0, M0, m, c]``)."""
    transform = np.zeros((12, len(covariance)))
    transform[2, 6] = -g  # a_z = −m g
    transform[3:9, 0:6] = np.eye(6)
    transform[9:12, 7:10] = np.eye(3)
    return transform @ covariance @ transform.T


MAX_POSES = 2000
"""Most static poses of one IMU fit (its Jacobian grows with the square of the poses)."""


def calibrate_imu(samples: ImuSamples, options=None, **keywords) -> ImuCalibrationResult:
    """Calibrate from static poses with the sensor's own IMU: no arm, no orientation.

    Args:
        samples: :class:`~ftkin.calibration.imu_samples.ImuSamples`
            (:meth:`ImuSamples.from_arrays`); readings sharing a pose id are averaged first.
        options: An :class:`ImuCalibrationOptions` (default: all defaults).
        **keywords: Its fields, given directly.

    Returns:
        A frozen :class:`~ftkin.calibration.imu_result.ImuCalibrationResult`.

    Raises:
        UnobservableParameters: the poses leave a parameter open (fewer than four, or gravity
            not seen along every IMU direction: the accelerometer bias and ``F0`` are then named).
        SuspectConvention: a mirrored accelerometer or wrench, or a non-positive mass.
        InvalidInput: an unknown option.
    """
    if not isinstance(samples, ImuSamples):
        raise InvalidInput(
            "samples must be ftkin ImuSamples (ImuSamples.from_arrays), got "
            f"{type(samples).__name__}"
        )
    stated = options.g if isinstance(options, CalibrationOptions) else samples.g
    given_g = keywords.pop("g", stated)  # ImuCalibrationOptions has none: the samples carry g
    if not np.isclose(float(given_g), samples.g, rtol=1e-12):
        raise InvalidInput(
            f"g = {given_g} m/s² differs from the samples' {samples.g:g} m/s²: give it once, to "
            "ImuSamples.from_arrays(..., g=...)"
        )
    options = ImuCalibrationOptions.from_keywords(options, **keywords)
    poses = samples.pose_averages()
    if len(poses) > MAX_POSES:
        raise InvalidInput(
            f"{len(poses)} poses: a static calibration from the IMU fits up to {MAX_POSES} (two "
            "nuisance parameters each); group the readings into poses first: a 'pose' column "
            "(pose_ids in Python), or a time column 't' from which ftkin calibrate finds the "
            "still phases (ftkin.io.load_imu_samples(..., segments=ftkin.io.static_segments."
            "SegmentParameters()) in Python); a motion is calibrated with --dynamic "
            "(ftkin.calibrate_dynamic in Python)"
        )
    g = samples.g
    fit = fit_imu_static(poses, g, options)
    p = fit.parameters
    rotation = fit.problem.rotation0
    bias_wrench = np.concatenate([p["F0"], p["M0"]])
    measured = specific_force_at_rest(poses.specific_force, rotation, p["b"], p["s"])
    residuals = poses.wrenches - predict_imu(
        bias_wrench, point_mass_parameters(p["m"], p["c"]), measured
    )
    covariance = covariance_in_sensor_axes(
        fit.covariance, rotation, 10 if fit.problem.rotation_free else None
    )
    warnings = list(fit.notes)
    for note in warnings:
        logger.warning("%s", note)
    return ImuCalibrationResult(
        force_offset=p["F0"],
        torque_offset=p["M0"],
        gravity_in_base=np.array([0.0, 0.0, -p["m"] * g]),
        center_of_mass=p["c"],
        g=g,
        method="imu",
        pose_ids=poses.pose_ids,
        pose_wrenches=poses.wrenches,
        residuals=residuals,
        sample_count=int(np.sum(poses.counts)),
        covariance=theta_covariance(covariance, g),
        imu_rotation=rotation,
        accel_bias=p["b"],
        accel_scale=p["s"],
        scale_estimated=tuple(k in fit.problem.scale_free for k in range(3)),
        imu_position=options.imu_position,
        imu_position_source=None if options.imu_position is None else "given",
        parameter_names=fit.problem.names,
        parameter_covariance=covariance,
        accel_std=fit.problem.noise[0:3],
        fit_test=fit.fit_test,
        imu_warnings=tuple(warnings),
    )


def specific_force_at_rest(accel: np.ndarray, rotation, bias, scale) -> np.ndarray:
    """``f_S = R_SI (a − b) ⊘ (1 + s)`` ``(N, 3)`` [m/s²] (no lever arm: at rest)."""
    return corrected_specific_force(accel, bias, scale) @ np.asarray(rotation).T
