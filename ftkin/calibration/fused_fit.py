"""The fused static calibration: an orientation (FK or ``R_BS``) and the sensor's IMU in one fit,
and the check of the sensor's mount.

FK gives the orientation of the URDF's sensor frame at every pose; the accelerometer measures
gravity in the IMU's axes; the wrench measures the tool's weight in the real sensor's. One
maximum-likelihood fit of all nine channels per pose (:mod:`ftkin.calibration.fused_problem`)
estimates ``θ = [a, F0, M0, P]`` (``a`` the weight in the base frame: the mass and the **base
tilt**, which the accelerometer pins down), ``R_SI`` (unless given), the accelerometer's bias
``b`` (its norm ``g`` is built in: the IMU fit's sphere, the direction now given by FK) and scale
(where the poses determine it), and the mount ``R_M`` when asked (``estimate_mount``).

What the data determine, and what the fit reports:

* The accelerometer sees the IMU's orientation relative to the **URDF's** sensor frame,
  ``R_SIᵀ R_M``; the wrench sees the **real** sensor's, ``R_M``. With ``R_SI`` estimated, only
  the wrench tells ``R_M`` from ``R_SI`` (as precisely as the FK mount fit determines it: the
  tool's weight against the force noise); with ``R_SI`` given (an IMU built into the sensor,
  its datasheet rotation), the accelerometer sees ``R_M`` as well, with a precision that does
  not depend on the tool's weight (1.3-1.7× sharper with the tests' 15 N tool).
* ``imu_rotation`` is reported IMU → real sensor frame. Without ``estimate_mount`` the real
  frame is taken as the URDF's (``R_M = I``): then ``R_SI`` is the IMU in the URDF's frame, and
  a mount error shows in the wrench's residuals and in the check below.
* A mount about an axis whose horizontal part stays the same at every pose trades against the
  base tilt (and the offsets), for the accelerometer as for the wrench: such pose sets are
  refused with :class:`~ftkin.exceptions.UnobservableParameters` naming ``mount[...]`` (with
  ``estimate_mount``), and leave the check undetermined (said in the warnings) without it.

The check: whatever it reports, the fit is also made with the mount free and ``R_M`` tested
against the identity (:mod:`ftkin.calibration.mount_check`); beyond the noise and the tolerance,
a warning names the angle, the axis and the fix: "the sensor (or the IMU) is not mounted as the
URDF says". The start is closed-form: the FK fit's two steps (or its yaw grid with a mount)
give ``θ`` and ``R_M0``, the Kabsch rotation of the accelerometer's centred means against the
specific force FK predicts gives ``R_SI`` (a mirror is refused: the accelerometer or the wrench
negated), their mean difference ``b``.
"""

import logging
from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput, SuspectConvention, UnobservableParameters
from .conventions import check_conventions, detect_sign_and_handedness, reading_signs
from .covariance import covariance_in_sensor_axes
from .fused_options import FusedCalibrationOptions
from .fused_problem import POSES_NEEDED, FusedStaticProblem, check_observable
from .fused_result import FusedCalibrationResult
from .fused_samples import FusedPoseAverages, FusedSamples
from .goodness_of_fit import FitTest
from .imu_fit import (  # the IMU fit's noise estimates and solver serve any 9-channel problem
    covariance_at,
    misfit_note,
    nine_channel_fit_test,
    solve_with_noise,
    spread_dof,
    starting_noise,
    starting_scale,
)
from .imu_model import ACCEL_SCALE_NAMES
from .linear import fit_linear
from .model import gravity_in_sensor
from .mount import MOUNT_NAMES, mount_start, rotation_to_rpy
from .mount_check import MOUNT_CHECK_P, MountCheck

logger = logging.getLogger(__name__)

MAX_GIVEN_ROTATION_ERROR_DEG = 20.0
"""Largest angle [deg] between a given ``R_SI`` and the one the data imply at the start: beyond,
the given rotation is refused (transposed, or another IMU's)."""


