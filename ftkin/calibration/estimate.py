"""Static calibration of a wrist F/T sensor: :func:`calibrate`, its options and its result.

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

import logging
from dataclasses import dataclass, fields, replace

import numpy as np

from ..exceptions import InvalidInput, InvalidSamples
from ..options import checked, number, option
from ..validation import as_float_array
from .conventions import BASE_MOUNTS, check_conventions, detect_sign_and_handedness, reading_signs
from .diagnostics import FitDiagnostics
from .drift import BiasDrift, check_drift_spec, drift_candidates
from .explained import check_explained
from .fit_quality import diagnose, log_warnings
from .information import SensorNoise, noise_floor
from .ml import LOSSES, fit_ml
from .model import STANDARD_GRAVITY, SensorModel, check_gravity
from .mount import MOUNT_NAMES, POSES_NEEDED, MountMode
from .orientation_mistakes import refuse_orientation_mistakes
from .result import CalibrationResult
from .samples import PoseAverages, Samples, check_one_visit_per_pose

logger = logging.getLogger(__name__)

MOUNT_STD_WARNING_DEG = 1.0
"""Standard error [deg] of a mount angle above which the calibration warns."""

METHODS = ("ml", "linear")
"""Estimators :func:`calibrate` accepts; the first is the default."""


@dataclass(frozen=True)
class CalibrationOptions:
    """How :func:`calibrate` fits; every combination is checked here, once.

    Attributes:
        method: ``"ml"`` (default): joint maximum-likelihood fit of all six
            channels with standard errors and diagnostics (:mod:`ftkin.calibration.ml`);
            ``"linear"``: the paper's two-step least squares.
        g: Gravity used to report the tool mass [m/s²] (the paper used 9.8).
        noise: ``ml`` only: noise of one raw reading [N, N·m]. None estimates
            it from the spread of repeated readings per pose, else from the
            residuals (jointly with a drift, :mod:`ftkin.calibration.drift_fit`).
        loss: ``ml`` only: ``"linear"`` (Gaussian likelihood), ``"soft_l1"``
            or ``"huber"`` (robust to outlying poses).
        drop_outliers: ``ml`` only: refit once without the poses flagged as
            outliers (see :mod:`ftkin.calibration.fit_quality`).
        estimate_mount: ``ml`` only: ``"none"`` (default), ``"yaw"`` (the
            sensor turned about its z axis on the flange) or ``"full"`` (any
            rotation): estimate the mount ``R_M`` jointly (samples from joint
            angles only; :mod:`ftkin.calibration.mount`).
        sensor_sign: ``+1`` (default) or ``-1``: negate every reading (a sensor
            reporting the reaction); see :mod:`ftkin.calibration.conventions`.
        flip_axis: None or ``"x"``, ``"y"``, ``"z"``: negate that axis's force
            and torque channels (a mirrored axis).
        base_mount: ``"floor"`` (gravity along base −z), ``"ceiling"`` (+z) or ``"wall"`` (no
            direction check); None (default): a floor mount nobody declared. A fitted tool
            weight more than :data:`~ftkin.calibration.conventions.TILT_WARNING_DEG` (5°) from
            the expected direction is warned; from a *declared* one (``base_mount`` or
            ``expected_gravity`` given), more than
            :data:`~ftkin.calibration.conventions.TILT_REFUSAL_DEG` (15°) is refused.
        expected_gravity: Expected gravity direction [base frame]; overrides ``base_mount``.
        allow_tilt: Accept a tool weight more than 15° from a declared gravity direction (the
            base really is tilted so far; still warned).
        drift: How the bias may change with time when the samples carry
            times (:mod:`ftkin.calibration.drift`): ``"auto"`` (default: the
            model the information criterion prefers; the constant bias without
            times, with ``method="linear"``, a robust loss, ``drop_outliers`` or
            a mount estimate), ``"none"`` (constant), or a registered model
            (``"poly:N"``, ``"random-walk"``, ...; these need times and the plain ``ml`` fit).
        resolution: ``ml`` only: ``(force [N], torque [N·m])`` resolution of one
            reading (its quantization step): an estimated noise is at least
            ``resolution / √12``, so a drift model cannot take all of it.
        convention_check: Read orientations given directly (Euler angles, quaternions,
            matrices) under their common mistakes and refuse data that fit only so
            (:mod:`ftkin.calibration.orientation_mistakes`); False: fit as given (CLI:
            ``--no-convention-check``).
    """

    method: str = option(
        "ml",
        "estimator: ml (joint maximum likelihood, with standard errors) or linear (the paper's "
        "two-step least squares) (default: ml; ftkin paper: linear, the paper's)",
        choices=METHODS,
        cli_default=None,
    )
    g: float = option(
        STANDARD_GRAVITY,
        "gravity for the tool mass, 1 to 30 (the paper used 9.8, franky-sim and MuJoCo's "
        "scenes 9.81)",
        unit="m/s²",
        parse=checked(lambda text: check_gravity(float(text)), "a number of m/s²"),
    )
    noise: SensorNoise | None = option(
        None, "the noise of one reading (CLI: --noise-force and --noise-torque)", cli=False
    )
    loss: str = option(
        "linear", "loss function; soft_l1 and huber resist outlier poses", choices=LOSSES
    )
    drop_outliers: bool = option(
        False, "refit without the poses flagged as outliers", action="store_true"
    )
    estimate_mount: MountMode | str = option(
        MountMode.NONE,
        "the sensor's rotation on the flange is estimated too: yaw (about its z axis) or full "
        "(any rotation); calibrate needs joint-angle samples, plan and evaluate-poses plan and "
        "predict for it",
        choices=("yaw", "full"),
        metavar="yaw|full",
        cli_default=None,
    )
    sensor_sign: int = option(
        1,
        "-1: the sensor reports the reaction, not the load on it (calibrate negates every "
        "reading, simulate writes such readings)",
        parse=int,
        choices=(1, -1),
    )
    flip_axis: str | None = option(
        None,
        "negate this axis's force and torque channels in every reading (a mirrored, left-handed "
        "sensor axis)",
        choices=("x", "y", "z"),
    )
    base_mount: str | None = option(
        None,
        "how the robot base is mounted: floor (gravity along base -z), ceiling (+z), wall (no "
        "check); a fitted weight more than 90° off the expected direction is refused as a "
        "suspect sign, more than 5° warned, and more than 15° from a declared mount refused "
        "(--allow-tilt) (default: floor, not declared: a tilt is warned, not refused)",
        choices=BASE_MOUNTS,
    )
    expected_gravity: object = option(
        None,
        "expected gravity direction in the base frame (overrides --base-mount); a fitted weight "
        "more than 15° from it is refused (--allow-tilt)",
        parse=number(),
        nargs=3,
        metavar=("GX", "GY", "GZ"),
    )
    allow_tilt: bool = option(
        False,
        "accept a fitted weight more than 15° from the declared gravity direction (--base-mount, "
        "--expected-gravity): the base really is tilted so far (still warned)",
        action="store_true",
    )
    drift: str = option(
        "auto",
        "bias drift over time, with a 't' column: auto (the model BIC prefers, said), none, "
        "poly:N (a polynomial of degree N), random-walk (estimates the rate), random-walk+poly:N, "
        "or a model registered with register_drift_model",
        parse=checked(check_drift_spec, "a drift model"),
        metavar="MODEL",
    )
    resolution: object = option(
        None,
        "resolution (quantization step) of one force and one torque reading: an estimated noise "
        "is at least resolution/√12, so a drift model cannot take all of it",
        unit="N, N·m",
        parse=number(0.0, above=True),
        nargs=2,
        metavar=("N", "N·m"),
    )

    convention_check: bool = option(
        True, "refit orientations under their common mistakes (--no-convention-check)", cli=False
    )

    def __post_init__(self):
        object.__setattr__(self, "g", check_gravity(self.g))
        if self.resolution is not None:
            resolution = as_float_array(self.resolution, "resolution").reshape(-1)
            if resolution.shape != (2,) or not np.all(np.isfinite(resolution) & (resolution > 0)):
                raise InvalidInput(
                    "resolution must be [force N, torque N·m], finite and > 0, got "
                    f"{self.resolution}"
                )
            object.__setattr__(self, "resolution", resolution)
        check_drift_spec(self.drift)  # refused here; "auto" and "none" build no model
        ml_only = self.noise is not None or self.loss != "linear" or self.drop_outliers
        mount = MountMode.of(self.estimate_mount)  # the one check of the mode
        object.__setattr__(self, "estimate_mount", mount)
        drifting = self.drift not in ("auto", "none")
        for refused, message in (
            (
                self.method not in METHODS,
                f"unknown calibration method {self.method!r}; expected one of {', '.join(METHODS)}",
            ),
            (
                not isinstance(self.convention_check, bool),
                f"convention_check must be True or False, got {self.convention_check!r}",
            ),
            (
                self.loss not in LOSSES,
                f"unknown loss {self.loss!r}; expected one of {', '.join(LOSSES)}",
            ),
            (
                self.noise is not None and not isinstance(self.noise, SensorNoise),
                f"noise must be an ftkin.SensorNoise, got {type(self.noise).__name__}",
            ),
            (
                self.method == "linear" and (ml_only or self.resolution is not None),
                "noise, resolution, loss and drop_outliers (--noise-force/--noise-torque, "
                "--resolution, --loss, --drop-outliers) apply to method='ml' (--method ml) only",
            ),
            (
                mount != "none" and self.method != "ml",
                "estimate_mount (--estimate-mount) applies to method='ml' (--method ml) only",
            ),
            (
                drifting and (self.method != "ml" or ml_only),
                f"drift={self.drift!r} needs method='ml' with loss='linear' and no drop_outliers",
            ),
            (
                drifting and mount != "none",
                f"drift={self.drift!r} and estimate_mount={self.estimate_mount!r} cannot be fitted "
                "together yet: estimate the mount from a short recording (drift='none'), then the "
                "drift",
            ),
        ):
            if refused:
                raise InvalidInput(message)

    def check(self, samples: Samples) -> tuple:
        """Check the options against ``samples``; the drift models to fit (empty: a constant bias).

        Raises:
            InvalidInput: a mount estimate for samples whose rotations were given
                directly; a drift model without times, with all times equal, or
                with a pose revisited (``auto`` keeps the constant bias instead).
        """
        if not isinstance(samples, Samples):
            raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
        auto, timed = self.drift == "auto", samples.times is not None
        spread = timed and np.ptp(samples.times) > 0.0
        # auto looks for a drift only with the plain ml fit, no mount and times that differ
        plain = self.method == "ml" and self.loss == "linear" and not self.drop_outliers
        fits_drift = self.drift != "none" and (
            not auto or (plain and spread and self.estimate_mount == "none")
        )
        for refused, message in (
            (
                self.estimate_mount != "none" and samples.joint_positions is None,
                "estimate_mount needs samples from joint angles (Samples.from_joint_positions): "
                "rotations given directly are taken as the real sensor orientation, so any mount "
                "is already in them (absorbed)",
            ),
            (
                fits_drift and not timed,
                f"drift={self.drift!r} needs the time of each reading (Samples.times, a 't' column "
                "in the CSV)",
            ),
            (
                fits_drift and timed and not spread,
                f"drift={self.drift!r}: all readings have the same time; a drift needs readings "
                "spread over time",
            ),
        ):
            if refused:
                raise InvalidInput(message)
        if not fits_drift:
            return ()
        try:
            check_one_visit_per_pose(samples)
        except InvalidSamples as error:
            if not auto:
                raise
            logger.warning("%s; drift='auto' keeps a constant bias", error)  # not asked for
            return ()
        return drift_candidates(self.drift)

    def noise_floor(self, wrenches) -> np.ndarray:
        """``(6,)`` lowest noise an estimate may take [N, N·m]: the numeric floor, or the
        resolution's quantization noise.
        """
        quantization = (
            0.0 if self.resolution is None else np.repeat(self.resolution, 3) / np.sqrt(12.0)
        )
        return np.maximum(noise_floor(wrenches), quantization)


def calibrate(samples: Samples, options: CalibrationOptions | None = None, **keywords):
    """Estimate bias, tool gravity and base tilt from static-pose readings.

    Args:
        samples: Raw readings with sensor orientations (see :class:`Samples`);
            readings sharing a pose id are averaged first. IMU samples
            (:meth:`Samples.from_imu`) are fitted by
            :func:`~ftkin.calibration.imu_fit.calibrate_imu` (options:
            :class:`~ftkin.calibration.imu_options.ImuCalibrationOptions`); samples with both
            (:meth:`Samples.with_imu`) by :func:`~ftkin.calibration.fused_fit.calibrate_fused`
            (options: :class:`~ftkin.calibration.fused_options.FusedCalibrationOptions`).
        options: A :class:`CalibrationOptions` (default: all defaults).
        **keywords: Its fields, given directly (``method="linear"``, ``drift="poly:2"``, ...);
            they replace those of ``options``.

    Returns:
        A frozen :class:`CalibrationResult`.

    Raises:
        UnobservableParameters: the poses cannot determine the parameters
            (fewer than three, orientations alike, gravity along one sensor
            direction); the error names them.
        InvalidInput: an option or a combination of options
            (:class:`CalibrationOptions`), or options the samples do not support.
        ConventionMistake: orientations that fit only when read in another convention (Euler
            angles in radians, a quaternion x,y,z,w, ``R_SB`` for ``R_BS``), with the fix;
            ``convention_check=False`` fits them as given.
        SuspectConvention: the data fit with an axis reversed, or the tool
            weight points more than 90° from the expected gravity direction, or more than 15°
            from a declared one without ``allow_tilt``.
        UnexplainedReadings: the fit explains less than half of the readings' variation
            across poses (:mod:`ftkin.calibration.explained`): mislabelled columns.
    """
    if not isinstance(samples, Samples):  # the IMU's samples (their modules load on demand)
        from .fused_samples import FusedSamples
        from .imu_samples import ImuSamples

        if isinstance(samples, ImuSamples):  # no orientation: the IMU's own fit
            from .imu_fit import calibrate_imu

            return calibrate_imu(samples, options, **keywords)
        if isinstance(samples, FusedSamples):  # an orientation and the IMU: the fused fit
            from .fused_fit import calibrate_fused

            return calibrate_fused(samples, options, **keywords)
    unknown = set(keywords) - {f.name for f in fields(CalibrationOptions)}
    if unknown:
        raise InvalidInput(f"unknown calibrate option(s) {', '.join(sorted(unknown))}")
    options = replace(options or CalibrationOptions(), **keywords)
    drift_models = options.check(samples)
    signs = reading_signs(options.sensor_sign, options.flip_axis)
    raw_poses = samples.pose_averages()
    poses = replace(raw_poses, wrenches=raw_poses.wrenches * signs)
    given = None  # the two-step fit of ``poses``, fitted once (the checks' and ml's start)
    if options.convention_check:  # before the sign's check: a wrong order is no sign
        given = refuse_orientation_mistakes(samples, signs, poses)
    convention = detect_sign_and_handedness(
        raw_poses,
        sensor_sign=options.sensor_sign,
        flip_axis=options.flip_axis,
        estimate_mount=options.estimate_mount,
        base_mount=options.base_mount,
        expected_gravity=options.expected_gravity,
        g=options.g,
        linear_fit=given,
    )
    tilt_warnings = check_conventions(
        convention, options.sensor_sign, options.base_mount, options.allow_tilt
    )
    # the check's two-step fit of ``poses`` (without a mount): the linear answer and ml's start
    linear = convention.linear_fit if options.estimate_mount == "none" else None
    if options.method == "linear":
        static = _Static(linear, None, np.eye(3), None, None, poses)
    else:
        name = static_fit_name(samples, options)
        static = _fit_static(poses, options, drift_models, name, start=linear)
    if tilt_warnings and static.diagnostics is None:
        for message in tilt_warnings:
            logger.warning(message)
    elif tilt_warnings:  # with the fit's warnings: in the summary and the file
        added = replace(static.diagnostics, warnings=tilt_warnings)
        log_warnings(added)
        warnings = static.diagnostics.warnings + tilt_warnings
        static = replace(static, diagnostics=replace(static.diagnostics, warnings=warnings))
    if samples.times is not None:  # the bias trajectory (constant without a drift model)
        drift = static.drift or _constant_trajectory(static, {})
        span = np.array([np.min(samples.times), np.max(samples.times)])
        static = replace(static, drift=replace(drift, recorded_span=span))
    result = _result(samples, options, static)
    check_explained(result)  # a fit that explains nothing is no calibration
    return result


@dataclass(frozen=True)
class _Static:
    """A fit: model, its diagnostics (None for ``linear``) and covariance, mount, the poses fitted
    (after any dropped outliers) and the bias trajectory.
    """

    model: SensorModel
    diagnostics: FitDiagnostics | None
    mount: np.ndarray
    mount_covariance: np.ndarray | None
    covariance: np.ndarray | None
    poses: PoseAverages
    drift: BiasDrift | None = None


def static_fit_name(samples: Samples, options) -> str:
    """How warnings name a static fit: ``"the static fit from joints"`` (or ``"from rotations"``),
    ``" with the mount (yaw)"`` added when the mount is estimated."""
    source = "joints" if samples.joint_positions is not None else "rotations"
    mount = str(getattr(options.estimate_mount, "value", options.estimate_mount))
    return f"the static fit from {source}" + (
        f" with the mount ({mount})" if mount != "none" else ""
    )


def _fit_static(
    poses: PoseAverages,
    options: CalibrationOptions,
    drift_models,
    fit_name="the static fit",
    start: SensorModel | None = None,
) -> _Static:
    """The ``ml`` fit with a constant bias (and any mount), refitted without outliers if asked,
    then with the best of the ``drift_models`` (:func:`_fit_drift`) if any; ``fit_name`` names
    it in the fit test (:func:`static_fit_name`); ``start``: the two-step fit of ``poses``
    (:func:`~ftkin.calibration.ml.fit_ml`'s), when at hand.
    """
    floor = options.noise_floor(poses.wrenches)
    # noise-free raw readings: repeated readings per pose, all identical
    repeated, scale = poses.counts > 1, np.maximum(np.abs(poses.wrenches).max(axis=0), 1.0)
    noise_free = bool(np.any(repeated) and np.all(poses.spread[repeated] <= 1e-12 * scale))
    mount = options.estimate_mount
    fit = fit_ml(poses, options.g, options.noise, options.loss, mount, floor, start=start)
    diagnostics, covariance = diagnose(
        fit,
        poses.pose_ids,
        log=not drift_models,
        wrenches=poses.wrenches,
        noise_free=noise_free,
        fit_name=fit_name,
    )
    if options.drop_outliers and diagnostics.outlier_pose_ids:
        keep = ~np.isin(poses.pose_ids, diagnostics.outlier_pose_ids)
        poses = poses.subset(keep)
        fit = fit_ml(poses, options.g, options.noise, options.loss, options.estimate_mount, floor)
        diagnostics, covariance = diagnose(  # the outliers dropped, said in the diagnostics
            fit,
            poses.pose_ids,
            diagnostics.outlier_pose_ids,
            wrenches=poses.wrenches,
            noise_free=noise_free,
            fit_name=fit_name,
        )
    mount_covariance = fit.mount_covariance
    if mount_covariance is not None:  # the same goodness-of-fit scaling as θ
        mount_covariance = mount_covariance * diagnostics.covariance_scale
        sigma = np.rad2deg(np.sqrt(np.clip(np.diag(mount_covariance), 0.0, None)))
        weak = [
            f"{name} ± {value:.2g}°"
            for name, value in zip(MOUNT_NAMES[options.estimate_mount], sigma)
            if value > MOUNT_STD_WARNING_DEG
        ]
        if weak:
            message = (
                f"the mount is poorly determined ({', '.join(weak)}): "
                f"{POSES_NEEDED[options.estimate_mount]}"
            )
            logger.warning(message)
            diagnostics = replace(diagnostics, warnings=diagnostics.warnings + (message,))
    static = _Static(
        fit.model, diagnostics, fit.mount_rotation, mount_covariance, covariance, poses
    )
    if not drift_models:
        return static
    return _fit_drift(static, fit, drift_models, floor, noise_free, options, fit_name)


def _fit_drift(
    static: _Static, fit, models: tuple, floor, noise_free: bool, options, fit_name: str
) -> _Static:
    """The constant-bias fit ``static`` (by ``fit``) with the best of the drift ``models`` (or
    kept).
    """
    from .drift_fit import DriftStart, select_drift  # only a calibration that fits a drift

    poses = static.poses
    start = DriftStart(
        fit.model.to_vector(),
        np.asarray(fit.problem.channel_std),
        fit.noise_source,
        fit.noise_dof,
        floor,
        options.resolution is not None,
    )
    drift_fit, criteria, notes = select_drift(models, poses, start)
    if drift_fit is None:
        log_warnings(static.diagnostics)
        static = replace(static, drift=_constant_trajectory(static, criteria))
    else:
        diagnostics, covariance = diagnose(
            drift_fit,
            poses.pose_ids,
            parameter_count=drift_fit.parameter_count,
            wrenches=poses.wrenches,
            noise_free=noise_free,
            fit_name=f"{fit_name} with the {drift_fit.drift.model} drift",
        )
        static = replace(
            static,
            model=SensorModel.from_vector(drift_fit.model.to_vector(), options.g),
            diagnostics=diagnostics,
            covariance=covariance,
            drift=drift_fit.drift,
        )
    diagnostics = static.diagnostics
    return replace(static, diagnostics=replace(diagnostics, warnings=diagnostics.warnings + notes))


def _constant_trajectory(static: _Static, criteria: dict) -> BiasDrift:
    """The constant bias as a :class:`BiasDrift` (``"none"``), for samples that had times."""
    times = np.sort(static.poses.times)
    covariance = static.covariance
    std = np.zeros(6) if covariance is None else np.sqrt(np.diag(covariance)[3:9])
    return BiasDrift(
        "none",
        "auto" if criteria else "given",
        times,
        np.tile(static.model.bias, (len(times), 1)),
        np.tile(std, (len(times), 1)),
        criteria=criteria,
    )


def _result(samples: Samples, options: CalibrationOptions, static: _Static) -> CalibrationResult:
    model, trajectory = static.model, static.drift
    poses, rotations = static.poses, static.poses.rotations @ static.mount.T
    constant = trajectory is None or trajectory.model == "none"
    bias = model.bias if constant else trajectory.bias_at(poses.times)
    return CalibrationResult(
        force_offset=model.force_offset,
        torque_offset=model.torque_offset,
        gravity_in_base=model.gravity_in_base,
        center_of_mass=model.center_of_mass,
        g=options.g,
        method=options.method,
        pose_ids=poses.pose_ids,
        pose_wrenches=poses.wrenches,
        residuals=poses.wrenches - model.tool_gravity_wrench(rotations) - bias,
        sample_count=int(np.sum(poses.counts)),
        urdf=samples.urdf,
        sensor_frame=samples.sensor_frame,
        kinematics=samples.kinematics,
        covariance=static.covariance,
        diagnostics=static.diagnostics,
        fit_test=None if static.diagnostics is None else static.diagnostics.fit_test,
        mount_rotation=static.mount,
        mount_mode=options.estimate_mount,
        mount_covariance=static.mount_covariance,
        sensor_sign=options.sensor_sign,
        flip_axis=options.flip_axis,
        drift=trajectory,
    )
