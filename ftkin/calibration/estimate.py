"""Static calibration of a wrist F/T sensor: :func:`calibrate` and its result.

From readings at several static poses, estimate the sensor bias (``F0``,
``M0``), the tool's weight vector in the base frame (``a``, which carries the
base tilt ``U``, ``V``) and the tool's centre of mass ``P`` in the sensor frame.
"""

from __future__ import annotations

import logging
from dataclasses import replace

import numpy as np

from ..exceptions import InvalidInput, InvalidSamples
from ..validation import as_positive
from .conventions import check_conventions, detect_sign_and_handedness, reading_signs
from .diagnostics import FitDiagnostics
from .drift import BiasDrift, parse_drift
from .drift_select import fit_drift
from .fit_quality import diagnose, log_warnings
from .information import SensorNoise
from .linear import fit_linear
from .ml import LOSSES, fit_ml
from .model import STANDARD_GRAVITY, SensorModel
from .mount import MOUNT_NAMES, POSES_NEEDED, check_mount_mode
from .result import CalibrationResult
from .samples import PoseAverages, Samples, check_one_visit_per_pose

logger = logging.getLogger(__name__)

MOUNT_STD_WARNING_DEG = 1.0
"""Standard error [deg] of a mount angle above which the calibration warns."""

METHODS = ("ml", "linear")
"""Estimators :func:`calibrate` accepts; the first is the default."""


def _with_mount_warning(
    diagnostics: FitDiagnostics, mode: str, covariance: np.ndarray
) -> FitDiagnostics:
    """Add a warning for mount angles with a standard error above :data:`MOUNT_STD_WARNING_DEG`."""
    sigma = np.rad2deg(np.sqrt(np.clip(np.diag(covariance), 0.0, None)))
    weak = [
        f"{name} ± {value:.2g}°"
        for name, value in zip(MOUNT_NAMES[mode], sigma)
        if value > MOUNT_STD_WARNING_DEG
    ]
    if not weak:
        return diagnostics
    message = f"the mount is poorly determined ({', '.join(weak)}): {POSES_NEEDED[mode]}"
    logger.warning(message)
    return replace(diagnostics, warnings=diagnostics.warnings + (message,))


def _subset(poses: PoseAverages, keep: np.ndarray) -> PoseAverages:
    times = poses.times[keep] if poses.times is not None else None
    return PoseAverages(
        poses.pose_ids[keep],
        poses.rotations[keep],
        poses.wrenches[keep],
        poses.counts[keep],
        poses.spread[keep],
        times,
    )


