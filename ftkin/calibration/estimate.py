"""Static calibration of a wrist F/T sensor: :func:`calibrate_static`, the fit
:func:`~ftkin.calibration.fit_registry.calibrate` runs for
:class:`~ftkin.calibration.samples.Samples` (its options:
:class:`~ftkin.calibration.fit_options.CalibrationOptions`).

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

import logging
from dataclasses import dataclass, fields, replace

import numpy as np

from ..exceptions import InvalidInput
from .conventions import check_conventions, detect_sign_and_handedness, reading_signs
from .diagnostics import FitDiagnostics
from .drift import BiasDrift
from .explained import check_explained
from .fit_options import CalibrationOptions
from .fit_quality import diagnose, log_warnings
from .ml import fit_ml
from .model import SensorModel
from .mount import MOUNT_NAMES, POSES_NEEDED
from .orientation_mistakes import refuse_orientation_mistakes
from .result import CalibrationResult
from .samples import PoseAverages, Samples

logger = logging.getLogger(__name__)

MOUNT_STD_WARNING_DEG = 1.0
"""Standard error [deg] of a mount angle above which the calibration warns."""


def calibrate_static(
    samples: Samples, options: CalibrationOptions | None = None, **keywords
) -> CalibrationResult:
    """Estimate bias, tool gravity and base tilt from static-pose readings: the fit
    :func:`~ftkin.calibration.fit_registry.calibrate` (``ftkin.calibrate``) runs for
    :class:`Samples`.

    Args:
        samples: Raw readings with sensor orientations (see :class:`Samples`);
            readings sharing a pose id are averaged first.
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