def _kabsch(force_in_sensor: np.ndarray, accel: np.ndarray, gravity: np.ndarray) -> np.ndarray:
    """``R_SI`` best mapping the centred accelerometer means onto the centred specific force FK
    predicts (``f = R_SI (acc − b)``), det = +1.

    Raises:
        SuspectConvention: the data fit a mirror far better: the accelerometer or the wrench is
            negated (or one of their axes reversed).
    """
    centred_force = force_in_sensor - force_in_sensor.mean(axis=0)
    centred_accel = accel - accel.mean(axis=0)
    left, singular, right_t = np.linalg.svd(centred_force.T @ centred_accel)
    mirrored = np.linalg.det(left @ right_t) < 0.0
    if mirrored and singular[2] > 0.1 * singular[0]:
        up = float(gravity[2]) > 0.0  # the wrench's weight points up (a floor mount assumed)
        blamed, other = (
            ("the wrench is the reaction (sensor_sign=-1, --sensor-sign -1)", "the accelerometer")
            if up
            else ("the accelerometer reports the acceleration (−g upward at rest)", "the wrench")
        )
        raise SuspectConvention(
            "the accelerometer follows the gravity FK and the wrench predict through a mirror, "
            f"not a rotation: most likely {blamed}, with the robot on the floor; else {other} "
            "is negated or one axis of it reversed. An accelerometer at rest reads +g upward, a "
            "raw reading is the load on the sensor",
            explanations=[
                "an accelerometer at rest must read +g upward (specific force)",
                "a raw reading is the load on the sensor (a tool hanging below pulls it down)",
            ],
            fixes=["negate specific_force (ax, ay, az)", "sensor_sign=-1 (--sensor-sign -1)"],
            sensor_sign=-1 if up else None,
        )
    return left @ np.diag([1.0, 1.0, -1.0 if mirrored else 1.0]) @ right_t


def _rotation_angle_deg(first: np.ndarray, second: np.ndarray) -> float:
    cosine = np.clip((np.trace(first.T @ second) - 1.0) / 2.0, -1.0, 1.0)
    return float(np.rad2deg(np.arccos(cosine)))


def _imu_start(orientation, accel, g: float, mount0, model):
    """The specific force FK predicts (real sensor frame, ``f_i = −g R_M Rᵢᵀ â``) at the mount
    ``R_M0`` and linear fit ``model``, and the Kabsch ``R_SI`` of the accelerometer against it."""
    gravity = model.gravity_in_base
    up = -g * gravity_in_sensor(orientation.rotations, gravity / np.linalg.norm(gravity))
    force_in_sensor = up @ mount0.T
    return force_in_sensor, _kabsch(force_in_sensor, accel, gravity)


def fused_start(poses: FusedPoseAverages, g: float, mount_mode: str, imu_rotation=None):
    """The closed-form start: ``(x0 without the scale, R_M0, R_I0)`` (module docstring).

    Raises:
        UnobservableParameters: the FK fit's own refusals (fewer than three poses, orientations
            alike, gravity along one sensor direction).
        SuspectConvention: a mirrored accelerometer or wrench; a given ``R_SI`` far from the
            one the data imply, with or without a mount.
    """
    orientation, accel = poses.orientation, poses.imu.specific_force
    if mount_mode == "none":
        mount0, model = np.eye(3), fit_linear(orientation, g)
    else:
        mount0, model = mount_start(orientation, g)
    force_in_sensor, estimated = _imu_start(orientation, accel, g, mount0, model)
    rotation = estimated if imu_rotation is None else np.asarray(imu_rotation, dtype=float)
    angle = _rotation_angle_deg(estimated, rotation)
    if angle > MAX_GIVEN_ROTATION_ERROR_DEG and mount_mode == "none":
        # a sensor mounted far from the URDF's frame moves the IMU too: the check will name it
        mounted, mounted_model = mount_start(orientation, g)
        turned = _imu_start(orientation, accel, g, mounted, mounted_model)[1]
        angle = _rotation_angle_deg(turned, rotation)
    if angle > MAX_GIVEN_ROTATION_ERROR_DEG:
        rpy = ", ".join(f"{v:+.1f}" for v in np.rad2deg(rotation_to_rpy(estimated)))
        raise SuspectConvention(
            f"the given imu_rotation is {angle:.1f}° from the rotation the accelerometer and the "
            f"orientations imply (rpy [{rpy}]°), with the sensor mounted as the URDF says or "
            "turned on the flange: is it R_SI (IMU → sensor frame) and not its transpose, and "
            "this sensor's IMU?",
            fixes=["pass R_SI (IMU → sensor), not R_IS", "imu_rotation=None (estimate it)"],
        )
    bias = np.mean(accel - force_in_sensor @ rotation, axis=0)  # acc = R_SIᵀ f + b
    x0 = np.concatenate(
        [model.to_vector(), np.zeros(len(MOUNT_NAMES[mount_mode]))]
        + ([np.zeros(3)] if imu_rotation is None else [])
        + [bias]
    )
    return x0, mount0, rotation