def calibrate(
    samples: Samples,
    *,
    method: str = "ml",
    g: float = STANDARD_GRAVITY,
    noise: SensorNoise | None = None,
    loss: str = "linear",
    drop_outliers: bool = False,
    estimate_mount: str = "none",
    sensor_sign: int = 1,
    flip_axis: str | None = None,
    base_mount: str = "floor",
    expected_gravity=None,
    drift: str = "auto",
) -> CalibrationResult:
    """Estimate bias, tool gravity and base tilt from static-pose readings.

    Args:
        samples: Raw readings with sensor orientations (see :class:`Samples`);
            readings sharing a pose id are averaged first.
        method: ``"ml"`` (default): joint maximum-likelihood fit of all six
            channels with standard errors and diagnostics (:mod:`ftkin.calibration.ml`);
            ``"linear"``: the paper's two-step least squares.
        g: Gravity used to report the tool mass [m/s²] (the paper used 9.8).
        noise: ``ml`` only: noise of one raw reading [N, N·m]. None estimates
            it from the spread of repeated readings per pose, else from the
            residuals.
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
        base_mount: ``"floor"`` (default: gravity along base −z),
            ``"ceiling"`` (+z) or ``"wall"`` (no direction check).
        expected_gravity: Expected gravity direction [base frame]; overrides ``base_mount``.
        drift: How the bias may change with time when the samples carry
            times (:mod:`ftkin.calibration.drift`): ``"auto"`` (default: the
            model the information criterion prefers; the constant bias without
            times, with ``method="linear"``, a robust loss or ``drop_outliers``),
            ``"none"`` (constant), ``"poly:N"`` or ``"random-walk"`` (these two
            need times and the plain ``ml`` fit).

    Returns:
        A frozen :class:`CalibrationResult`.

    Raises:
        UnobservableParameters: the poses cannot determine the parameters
            (fewer than three, orientations alike, gravity along one sensor
            direction); the error names them.
        InvalidInput: unknown method, loss or drift model, bad ``g`` or
            ``noise``, ml options with ``method="linear"``, a mount for samples
            whose rotations were given directly, a drift model without times or
            with options it does not support (a mount estimate among them).
        SuspectConvention: the data fit with an axis reversed, or the tool
            weight points more than 90° from the expected gravity direction.
    """
    if not isinstance(samples, Samples):
        raise InvalidInput(f"samples must be an ftkin.Samples, got {type(samples).__name__}")
    if method not in METHODS:
        raise InvalidInput(
            f"unknown calibration method {method!r}; expected one of {', '.join(METHODS)}"
        )
    if loss not in LOSSES:
        raise InvalidInput(f"unknown loss {loss!r}; expected one of {', '.join(LOSSES)}")
    if noise is not None and not isinstance(noise, SensorNoise):
        raise InvalidInput(f"noise must be an ftkin.SensorNoise, got {type(noise).__name__}")
    if method == "linear" and (noise is not None or loss != "linear" or drop_outliers):
        raise InvalidInput("noise, loss and drop_outliers apply to method='ml' only")
    if check_mount_mode(estimate_mount) != "none" and method != "ml":
        raise InvalidInput("estimate_mount applies to method='ml' only")
    if estimate_mount != "none" and samples.joint_positions is None:
        raise InvalidInput(
            "estimate_mount needs samples from joint angles (Samples.from_joint_positions): "
            "rotations given "
            "directly are taken as the real sensor orientation, so any mount is already in them "
            "(absorbed)"
        )
    g = as_positive(g, "g")
    drift_kind, degree = _drift_kind(drift, samples, method, loss, drop_outliers)
    if drift_kind != "none" and estimate_mount != "none":
        if drift != "auto":
            raise InvalidInput(
                f"drift={drift!r} and estimate_mount={estimate_mount!r} cannot be fitted together "
                "yet: "
                "estimate the mount from a short recording (drift='none'), then the drift"
            )
        drift_kind = "none"  # documented: with a mount estimate, auto keeps the constant bias
    if drift_kind != "none":
        try:
            check_one_visit_per_pose(samples)
        except InvalidSamples as error:
            if drift != "auto":
                raise
            logger.warning(
                "%s; drift='auto' keeps a constant bias", error
            )  # the user did not ask for a drift model
            drift_kind = "none"
    signs = reading_signs(sensor_sign, flip_axis)
    raw_poses = samples.pose_averages()
    poses = replace(raw_poses, wrenches=raw_poses.wrenches * signs)
    check = detect_sign_and_handedness(
        raw_poses,
        sensor_sign=sensor_sign,
        flip_axis=flip_axis,
        estimate_mount=estimate_mount,
        base_mount=base_mount,
        expected_gravity=expected_gravity,
        g=g,
    )
    check_conventions(check, sensor_sign, base_mount)
    covariance = diagnostics = mount_covariance = None
    mount = np.eye(3)
    if method == "linear":
        model = fit_linear(poses, g)
    else:
        fit = fit_ml(poses, g, noise, loss, estimate_mount)
        diagnostics, covariance = diagnose(
            fit, poses.pose_ids, log=drift_kind == "none", wrenches=poses.wrenches
        )
        if drop_outliers and diagnostics.outlier_pose_ids:
            dropped = diagnostics.outlier_pose_ids
            poses = _subset(poses, ~np.isin(poses.pose_ids, dropped))
            fit = fit_ml(poses, g, noise, loss, estimate_mount)
            diagnostics, covariance = diagnose(
                fit, poses.pose_ids, dropped, wrenches=poses.wrenches
            )
        model, mount, mount_covariance = fit.model, fit.mount_rotation, fit.mount_covariance
        if mount_covariance is not None:
            mount_covariance = (
                mount_covariance * diagnostics.covariance_scale
            )  # the same goodness-of-fit scaling as θ
            diagnostics = _with_mount_warning(diagnostics, estimate_mount, mount_covariance)
    trajectory = None
    if samples.times is not None and method == "ml" and drift_kind != "none":
        drift_fit, criteria = fit_drift(poses, fit, drift_kind, degree)
        if drift_fit is not None:
            diagnostics, covariance = diagnose(
                drift_fit,
                poses.pose_ids,
                parameter_count=drift_fit.parameter_count,
                wrenches=poses.wrenches,
            )
            model, trajectory = (
                SensorModel.from_vector(drift_fit.model.to_vector(), g),
                drift_fit.drift,
            )
        else:
            log_warnings(diagnostics)
            trajectory = _constant_trajectory(model, poses, covariance, criteria)
    elif samples.times is not None:
        trajectory = _constant_trajectory(model, poses, covariance, {})
    if trajectory is not None:
        trajectory = replace(
            trajectory, recorded_span=np.array([np.min(samples.times), np.max(samples.times)])
        )
    if trajectory is None or trajectory.model == "none":
        residuals = poses.wrenches - model.predict(poses.rotations @ mount.T)
    else:
        residuals = (
            poses.wrenches
            - model.tool_gravity_wrench(poses.rotations @ mount.T)
            - trajectory.bias_at(poses.times)
        )
    return CalibrationResult(
        force_offset=model.force_offset,
        torque_offset=model.torque_offset,
        gravity_in_base=model.gravity_in_base,
        center_of_mass=model.center_of_mass,
        g=g,
        method=method,
        pose_ids=poses.pose_ids,
        pose_wrenches=poses.wrenches,
        residuals=residuals,
        sample_count=int(np.sum(poses.counts)),
        urdf=samples.urdf,
        sensor_frame=samples.sensor_frame,
        covariance=covariance,
        diagnostics=diagnostics,
        mount_rotation=mount,
        mount_mode=estimate_mount,
        mount_covariance=mount_covariance,
        sensor_sign=sensor_sign,
        flip_axis=flip_axis,
        drift=trajectory,
    )


