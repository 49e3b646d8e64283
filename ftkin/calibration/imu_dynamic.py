"""Dynamic identification from the sensor's IMU: mass, COM, inertia, ``R_SI`` and the IMU's
position from a moving recording with wrench, specific force and angular velocity, no joints.

The gyro's ``w`` and the accelerometer's ``a`` are smoothed and ``w`` differentiated by the
zero-phase Savitzky–Golay filter of the joint-based dynamic path
(:func:`~ftkin.calibration.derivatives.joint_derivatives`), then moved to the sensor frame
(:mod:`ftkin.calibration.imu_model`)::

    ω = R_SI w,  α = R_SI ẇ,  f_S = R_SI (a − b) ⊘ (1 + s) − α × r − ω × (ω × r)
    raw = [F0, M0] − Y([0, ω], [f_S, α]) θ

and the parameters ``x = [F0, M0, θ (10), δ, r]`` (``R_SI = R0 Exp(δ)``; ``δ`` and ``r`` only
when not given) are fitted as in :mod:`ftkin.calibration.dynamic_fit`: linear least squares at
the start rotation and position, the unconstrained nonlinear fit, then the maximum likelihood
over physically consistent bodies (log-Cholesky coordinates).

The accelerometer's bias and scale come from a static IMU calibration (``prior``) or are given.
A moving recording cannot separate the bias from the sensor's offsets: ``F0`` absorbs
``m R_SI b`` and ``M0`` absorbs ``m c × (R_SI b)`` at every sample, whatever the motion. It does
determine the mass, the centre of mass, the inertia, ``R_SI``, the IMU's position and those
combined offsets, which are all that compensating this tool with this IMU needs. Without a bias
the fit takes ``b = 0``, reports the combined offsets, and names the combination it cannot split
(:attr:`~ftkin.calibration.imu_result.ImuCalibrationResult.inseparable`, :data:`UNSPLIT`) with
the way to split it: a static IMU calibration of the same IMU (``prior=``; ``--prior`` on the
command line).
"""

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput, UnobservableParameters
from ..validation import as_vector
from .covariance import (
    check_determined,
    covariance_in_sensor_axes,
    delta_method,
    invert_information,
)
from .derivatives import DEFAULT_POLYORDER, joint_derivatives, uniform_period, window_samples
from .dynamic_fit import THETA_NAMES, noise_from_residuals
from .goodness_of_fit import fit_test
from .imu_fit import theta_covariance
from .imu_model import (
    ACCEL_BIAS_NAMES,
    ACCEL_SCALE_NAMES,
    IMU_POSITION_NAMES,
    IMU_ROTATION_NAMES,
    corrected_specific_force,
    imu_regressor,
)
from .imu_result import ImuCalibrationResult
from .imu_samples import ImuSamples
from .imu_start import kabsch_start
from .information import SensorNoise
from .log_cholesky import (
    body_from_parameters,
    inertia_entries,
    inertia_matrix,
    is_physically_consistent,
    log_cholesky_from_parameters,
    log_cholesky_jacobian,
    nearest_consistent,
    parameters_from_log_cholesky,
)
from .model import WRENCH_CHANNELS, cross_rows, skew
from .mount import exp_so3, right_jacobian_so3
from .observability import MIN_RELATIVE_SINGULAR_VALUE

BIAS_NAMES = tuple(
    f"{'force' if c[0] == 'f' else 'torque'}_offset[{c[1]}]" for c in WRENCH_CHANNELS
)

logger = logging.getLogger(__name__)

IMU_WINDOW_SECONDS = 0.101
"""Default Savitzky–Golay window [s] of the IMU's signals (25 samples at 250 Hz).

Longer than the joints' 51 ms: the gyro's rate ``ẇ`` is its derivative, and the derivative's
noise sits in the regressor (errors in the variables), which biases the fit. With a gyro of
0.005 rad/s per reading at 250 Hz the 51 ms window biased mass, COM and offsets by several
standard errors (``benchmarks/bench_standard_errors.py``, issue 38); at 101 ms no bias shows."""