@dataclass(frozen=True)
class FusedStaticFit:
    """What :func:`fit_fused_static` found.

    Attributes:
        problem: The final problem (recentred: ``δ_M = δ_I = 0`` at ``x``).
        x: The parameters at the solution.
        covariance: ``(n, n)`` covariance of every parameter (rotation increments on the right).
        noise_source: ``"given"``, ``"spread"`` or ``"residuals"``.
        notes: What the fit decided on its own (a scale left out).
        fit_test: Its goodness of fit (:class:`~ftkin.calibration.goodness_of_fit.FitTest`);
            the covariance is scaled by ``χ²/ν`` when it rejects the model.
    """

    problem: FusedStaticProblem
    x: np.ndarray
    covariance: np.ndarray
    noise_source: str
    notes: tuple[str, ...]
    fit_test: FitTest | None = None


def fit_fused_static(
    poses: FusedPoseAverages, g: float, options: FusedCalibrationOptions, mount_mode: str
) -> FusedStaticFit:
    """The joint maximum-likelihood fit (module docstring) with the mount ``mount_mode``.

    Raises:
        UnobservableParameters: the poses leave a parameter open (named).
        SuspectConvention: a mirrored accelerometer or wrench, a given ``R_SI`` far off.
    """
    imu = options.imu
    notes = []
    scale_free = starting_scale(imu, len(poses), notes)
    noise, source, from_residuals = starting_noise(poses.imu, imu, g)

    while True:  # at the start, then at the solution: a scale the poses leave open is dropped
        x0, mount0, rotation0 = fused_start(poses, g, mount_mode, imu.imu_rotation)
        problem = FusedStaticProblem(
            poses.orientation.rotations,
            poses.imu.specific_force,
            poses.orientation.wrenches,
            np.asarray(poses.orientation.counts, dtype=float),
            noise,
            g,
            mount0,
            rotation0,
            mount_mode,
            imu.imu_rotation is None,
            scale_free,
            poses.imu.accel_count_factor,
        )
        x0 = np.concatenate([x0, np.zeros(len(scale_free))])
        solved = solve_with_noise(problem, x0, source, from_residuals, imu, notes, check_observable)
        if solved is None:  # a scale the poses leave open: dropped, and the fit started again
            scale_free = tuple(k for k in scale_free if ACCEL_SCALE_NAMES[k] not in notes[-1])
            continue
        problem, x = solved
        break
    covariance = covariance_at(problem, x, len(x), POSES_NEEDED)
    test, factor = nine_channel_fit_test(
        "the fused fit (orientation and IMU)",
        problem,
        x,
        source,
        spread_dof(poses.imu),
        poses.orientation.pose_ids,
    )
    return FusedStaticFit(problem, x, covariance * factor, source, tuple(notes), test)


