"""Dynamic calibration: the tool's full inertia from a moving recording, :func:`calibrate_dynamic`.

Estimates, from raw readings along a motion (:class:`~ftkin.calibration.regressor.MotionSamples`),
the sensor bias, the gravity direction (base tilt ``U``, ``V``), and the ten
inertial parameters of the tool in the sensor frame: mass, centre of mass and
inertia tensor. The fit (:mod:`ftkin.calibration.dynamic_fit`) runs weighted
least squares first, then the maximum-likelihood fit restricted to physically
consistent bodies through log-Cholesky coordinates; standard errors come from
the Gauss–Newton covariance by the delta method.

Static calibration is the special case ``estimate_inertia=False`` (mass and
centre of mass only). Static data with ``estimate_inertia=True`` raise
:class:`~ftkin.exceptions.UnobservableParameters` naming the inertia: it is
never invented.
"""

from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput, SuspectConvention
from ..kinematics.rotations import gravity_in_base_from_tilt
from .conventions import check_conventions, detect_sign_and_handedness
from .covariance import delta_method, invert_information
from .dynamic_fit import (
    ALL_INDICES,
    STATIC_INDICES,
    DynamicProblem,
    check_observability,
    fit_linear,
    fit_nonlinear,
    noise_from_residuals,
    theta_space,
)
from .goodness_of_fit import WRENCH_CHANNELS, fit_test
from .information import SensorNoise
from .log_cholesky import (
    body_from_parameters,
    inertia_entries,
    inertia_matrix,
    is_physically_consistent,
    log_cholesky_from_parameters,
    nearest_consistent,
    parameters_from_log_cholesky,
)
from .model import STANDARD_GRAVITY, check_gravity
from .regressor import MotionSamples
from .result import CalibrationResult
from .samples import Samples


@dataclass(frozen=True)
class DynamicCalibrationResult(CalibrationResult):
    """A :class:`~ftkin.calibration.CalibrationResult` plus the tool's inertia.

    The inherited static parameters (bias, ``gravity_in_base``, ``center_of_mass``,
    ``g``) and their ``(12, 12)`` ``covariance`` come from the same fit, so this
    result compensates statically like any calibration.

    The inertia (``inertia_about_com_in_sensor``, ``inertial_parameters``, their errors and
    covariance) is a declared part of every calibration; this adds the fit over the motion.

    Attributes:
        motion_residual_rms: ``(6,)`` RMS of measured minus predicted per channel [N, N·m].
        channel_std: ``(6,)`` noise per reading used as weights [N, N·m].
        unconstrained_parameters: θ of the unconstrained least squares (before
            the consistency constraint), or None.
        unconstrained_consistent: Whether that θ was physically consistent.
    """

    motion_residual_rms: np.ndarray | None = None
    channel_std: np.ndarray | None = None
    unconstrained_parameters: np.ndarray | None = None
    unconstrained_consistent: bool | None = None

    _OPTIONAL_ARRAYS = CalibrationResult._OPTIONAL_ARRAYS + (
        "motion_residual_rms",
        "channel_std",
        "unconstrained_parameters",
    )

    def summary(self) -> str:
        """Static summary (with the inertia) plus the fit over the motion."""
        lines = super().summary().split("\n")
        lines[0] = (
            f"ftkin calibration: method {self.method}, moving recording of {self.sample_count} "
            "readings"
        )
        if self.unconstrained_consistent is False:
            lines.append(
                "  NOTE: the unconstrained least squares was not physically consistent; the ML fit "
                "is"
            )
        if self.motion_residual_rms is not None:
            lines.append(
                "  residual RMS over the motion: "
                + ", ".join(f"{v:.4g}" for v in self.motion_residual_rms)
                + " (N, N·m)"
            )
        return "\n".join(lines)