UNSPLIT = ("accel_bias", "force_offset", "torque_offset")
"""What a moving recording without the accelerometer's bias determines only in combination."""

UNSPLIT_NOTE = (
    "the accelerometer's bias is not separated from the sensor's offsets (a motion cannot split "
    "them: F0 absorbs m·R_SI·b, M0 absorbs m·c × R_SI·b): accel_bias is taken as 0 and "
    "force_offset, torque_offset are the combined offsets, which compensate this tool with this "
    "IMU; to split them, calibrate the same IMU from static poses first and give that "
    "calibration as the prior (ftkin calibrate ... --dynamic --prior STATIC.json; "
    "calibrate_dynamic(samples, prior=static) in Python)"
)
"""The warning of a moving recording calibrated without the accelerometer's bias."""


@dataclass(frozen=True)
class ImuMotion:
    """A moving recording in the sensor frame's terms, before ``R_SI`` and ``r`` are applied.

    Attributes:
        wrenches: ``(N, 6)`` raw readings [N, N·m].
        corrected: ``(N, 3)`` smoothed ``(a − b) ⊘ (1 + s)`` [m/s², IMU frame].
        gyro: ``(N, 3)`` smoothed ``w`` [rad/s, IMU frame].
        gyro_rate: ``(N, 3)`` its derivative ``ẇ`` [rad/s², IMU frame].
    """

    wrenches: np.ndarray
    corrected: np.ndarray
    gyro: np.ndarray
    gyro_rate: np.ndarray