def _pose_angles_deg(fit: FusedStaticFit) -> np.ndarray:
    """Per pose: the angle [deg] between the upward direction the orientation predicts in its
    sensor frame and the one the accelerometer measures (through the fit's ``R_SI``, ``b``,
    ``s``)."""
    problem, p = fit.problem, fit.problem.unpack(fit.x)
    measured = ((problem.accel - p["b"]) / (1.0 + p["s"])) @ problem.imu_rotation(fit.x).T
    gravity = p["theta"][0:3]
    predicted = -gravity_in_sensor(problem.rotations, gravity / np.linalg.norm(gravity))
    cosine = np.einsum("ij,ij->i", measured / np.linalg.norm(measured, axis=1)[:, None], predicted)
    return np.rad2deg(np.arccos(np.clip(cosine, -1.0, 1.0)))


def check_mount(
    poses: FusedPoseAverages, g: float, options: FusedCalibrationOptions, fit: FusedStaticFit, frame
) -> tuple[MountCheck | None, str | None]:
    """The mount the data see with it free (``fit`` itself when it estimated the full mount),
    against the identity; or None and why (the poses cannot determine it)."""
    if fit.problem.mount_mode != "full":
        try:
            fit = fit_fused_static(poses, g, options, "full")
        except UnobservableParameters as error:
            return None, (
                f"these poses cannot check the sensor's mount against the URDF ("
                f"{', '.join(error.names)} open): {POSES_NEEDED}"
            )
    source = "accelerometer" if options.imu.imu_rotation is not None else "wrench"
    check = MountCheck.from_increment_covariance(
        fit.problem.mount0,
        fit.covariance[12:15, 12:15],
        _pose_angles_deg(fit),
        source,
        options.mount_tolerance_deg,
        frame,
    )
    return check, None


def calibrate_fused(samples: FusedSamples, options=None, **keywords) -> FusedCalibrationResult:
    """Calibrate from static poses with both an orientation and the sensor's IMU.

    Args:
        samples: :class:`~ftkin.calibration.fused_samples.FusedSamples`
            (``FusedSamples.from_arrays(samples, specific_force)``); readings sharing a
            pose id are averaged first. Static poses: the bias is constant (no drift model) and
            the gyro, if any, is not used.
        options: A :class:`~ftkin.calibration.fused_options.FusedCalibrationOptions` (an
            ``ImuCalibrationOptions`` or a default-like FK ``CalibrationOptions`` are taken too).
        **keywords: Fields of either (``estimate_mount="full"``, ``imu_rotation=R_SI``, ...).

    Returns:
        A frozen :class:`~ftkin.calibration.fused_result.FusedCalibrationResult`; its
        :attr:`~ftkin.calibration.fused_result.FusedCalibrationResult.mount_check` holds the
        mount the IMU and the wrench see, and a mount beyond the noise is logged as a warning
        (and kept in ``warnings``).

    Raises:
        UnobservableParameters: the poses leave a parameter open (named).
        SuspectConvention: a mirrored accelerometer or wrench, a reversed axis, a given
            ``R_SI`` far from the data's.
        InvalidInput: an unknown option, a mount estimate for rotations given directly, a
            ``g`` other than the samples'.
    """
    if not isinstance(samples, FusedSamples):
        raise InvalidInput(
            "samples must be ftkin FusedSamples (FusedSamples.from_arrays), got "
            f"{type(samples).__name__}"
        )
    given_g = keywords.pop("g", getattr(options, "g", samples.g))
    if not np.isclose(float(given_g), samples.g, rtol=1e-12):
        raise InvalidInput(
            f"g = {given_g} m/s² differs from the samples' {samples.g:g} m/s²: give it once, to "
            "FusedSamples.from_arrays(..., g=...)"
        )
    options = FusedCalibrationOptions.from_keywords(options, **keywords)
    if options.estimate_mount != "none" and samples.joint_positions is None:
        raise InvalidInput(
            "estimate_mount needs samples from joint angles (Samples.from_joint_positions): "
            "rotations given directly are taken as the real sensor orientation (the fused fit "
            "still checks them against the IMU and the wrench)"
        )
    g = samples.g
    raw = samples.pose_averages()
    check_conventions(
        detect_sign_and_handedness(
            raw.orientation,
            sensor_sign=options.sensor_sign,
            flip_axis=options.flip_axis,
            estimate_mount=options.estimate_mount,
            base_mount="wall",  # the accelerometer checks the direction (a mirror is refused)
            g=g,
        ),
        options.sensor_sign,
        "wall",
    )
    signs = reading_signs(options.sensor_sign, options.flip_axis)
    poses = FusedPoseAverages(
        replace(raw.orientation, wrenches=raw.orientation.wrenches * signs),
        replace(raw.imu, wrenches=raw.imu.wrenches * signs),
    )
    fit = fit_fused_static(poses, g, options, options.estimate_mount)
    check, undetermined = check_mount(poses, g, options, fit, samples.samples.sensor_frame)
    warnings = list(fit.notes)
    if undetermined is not None:
        warnings.append(undetermined)
    elif check.significant:
        warnings.append(check.message(estimated=options.estimate_mount != "none"))
    test = fit.fit_test
    if not test.fits:  # after the mount's warning, which names a likely cause
        note = misfit_note(test, test.chi_square / test.dof)
        if check is not None and check.p_value < MOUNT_CHECK_P and not check.significant:
            note += (
                f" (the mount check sees the sensor turned {check.angle_deg:.3g}° from the "
                "orientation's frame, within mount_tolerance_deg: that turn alone makes such "
                "a misfit; "
                + (
                    "estimate_mount='yaw' or 'full' (--estimate-mount) fits it)"
                    if samples.samples.joint_positions is not None
                    else "correct the rotations' source)"
                )
            )
        warnings.append(note)
    for message in warnings:
        logger.warning("%s", message)
    return _result(samples, options, fit, check, warnings)