def _with_noise_estimate(problem: DynamicProblem, x: np.ndarray) -> DynamicProblem:
    """``problem`` weighted by the noise per channel [N, N·m] of its residuals at ``x`` (θ)."""
    residuals = problem.wrenches - problem.predict(x)
    return replace(problem, channel_std=noise_from_residuals(residuals, len(x), problem.wrenches))


def _outputs(problem: DynamicProblem, x: np.ndarray, phi: bool) -> np.ndarray:
    """``[a (3), F0, M0, P, θ (10), I_com entries (6)]`` (28,) at ``x``."""
    theta = parameters_from_log_cholesky(x[8:]) if phi else problem.theta(x[8:])
    mass, com, about_com = body_from_parameters(theta)
    gravity = gravity_in_base_from_tilt(mass * problem.g, x[6], x[7])
    return np.concatenate([gravity, x[:6], com, theta, inertia_entries(about_com)])


def _covariance(problem: DynamicProblem, x: np.ndarray, phi: bool) -> np.ndarray:
    """Covariance of :func:`_outputs` by the delta method from the Gauss–Newton covariance of
    ``x``.
    """
    jac = problem.whitened_jacobian(x, phi)
    cov_x = invert_information(
        jac.T @ jac,
        problem.names,
        "the information at the solution is singular (the estimate sits on the boundary of "
        "physical consistency or the motion does not excite these parameters)",
    )
    return delta_method(lambda point: _outputs(problem, point, phi), x, cov_x)[1]


def _refuse_non_positive_mass(motion: MotionSamples, mass: float, g: float) -> None:
    """Name the likely convention behind a non-positive mass estimate, else refuse it [kg]."""
    # a negative mass is most often a convention: readings negated (the reaction) or a base
    # mounted upside down
    try:
        static = Samples(motion.wrenches, motion.rotations).pose_averages()
        check_conventions(detect_sign_and_handedness(static, g=g))
    except SuspectConvention as error:
        raise SuspectConvention(
            f"{error} The dynamic calibration takes none of these options yet: negate the "
            "readings (sign) or "
            "calibrate from static poses, where they apply.",
            error.explanations,
            error.fixes,
            error.sensor_sign,
            error.flip_axis,
        ) from None
    raise InvalidInput(
        f"the estimated tool mass is {mass:.4g} kg (not positive): is there a tool on the sensor?"
    )


def _checked_motion(motion, noise) -> MotionSamples:
    """``motion`` as :class:`MotionSamples` (static :class:`Samples` at rest), ``noise`` checked."""
    if isinstance(motion, Samples):
        motion = MotionSamples.from_static(motion)
    if not isinstance(motion, MotionSamples):
        raise InvalidInput(
            f"motion must be an ftkin MotionSamples or Samples, got {type(motion).__name__}"
        )
    if noise is not None and not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin.SensorNoise, got {type(noise).__name__}")
    return motion