@dataclass(frozen=True)
class ImuDynamicProblem:
    """Whitened least squares of the dynamic IMU identification (inspectable on its own).

    ``x = [F0, M0, θ (10), δ (if rotation_free), r (if position_free)]``; with ``phi`` the ten
    θ entries are log-Cholesky coordinates φ instead.

    Attributes:
        motion: The signals.
        channel_std: ``(6,)`` noise per reading [N, N·m].
        rotation0: ``R0`` ``(3, 3)``.
        position0: ``r`` ``(3,)`` [m] when given (or the value ``r`` is not estimated at).
        rotation_free, position_free: Whether ``δ`` and ``r`` are estimated.
    """

    motion: ImuMotion
    channel_std: np.ndarray
    rotation0: np.ndarray
    position0: np.ndarray
    rotation_free: bool = True
    position_free: bool = True

    @property
    def names(self) -> tuple[str, ...]:
        return (
            BIAS_NAMES
            + THETA_NAMES
            + (IMU_ROTATION_NAMES if self.rotation_free else ())
            + (IMU_POSITION_NAMES if self.position_free else ())
        )

    def unpack(self, x: np.ndarray, phi: bool = False):
        """``(bias (6), θ (10), δ (3), r (3))`` of ``x``."""
        theta = parameters_from_log_cholesky(x[6:16]) if phi else x[6:16]
        i, delta, position = 16, np.zeros(3), self.position0
        if self.rotation_free:
            delta, i = x[i : i + 3], i + 3
        if self.position_free:
            position = x[i : i + 3]
        return x[0:6], theta, delta, position

    def signals(self, delta: np.ndarray, position: np.ndarray):
        """``(R, ω, α, f_S)``: the rotation and the sensor-frame signals at ``δ``, ``r``."""
        rotation = self.rotation0 @ exp_so3(delta)
        motion = self.motion
        omega, alpha = motion.gyro @ rotation.T, motion.gyro_rate @ rotation.T
        lever = np.broadcast_to(position, omega.shape)
        force = (
            motion.corrected @ rotation.T
            - cross_rows(alpha, lever)
            - cross_rows(omega, cross_rows(omega, lever))
        )
        return rotation, omega, alpha, force

    def predict(self, x: np.ndarray, phi: bool = False) -> np.ndarray:
        """``(N, 6)`` predicted raw readings."""
        bias, theta, delta, position = self.unpack(x, phi)
        _, omega, alpha, force = self.signals(delta, position)
        return bias - imu_regressor(force, omega, alpha) @ theta

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(N, 6, len(x))`` derivative of :meth:`predict` (θ-space)."""
        bias, theta, delta, position = self.unpack(x)
        rotation, omega, alpha, force = self.signals(delta, position)
        regressor = imu_regressor(force, omega, alpha)
        count = len(force)
        out = np.zeros((count, 6, len(x)))
        out[:, :, 0:6] = np.eye(6)
        out[:, :, 6:16] = -regressor
        mass, first = theta[0], theta[1:4]
        first_skew, omega_skew, lever_skew = skew(first), skew(omega), skew(position)
        # ∂W/∂f_S: the wrench on the tool moves with the specific force as [m I; [h]×]
        d_wrench_force = np.concatenate([mass * np.eye(3), first_skew])
        i = 16
        if self.rotation_free:
            jr = right_jacobian_so3(delta)
            motion = self.motion
            d_corrected = -rotation @ skew(motion.corrected) @ jr  # ∂(R ã)/∂δ (N, 3, 3)
            d_omega = -rotation @ skew(motion.gyro) @ jr
            d_alpha = -rotation @ skew(motion.gyro_rate) @ jr
            d_force = (
                d_corrected
                + lever_skew @ d_alpha
                + (skew(cross_rows(omega, np.broadcast_to(position, omega.shape))) @ d_omega)
                + omega_skew @ lever_skew @ d_omega
            )
            inertia = inertia_matrix(theta[4:10])
            d_top = (
                mass * d_force
                - first_skew @ d_alpha
                - skew(cross_rows(omega, np.broadcast_to(first, omega.shape))) @ d_omega
                - omega_skew @ first_skew @ d_omega
            )
            d_bottom = (
                first_skew @ d_force
                + inertia @ d_alpha
                - skew(omega @ inertia.T) @ d_omega
                + omega_skew @ inertia @ d_omega
            )
            out[:, :, i : i + 3] = -np.concatenate([d_top, d_bottom], axis=1)
            i += 3
        if self.position_free:
            d_force_position = -(skew(alpha) + omega_skew @ omega_skew)  # ∂f_S/∂r
            out[:, :, i : i + 3] = -d_wrench_force @ d_force_position
        return out

    def whitened_residuals(self, x: np.ndarray, phi: bool = False) -> np.ndarray:
        return ((self.motion.wrenches - self.predict(x, phi)) / self.channel_std).ravel()

    def whitened_jacobian(self, x: np.ndarray, phi: bool = False) -> np.ndarray:
        """``(6N, len(x))`` derivative of the whitened prediction ``predict / σ`` (θ-space, or
        φ-space; ftkin's one sign, :mod:`ftkin.calibration.covariance`)."""
        x_theta = theta_space(x) if phi else x
        jac = (self.jacobian(x_theta) / self.channel_std[:, None]).reshape(-1, len(x))
        if phi:
            jac[:, 6:16] = jac[:, 6:16] @ log_cholesky_jacobian(x[6:16])
        return jac


def theta_space(x_phi: np.ndarray) -> np.ndarray:
    """``x`` with its log-Cholesky block turned back into θ."""
    out = np.array(x_phi, dtype=float)
    out[6:16] = parameters_from_log_cholesky(x_phi[6:16])
    return out


def _lstsq_start(problem: ImuDynamicProblem) -> np.ndarray:
    """Linear least squares of ``[bias, θ]`` at ``R0`` and ``r0`` (the model is linear there)."""
    x = np.zeros(len(problem.names))
    if problem.position_free:
        x[-3:] = problem.position0
    jac = problem.whitened_jacobian(x)[:, :16]
    target = (problem.motion.wrenches / problem.channel_std).ravel()
    x[:16] = np.linalg.lstsq(jac, target, rcond=None)[0]
    return x


def _least_squares(problem: ImuDynamicProblem, x0: np.ndarray, phi: bool) -> np.ndarray:
    from scipy.optimize import least_squares  # scipy loads where it is used

    return least_squares(
        problem.whitened_residuals,
        x0,
        jac=lambda x, phi: -problem.whitened_jacobian(x, phi),
        args=(phi,),
        method="lm",
        x_scale="jac",
        xtol=1e-12,
        ftol=1e-12,
        gtol=1e-12,
        max_nfev=500,
    ).x


def check_observable(problem: ImuDynamicProblem, x: np.ndarray) -> None:
    """Refuse a recording that cannot determine the parameters (static data and the inertia, a
    motion too slow for the IMU's position), naming them.
    """
    if np.sqrt(np.mean(np.sum(problem.motion.gyro_rate**2, axis=1))) < 1e-3:
        raise UnobservableParameters(
            ["inertia_about_com_in_sensor", "imu_position"],
            "the recording does not turn the sensor (angular acceleration ~0): record a moving "
            "excitation (ftkin plan --excitation), or calibrate from static poses",
        )
    check_determined(
        problem.whitened_jacobian(x),
        problem.names,
        "the motion does not excite them apart (a richer excitation turns the sensor about every "
        "axis)",
        MIN_RELATIVE_SINGULAR_VALUE,
    )


def smoothed_noise_variance(times, raw, smooth, rate, window, polyorder, scale) -> dict:
    """Noise variance of the smoothed IMU signals the model is fed, per axis: ``{"gyro": (3,)
    [(rad/s)²], "gyro_rate": (3,) [(rad/s²)²], "corrected": (3,) [(m/s²)²]}``.

    Each raw signal's white noise ``σ²`` is measured from its scatter about the
    Savitzky–Golay fit (``raw`` ``(N, 6)``: gyro then accelerometer; ``smooth``, ``rate`` its
    filtered value and derivative): ``Σ (raw − smooth)² / (N (1 − c₀))``, ``c₀`` the filter's
    weight on the centre sample; the filter passes ``σ² Σ c_k²`` of it to the smoothed value and
    ``σ² Σ d_k²`` to the derivative (``c``, ``d`` its coefficients). The accelerometer's is
    divided by ``(1 + s)²`` as its correction is.
    """
    from scipy.signal import savgol_coeffs

    from .derivatives import uniform_period, window_samples

    period = uniform_period(times)
    window = window_samples(period, polyorder=polyorder) if window is None else int(window)
    smoothing = savgol_coeffs(window, polyorder)
    derivative = savgol_coeffs(window, polyorder, deriv=1, delta=period)
    centre = smoothing[window // 2]
    raw_variance = np.mean((raw - smooth) ** 2, axis=0) / max(1.0 - centre, 1e-12)
    accel = raw_variance[3:6] / (1.0 + np.asarray(scale)) ** 2
    return {
        "gyro": raw_variance[0:3] * np.sum(smoothing**2),
        "gyro_rate": raw_variance[0:3] * np.sum(derivative**2),
        "corrected": accel * np.sum(smoothing**2),
    }


def hidden_noise_variance(times, raw, smooth, window, polyorder, scale) -> dict:
    """The IMU's noise variance, per axis, that reaches the estimate but not the residuals:
    ``{"gyro": (3,) [(rad/s)²], "corrected": (3,) [(m/s²)²]}``, ``σ² (1 − Σ c_k²)``.

    A smoothed reading carries ``σ² Σ c_k²`` of its signal's white noise
    (:func:`smoothed_noise_variance`), and that is all the wrench residuals show; but the
    smoothed noise is correlated over the window, and the parameters, constant over the
    recording, see it through the filter's gain at zero frequency, ``Σ c_k = 1``: the full
    ``σ²``. Added to the residuals' variance it gives the covariance the noise the estimate
    has. The derivative's noise (``Σ d_k = 0``) is left in the residuals' variance: that
    overstates its share, so the covariance errs on the safe side.
    """
    from scipy.signal import savgol_coeffs

    from .derivatives import uniform_period, window_samples

    period = uniform_period(times)
    window = window_samples(period, polyorder=polyorder) if window is None else int(window)
    smoothing = savgol_coeffs(window, polyorder)
    hidden = 1.0 - np.sum(smoothing**2)
    raw_variance = np.mean((raw - smooth) ** 2, axis=0) / max(1.0 - smoothing[window // 2], 1e-12)
    return {
        "gyro": raw_variance[0:3] * hidden,
        "corrected": raw_variance[3:6] / (1.0 + np.asarray(scale)) ** 2 * hidden,
    }


def propagated_variance(problem: ImuDynamicProblem, x: np.ndarray, variance: dict) -> np.ndarray:
    """``(6,)`` mean variance [N², (N·m)²] the smoothed IMU signals' noise (``variance``, per
    signal and axis, :func:`smoothed_noise_variance`) adds to :meth:`ImuDynamicProblem.predict`
    at ``x``: ``Σ_k (∂prediction/∂u_k)² σ_k²`` over the nine inputs, by central differences (each
    reading's prediction depends on its own inputs only), averaged over the readings."""
    added = np.zeros(6)
    for name, values in variance.items():
        signal = getattr(problem.motion, name)
        for axis in range(3):
            step = 1e-6 * max(1.0, float(np.max(np.abs(signal[:, axis]))))
            shifted = []
            for sign in (1.0, -1.0):
                moved = signal.copy()
                moved[:, axis] += sign * step
                shifted.append(
                    replace(problem, motion=replace(problem.motion, **{name: moved})).predict(x)
                )
            slope = (shifted[0] - shifted[1]) / (2.0 * step)
            added += np.mean(slope**2, axis=0) * values[axis]
    return added


def prior_covariance(
    problem: ImuDynamicProblem, x: np.ndarray, accel: np.ndarray, bias, scale, prior
) -> np.ndarray:
    """``(len(x), len(x))`` covariance the prior's accelerometer bias and scale add to ``x``.

    The fit holds ``b`` and ``s`` at the prior's estimates, which carry their own errors (their
    covariance in ``prior.parameter_covariance``; a component the prior did not estimate adds
    nothing). Linearised at the solution, ``x`` moves by ``G δp`` with ``G = −(JᵀJ)⁻¹ Jᵀ P``,
    ``J`` the whitened Jacobian and ``P`` the whitened prediction's derivative in ``p = [b, s]``
    (``accel`` ``(N, 3)`` the smoothed raw accelerometer [m/s², IMU frame]): ``G Σ_p Gᵀ``. The
    prior's readings are not the recording's, so the two errors are independent and add.
    """
    names = ACCEL_BIAS_NAMES + ACCEL_SCALE_NAMES
    known = {name: i for i, name in enumerate(prior.parameter_names)}
    rows = [known.get(name) for name in names]
    sigma = np.zeros((6, 6))
    if prior.parameter_covariance is not None:
        for i, row in enumerate(rows):
            for j, column in enumerate(rows):
                if row is not None and column is not None:
                    sigma[i, j] = prior.parameter_covariance[row, column]
    if not np.any(sigma):
        return np.zeros((len(x), len(x)))
    p0 = np.concatenate([np.asarray(bias, dtype=float), np.asarray(scale, dtype=float)])
    slopes = []
    for k in range(6):  # the prediction is linear in the corrected signal: central differences
        step = 1e-4 * max(1.0, abs(p0[k]))
        shifted = []
        for sign in (1.0, -1.0):
            p = p0.copy()
            p[k] += sign * step
            corrected = corrected_specific_force(accel, p[:3], p[3:])
            moved = replace(problem, motion=replace(problem.motion, corrected=corrected))
            shifted.append(moved.predict(x) / problem.channel_std)
        slopes.append(((shifted[0] - shifted[1]) / (2.0 * step)).ravel())
    jac = problem.whitened_jacobian(x)
    gain = -np.linalg.lstsq(jac, np.stack(slopes, axis=1), rcond=None)[0]
    return gain @ sigma @ gain.T


def _noise(problem: ImuDynamicProblem, x: np.ndarray) -> np.ndarray:
    residuals = problem.motion.wrenches - problem.predict(x)
    return noise_from_residuals(residuals, len(x), problem.motion.wrenches)


def _outputs(x: np.ndarray) -> np.ndarray:
    """``[F0, M0, m, c, I_com entries (6)]`` (16,) of θ-space ``x``."""
    mass, com, about_com = body_from_parameters(x[6:16])
    return np.concatenate([x[0:6], [mass], com, inertia_entries(about_com)])


def calibrate_imu_dynamic(
    samples: ImuSamples,
    prior: ImuCalibrationResult | None = None,
    *,
    accel_bias=None,
    accel_scale=None,
    imu_rotation=None,
    imu_position=None,
    noise: SensorNoise | None = None,
    window: int | None = None,
    polyorder: int = DEFAULT_POLYORDER,
) -> ImuCalibrationResult:
    """Identify bias, mass, COM, inertia, ``R_SI`` and the IMU's position from a moving recording.

    Args:
        samples: :class:`ImuSamples` with ``times`` (uniform) and ``angular_velocity``.
        prior: A static IMU calibration of the same IMU: its accelerometer bias and scale are
            used, its ``R_SI`` starts the fit (and its ``imu_position``, when given, is kept).
        accel_bias, accel_scale: ``(3,)`` [m/s², -]: the accelerometer's (override ``prior``'s).
            With neither ``prior`` nor ``accel_bias`` the bias is taken as 0: the offsets
            reported are then combined with it (:data:`UNSPLIT`, named in the result's
            ``inseparable`` and its warnings); the scale, when not given, is taken as 0.
        imu_rotation: ``R_SI`` ``(3, 3)`` when known: held fixed.
        imu_position: ``r`` ``(3,)`` [m, sensor frame] when known: held fixed (else estimated).
        noise: Per-reading wrench noise; None estimates it per channel from the residuals. A
            given noise is the wrench's alone: the IMU's own noise, measured from its readings'
            scatter about the smoothed signals, is added as it propagates through the model
            (:func:`propagated_variance`), so the fit test (``fit_test``) judges the model and
            not the IMU's noise.
        window, polyorder: The Savitzky–Golay filter (default window about
            :data:`IMU_WINDOW_SECONDS`, 101 ms).

    Raises:
        UnobservableParameters: a recording that does not turn the sensor, or a motion that
            leaves parameters open (named).
        InvalidInput: no times or gyro, non-uniform times, a non-positive mass, a prior that is
            not a calibration from the IMU or whose own bias was not separated.
    """
    if not isinstance(samples, ImuSamples):
        raise InvalidInput(f"samples must be ftkin ImuSamples, got {type(samples).__name__}")
    if samples.times is None or samples.angular_velocity is None:
        raise InvalidInput(
            "a dynamic calibration from the IMU needs the time of each reading (t) and the gyro's "
            "angular velocity (wx, wy, wz)"
        )
    if prior is not None and not isinstance(prior, ImuCalibrationResult):
        raise InvalidInput(
            "the prior (prior=, --prior) must be a static calibration from the IMU (ftkin "
            f"calibrate of static poses with ax,ay,az), got {type(prior).__name__}"
        )
    if prior is not None and accel_bias is None and "accel_bias" in prior.inseparable:
        raise InvalidInput(
            "the prior (prior=, --prior) did not separate the accelerometer's bias (it is a "
            "moving recording's, its offsets combined with the bias): give a static calibration "
            "from the IMU (ftkin calibrate of static poses with ax,ay,az)"
        )
    unsplit = accel_bias is None and prior is None  # b = 0: the offsets absorb m R_SI b
    if accel_bias is not None:
        bias = as_vector(accel_bias, 3, "accel_bias")
    else:
        bias = np.zeros(3) if unsplit else as_vector(prior.accel_bias, 3, "accel_bias")
    scale_given = (
        accel_scale
        if accel_scale is not None
        else (prior.accel_scale if prior is not None else np.zeros(3))
    )
    scale = as_vector(scale_given, 3, "accel_scale")
    order = np.argsort(samples.times, kind="stable")
    if window is None:
        period = uniform_period(samples.times[order])
        window = window_samples(period, IMU_WINDOW_SECONDS, polyorder)
    signals = np.concatenate([samples.angular_velocity, samples.specific_force], axis=1)[order]
    smooth, rate, _ = joint_derivatives(samples.times[order], signals, window, polyorder)
    motion = ImuMotion(
        samples.wrenches[order],
        corrected_specific_force(smooth[:, 3:6], bias, scale),
        smooth[:, 0:3],
        rate[:, 0:3],
    )
    position_given = (
        imu_position
        if imu_position is not None
        else (
            prior.imu_position
            if prior is not None and prior.imu_position_source == "given"
            else None
        )
    )
    if imu_rotation is not None:
        rotation0 = np.asarray(imu_rotation, dtype=float)
    elif prior is not None:
        rotation0 = np.array(prior.imu_rotation)
    else:  # Kabsch of the forces against the corrected specific force (motion terms are small)
        norm = float(np.linalg.norm(motion.corrected, axis=1).mean())
        rotation0 = kabsch_start(motion.corrected / norm, motion.wrenches[:, :3], norm)[0]
    problem = ImuDynamicProblem(
        motion,
        np.array([1.0, 1.0, 1.0, 0.1, 0.1, 0.1]) if noise is None else noise.channel_std,
        rotation0,
        np.zeros(3) if position_given is None else as_vector(position_given, 3, "imu_position"),
        imu_rotation is None,
        position_given is None,
    )
    x = _lstsq_start(problem)
    check_observable(problem, x)
    if noise is None:
        problem = replace(problem, channel_std=_noise(problem, x))
        x = _lstsq_start(problem)
    x = _least_squares(problem, x, False)
    if not x[6] > 0.0:
        raise InvalidInput(
            f"the estimated tool mass is {x[6]:.4g} kg (not positive): is there a tool on the "
            "sensor, and is the accelerometer the specific force (+g upward at rest)?"
        )
    unconstrained = x[6:16].copy()
    start_theta = (
        unconstrained
        if is_physically_consistent(unconstrained)
        else nearest_consistent(unconstrained)
    )
    x_phi = np.concatenate([x[:6], log_cholesky_from_parameters(start_theta), x[16:]])
    x = theta_space(_least_squares(problem, x_phi, True))
    if noise is None:
        problem = replace(problem, channel_std=_noise(problem, x))
    else:  # the IMU's own noise reaches the prediction: the readings' scatter is larger
        signal_variance = smoothed_noise_variance(
            samples.times[order], signals, smooth, rate, window, polyorder, scale
        )
        added = propagated_variance(problem, x, signal_variance)
        problem = replace(problem, channel_std=np.sqrt(noise.channel_std**2 + added))
    if unsplit:
        logger.warning("%s", UNSPLIT_NOTE)
    test = fit_test(
        "the dynamic fit from the IMU",
        problem.whitened_residuals(x).reshape(-1, 6),
        problem.whitened_jacobian(x),
        channel_names=WRENCH_CHANNELS,
        noise_source="residuals" if noise is None else "given",
        times=samples.times[order],
        parameter_count=len(x),
    )
    hidden = hidden_noise_variance(  # the covariance's noise is the estimate's (issue 38)
        samples.times[order], signals, smooth, window, polyorder, scale
    )
    estimate_std = np.sqrt(problem.channel_std**2 + propagated_variance(problem, x, hidden))
    from_prior = (  # the prior's b and s are estimates: their errors reach x (issue 38)
        prior_covariance(problem, x, smooth[:, 3:6], bias, scale, prior)
        if prior is not None and accel_bias is None and accel_scale is None
        else None
    )
    result = _result(
        samples,
        replace(problem, channel_std=estimate_std),
        x,
        bias,
        scale,
        position_given is None,
        unsplit,
        test.covariance_scale,
        from_prior,
    )
    warnings = result.imu_warnings + (() if test.fits else (test.warning,))
    return replace(result, fit_test=test, imu_warnings=warnings)


def _result(
    samples,
    problem: ImuDynamicProblem,
    x,
    bias,
    scale,
    position_estimated,
    unsplit,
    factor=1.0,
    from_prior=None,
):
    """The result at ``x``, its covariance scaled by ``factor`` (a misfit's ``χ²/ν``), plus
    ``from_prior`` (:func:`prior_covariance`) when given."""
    jac = problem.whitened_jacobian(x)
    covariance = factor * invert_information(
        jac.T @ jac, problem.names, "the information at the solution is singular"
    )
    if from_prior is not None:
        covariance = covariance + from_prior
    _, theta, delta, position = problem.unpack(x)
    rotation = problem.rotation0 @ exp_so3(delta)
    gradient, body_covariance = delta_method(_outputs, x, covariance)
    outputs = _outputs(x)
    mass, com, g = outputs[6], outputs[7:10], samples.g
    theta_cov = theta_covariance(body_covariance, g)  # [a, F0, M0, P] with a = [0, 0, −m g]
    # the reported parameters: [F0, M0, m, c] and the IMU's, rotation about the sensor axes
    names = BIAS_NAMES + (
        "tool_mass",
        "center_of_mass[x]",
        "center_of_mass[y]",
        "center_of_mass[z]",
    )
    rest = slice(16, len(x))
    rows = np.zeros((10 + len(x) - 16, len(x)))
    rows[:10] = gradient[:10]
    rows[10:, rest] = np.eye(len(x) - 16)
    parameter_covariance = covariance_in_sensor_axes(  # δ → sensor-axes increment R J_r(δ) δ
        rows @ covariance @ rows.T,
        rotation @ right_jacobian_so3(delta),
        10 if problem.rotation_free else None,
    )
    names += problem.names[16:]
    inertia_sigma = np.sqrt(np.clip(np.diag(body_covariance)[10:16], 0.0, None))
    residual = problem.motion.wrenches - problem.predict(x)
    return ImuCalibrationResult(
        force_offset=outputs[0:3],
        torque_offset=outputs[3:6],
        gravity_in_base=np.array([0.0, 0.0, -mass * g]),
        center_of_mass=com,
        g=g,
        method="imu-dynamic",
        sample_count=len(samples),
        covariance=theta_cov,
        inertia_about_com_in_sensor=inertia_matrix(outputs[10:16]),
        inertia_std_errors=inertia_matrix(inertia_sigma),
        inertial_parameters=theta,
        inertial_covariance=covariance[6:16, 6:16],
        imu_rotation=rotation,
        accel_bias=bias,
        accel_scale=scale,
        scale_estimated=(False, False, False),
        imu_position=position,
        imu_position_source="estimated" if position_estimated else "given",
        parameter_names=names,
        parameter_covariance=parameter_covariance,
        motion_residual_rms=np.sqrt(np.mean(residual**2, axis=0)),
        imu_warnings=(UNSPLIT_NOTE,) if unsplit else (),
        inseparable=UNSPLIT if unsplit else (),
    )