def _result(samples, options, fit: FusedStaticFit, check, warnings) -> FusedCalibrationResult:
    problem, x = fit.problem, fit.x
    p = problem.unpack(x)
    theta, k = p["theta"], problem.mount_count
    estimated = problem.mount_mode != "none"
    return FusedCalibrationResult(
        force_offset=theta[3:6],
        torque_offset=theta[6:9],
        gravity_in_base=theta[0:3],
        center_of_mass=theta[9:12],
        g=problem.g,
        method="fused",
        pose_ids=samples.samples.pose_averages().pose_ids,
        pose_wrenches=problem.wrenches,
        residuals=problem.residuals(x)[:, 3:9],
        sample_count=len(samples),
        urdf=samples.samples.urdf,
        sensor_frame=samples.samples.sensor_frame,
        kinematics=samples.samples.kinematics,
        covariance=fit.covariance[:12, :12],
        mount_rotation=problem.mount0 if estimated else np.eye(3),
        mount_mode=problem.mount_mode,
        mount_covariance=fit.covariance[12 : 12 + k, 12 : 12 + k] if estimated else None,
        sensor_sign=options.sensor_sign,
        flip_axis=options.flip_axis,
        imu_rotation=problem.imu_rotation0,
        accel_bias=p["b"],
        accel_scale=p["s"],
        scale_estimated=tuple(axis in problem.scale_free for axis in range(3)),
        imu_position=options.imu.imu_position,
        imu_position_source=None if options.imu.imu_position is None else "given",
        parameter_names=problem.names,
        parameter_covariance=covariance_in_sensor_axes(  # R_SI's increment, as the IMU fit's
            fit.covariance,
            problem.imu_rotation0,
            12 + k if problem.imu_rotation_free else None,
        ),
        accel_std=problem.noise[0:3],
        fit_test=fit.fit_test,
        imu_warnings=tuple(warnings),
        mount_check=check,
    )
