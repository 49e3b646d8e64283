"""How :func:`~ftkin.calibration.fit_registry.calibrate` fits samples with orientations:
:class:`CalibrationOptions`, every combination checked once.

Below every fit: the static fit (:mod:`ftkin.calibration.estimate`) takes it, and the IMU's
and the fused fits (:mod:`ftkin.calibration.imu_options`,
:mod:`ftkin.calibration.fused_options`) read the settings an FK ``CalibrationOptions`` carries
over to them.
"""

import logging
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, InvalidSamples
from ..options import checked, number, option
from ..validation import as_float_array
from .conventions import BASE_MOUNTS
from .drift import check_drift_spec, drift_candidates
from .information import SensorNoise, noise_floor
from .ml import LOSSES
from .model import STANDARD_GRAVITY, check_gravity
from .mount import MountMode
from .samples import Samples, check_one_visit_per_pose

logger = logging.getLogger(__name__)

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