def _drift_kind(
    drift, samples: Samples, method: str, loss: str, drop_outliers: bool
) -> tuple[str, int]:
    """The drift model to fit: ``("none"|"auto"|"poly"|"random-walk", degree)`` after checking the
    options.
    """
    kind, degree = parse_drift(drift)
    if kind in ("none", "auto"):
        unsupported = method != "ml" or loss != "linear" or drop_outliers
        if kind == "auto" and (
            samples.times is None or unsupported or np.ptp(samples.times) <= 0.0
        ):
            return "none", 0
        return kind, degree
    if samples.times is None:
        raise InvalidInput(
            f"drift={drift!r} needs the time of each reading (Samples.times, a 't' column in the "
            "CSV)"
        )
    if method != "ml" or loss != "linear" or drop_outliers:
        raise InvalidInput(
            f"drift={drift!r} needs method='ml' with loss='linear' and no drop_outliers"
        )
    if np.ptp(samples.times) <= 0.0:
        raise InvalidInput(
            f"drift={drift!r}: all readings have the same time; a drift needs readings spread over "
            "time"
        )
    return kind, degree


def _constant_trajectory(
    model: SensorModel, poses: PoseAverages, covariance, criteria: dict
) -> BiasDrift:
    """The constant bias as a :class:`BiasDrift` (``"none"``), for samples that had times."""
    times = np.sort(poses.times)
    std = np.sqrt(np.diag(covariance)[3:9]) if covariance is not None else np.zeros(6)
    return BiasDrift(
        "none",
        "auto" if criteria else "given",
        times,
        np.tile(model.bias, (len(times), 1)),
        np.tile(std, (len(times), 1)),
        criteria=criteria,
    )