def calibrate_dynamic(
    motion: MotionSamples | Samples,
    *,
    estimate_inertia: bool = True,
    g: float = STANDARD_GRAVITY,
    noise: SensorNoise | None = None,
    **imu,
) -> DynamicCalibrationResult:
    """Identify bias, base tilt, mass, centre of mass and (optionally) inertia from readings along a
    motion.

    Args:
        motion: Readings with the sensor frame's orientation, velocity and
            acceleration (:meth:`MotionSamples.from_joint_trajectory`); static
            :class:`Samples` count as a motion at rest.
        estimate_inertia: False fits the static model only (bias, tilt, mass, COM):
            static calibration as the special case.
        g: Magnitude of gravity [m/s²] (known; its direction is estimated).
        noise: Per-reading noise [N, N·m]; None estimates it per channel from the residuals.
        **imu: For IMU samples (``ImuSamples.from_arrays``, no joints): the options of
            :func:`~ftkin.calibration.imu_dynamic.calibrate_imu_dynamic` (``prior``, ...).

    Returns:
        A frozen :class:`DynamicCalibrationResult`.

    Raises:
        UnobservableParameters: the motion cannot determine the parameters (static
            data with ``estimate_inertia=True`` names the inertia).
        InvalidInput: bad arguments, or a non-positive mass estimate.
    """
    from .imu_samples import ImuSamples  # (with the dynamic fit, not with this module)

    if isinstance(motion, ImuSamples):  # no joints: the IMU's own fit
        from .imu_dynamic import calibrate_imu_dynamic

        if not estimate_inertia or check_gravity(g) != motion.g:
            raise InvalidInput(
                "a dynamic calibration from the IMU always estimates the inertia, with the g of "
                f"its samples ({motion.g:g} m/s²: ImuSamples.from_arrays(..., g=...))"
            )
        return calibrate_imu_dynamic(motion, noise=noise, **imu)
    if imu:
        raise InvalidInput(f"unknown calibrate_dynamic option(s) {', '.join(sorted(imu))}")
    motion = _checked_motion(motion, noise)
    g = check_gravity(g)
    problem = DynamicProblem(
        motion.wrenches,
        motion.rotations,
        motion.regressor(),
        np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]) if noise is None else noise.channel_std,
        g,
        ALL_INDICES if estimate_inertia else STATIC_INDICES,
    )
    check_observability(problem)
    x = fit_linear(problem)
    if noise is None:
        problem = _with_noise_estimate(problem, x)
        x = fit_linear(problem)
    x = fit_nonlinear(problem, x)
    theta_unconstrained = problem.theta(x[8:])
    if theta_unconstrained[0] <= 0.0:
        _refuse_non_positive_mass(motion, theta_unconstrained[0], g)
    consistent = is_physically_consistent(theta_unconstrained) if estimate_inertia else None
    if estimate_inertia:
        start = theta_unconstrained if consistent else nearest_consistent(theta_unconstrained)
        x = fit_nonlinear(
            problem, np.concatenate([x[:8], log_cholesky_from_parameters(start)]), True
        )
    x_theta = theta_space(x) if estimate_inertia else x
    if noise is None:
        problem = _with_noise_estimate(problem, x_theta)
    values = _outputs(problem, x, estimate_inertia)
    covariance = _covariance(problem, x, estimate_inertia)
    test = fit_test(
        "the dynamic fit from joints",
        problem.whitened_residuals(x_theta).reshape(-1, 6),
        problem.whitened_jacobian(x_theta),
        channel_names=WRENCH_CHANNELS,
        noise_source="residuals" if noise is None else "given",
        times=np.arange(len(motion), dtype=float) if motion.times is None else motion.times,
        parameter_count=len(x),
    )
    covariance = covariance * test.covariance_scale  # honest standard errors on a misfit
    return DynamicCalibrationResult(
        force_offset=values[3:6],
        torque_offset=values[6:9],
        gravity_in_base=values[0:3],
        center_of_mass=values[9:12],
        g=g,
        method="dynamic" if estimate_inertia else "dynamic-static",
        sample_count=len(motion),
        urdf=motion.urdf,
        sensor_frame=motion.sensor_frame,
        kinematics=motion.kinematics,
        covariance=covariance[:12, :12],
        inertia_about_com_in_sensor=inertia_matrix(values[22:28]) if estimate_inertia else None,
        inertia_std_errors=(
            inertia_matrix(np.sqrt(np.clip(np.diag(covariance)[22:28], 0.0, None)))
            if estimate_inertia
            else None
        ),
        inertial_parameters=values[12:22] if estimate_inertia else None,
        inertial_covariance=covariance[12:22, 12:22] if estimate_inertia else None,
        motion_residual_rms=np.sqrt(
            np.mean((problem.wrenches - problem.predict(x_theta)) ** 2, axis=0)
        ),
        channel_std=problem.channel_std,
        unconstrained_parameters=theta_unconstrained if estimate_inertia else None,
        unconstrained_consistent=consistent,
        fit_test=test,
    )
