"""Sign and handedness of the readings: catch a reversed sign or a reversed axis.

Vendors disagree on sign: some sensors report the load on the sensor (ftkin's
convention), others the reaction. A calibration on reaction-sign readings fits
perfectly, with the tool's weight pointing *up*; admittance control would then
move toward a contact instead of away from it. An axis can also be wired
mirrored (a left-handed sensor frame): no rotation of the model explains those
readings, but the same data with that axis reversed fit.

Two settings describe the convention, stored in the calibration file and
applied to every raw reading at calibration and at run time (the corrected
reading is ``signs · raw``, :func:`reading_signs`):

* ``sensor_sign`` (``+1`` or ``-1``): ``-1`` negates all six channels;
* ``flip_axis`` (None, ``"x"``, ``"y"`` or ``"z"``): negates that axis's force
  and torque channels.

:func:`detect_sign_and_handedness` fits the reflected alternatives (each axis
reversed) and measures the angle between the fitted weight and the expected
gravity direction; :func:`check_conventions` raises
:class:`~ftkin.exceptions.SuspectConvention` naming the cause and the fix.
"""

from dataclasses import dataclass, replace

import numpy as np

from ..exceptions import InvalidInput, SuspectConvention
from ..validation import as_vector
from .explained import MIN_EXPLAINED, explained_share
from .linear import fit_linear
from .model import STANDARD_GRAVITY, SensorModel
from .mount import MountMode, force_step_costs, mount_start
from .samples import Samples

FLIP_AXES = (None, "x", "y", "z")
"""Values of ``flip_axis``: no axis reversed, or the one reversed."""

BASE_MOUNTS = ("floor", "ceiling", "wall")
"""How the robot base is mounted; sets the expected gravity direction (wall: none)."""

MAX_GRAVITY_ANGLE_DEG = 90.0
"""Largest accepted angle [deg] between the fitted tool weight and the expected gravity
direction: beyond it the weight points away from gravity, a reversed sign or another mount.
"""

TILT_WARNING_DEG = 5.0
"""Angle [deg] between the fitted tool weight and the expected (declared or default) gravity
direction beyond which the calibration warns: a floor is rarely levelled worse than 1-2°, so
more is orientations in another frame than the base, or a kinematic model that disagrees with
the arm.
"""

TILT_REFUSAL_DEG = 15.0
"""Angle [deg] beyond which a *declared* expectation (``base_mount`` or ``expected_gravity``
given) is refused, unless ``allow_tilt`` says the base really is tilted so far.
"""

FLIP_COST_RATIO = 0.1
"""A reversed axis is named when its force residual sum of squares is below this fraction of the
assumed one's.
"""

MIN_POSES_FOR_FLIP = 6
"""Fewest poses for the reversed-axis test (fewer leave too few degrees of freedom to compare
fits).
"""


def check_sensor_sign(sensor_sign) -> int:
    """``sensor_sign`` as ``+1`` or ``-1``, else :class:`InvalidInput`."""
    if isinstance(sensor_sign, bool) or sensor_sign not in (1, -1):
        raise InvalidInput(
            f"sensor_sign must be +1 (load on the sensor) or -1 (the reaction), got {sensor_sign!r}"
        )
    return int(sensor_sign)


def check_flip_axis(flip_axis) -> str | None:
    """``flip_axis`` if it is one of :data:`FLIP_AXES`, else :class:`InvalidInput`."""
    if flip_axis not in FLIP_AXES:
        raise InvalidInput(f"flip_axis must be None, 'x', 'y' or 'z', got {flip_axis!r}")
    return flip_axis


def reading_signs(sensor_sign: int = 1, flip_axis: str | None = None) -> np.ndarray:
    """``(6,)`` factors ``±1`` that turn a raw reading into ftkin's convention (``signs · raw``)."""
    signs = np.full(6, float(check_sensor_sign(sensor_sign)))
    if check_flip_axis(flip_axis) is not None:
        signs["xyz".index(flip_axis) :: 3] *= -1.0  # its force and torque channels
    return signs


def expected_gravity_direction(
    base_mount: str | None = None, expected_gravity=None
) -> np.ndarray | None:
    """Unit vector [base frame] the tool weight should point along, or None (a wall mount without a
    direction).

    ``expected_gravity`` (any non-zero 3-vector in the base frame) overrides ``base_mount``;
    ``base_mount`` None is a floor mount nobody declared.
    """
    if base_mount is not None and base_mount not in BASE_MOUNTS:
        raise InvalidInput(
            f"base_mount must be one of {', '.join(BASE_MOUNTS)}, got {base_mount!r}"
        )
    if expected_gravity is not None:
        direction = as_vector(expected_gravity, 3, "expected_gravity")
        norm = float(np.linalg.norm(direction))
        if norm == 0.0:
            raise InvalidInput("expected_gravity must be a non-zero direction in the base frame")
        return direction / norm
    return (
        None
        if base_mount == "wall"
        else np.array([0.0, 0.0, 1.0 if base_mount == "ceiling" else -1.0])
    )


@dataclass(frozen=True)
class ConventionCheck:
    """What :func:`detect_sign_and_handedness` found.

    Attributes:
        flip_costs: Force residual sum of squares [N²] of the force step with
            each ``flip_axis`` alternative (keys None, ``"x"``, ``"y"``, ``"z"``).
        assumed_flip: The ``flip_axis`` the readings were taken with.
        best_flip: The alternative with the smallest cost.
        gravity_angle_deg: Angle [deg] between the fitted tool weight and the
            expected gravity direction (NaN when none is expected, or when the fit explains
            less than :data:`~ftkin.calibration.explained.MIN_EXPLAINED` of the readings'
            variation: a direction fitted to what it does not explain is not judged, and the
            calibration refuses such a fit itself).
        gravity_in_base: The tool weight [N, base frame] of the linear fit with the assumed
        convention.
        equivalent_flips: Other axes whose reversal the data cannot tell from
            ``best_flip`` (with a yaw mount estimated, x and y).
        estimate_mount: The mount mode the alternatives were fitted with.
        expectation_declared: The expected gravity direction was declared (``base_mount`` or
            ``expected_gravity`` given), not the default floor mount.
        expected_direction: The expected gravity direction [base frame, unit], or None.
        linear_fit: The two-step linear fit (:func:`~ftkin.calibration.linear.fit_linear`) of
            the readings with the assumed convention, at the mount's start with a mount (the
            ``ml`` fit starts from it without fitting it again).
    """

    flip_costs: dict
    assumed_flip: str | None
    best_flip: str | None
    gravity_angle_deg: float
    gravity_in_base: np.ndarray
    equivalent_flips: tuple = ()
    estimate_mount: str = "none"
    expectation_declared: bool = False
    expected_direction: np.ndarray | None = None
    linear_fit: SensorModel | None = None

    @property
    def flip_suspected(self) -> bool:
        """True when another axis reversal fits far better (:data:`FLIP_COST_RATIO`)."""
        return (
            self.best_flip != self.assumed_flip
            and self.flip_costs[self.best_flip]
            < FLIP_COST_RATIO * self.flip_costs[self.assumed_flip]
        )

    @property
    def sign_suspected(self) -> bool:
        """True when the tool weight points more than :data:`MAX_GRAVITY_ANGLE_DEG` away from the
        expected gravity.
        """
        return bool(self.gravity_angle_deg > MAX_GRAVITY_ANGLE_DEG)

    @property
    def tilt_warned(self) -> bool:
        """True when the tool weight is more than :data:`TILT_WARNING_DEG` (and at most
        :data:`MAX_GRAVITY_ANGLE_DEG`) from the expected gravity direction."""
        return bool(TILT_WARNING_DEG < self.gravity_angle_deg <= MAX_GRAVITY_ANGLE_DEG)

    @property
    def tilt_refused(self) -> bool:
        """True when the tilt is beyond :data:`TILT_REFUSAL_DEG` from a *declared* direction."""
        return bool(
            self.expectation_declared
            and TILT_REFUSAL_DEG < self.gravity_angle_deg <= MAX_GRAVITY_ANGLE_DEG
        )


def detect_sign_and_handedness(
    samples,
    *,
    sensor_sign: int = 1,
    flip_axis: str | None = None,
    estimate_mount: str = "none",
    base_mount: str | None = None,
    expected_gravity=None,
    g: float = STANDARD_GRAVITY,
    linear_fit: SensorModel | None = None,
) -> ConventionCheck:
    """Fit the reflected alternatives and compare the fitted weight with the expected gravity.

    Cheap (linear force steps only), so :func:`~ftkin.calibration.fit_registry.calibrate`
    runs it before its maximum-likelihood fit; other checks (a general
    "doctor") can call it on their own.

    Args:
        samples: :class:`~ftkin.calibration.samples.Samples` (or their
            :class:`~ftkin.calibration.samples.PoseAverages`) with the readings
            **as the sensor gave them** (no sign or flip applied).
        sensor_sign: The assumed sign (see :func:`reading_signs`).
        flip_axis: The assumed reversed axis.
        estimate_mount: ``"none"``, or a mount mode: the alternatives are then
            scored with the best yaw mount of a grid, and a reversed x axis
            cannot be told from a reversed y axis (a 180° yaw turns one into the other).
        base_mount: ``"floor"`` (gravity along base −z), ``"ceiling"`` (+z) or ``"wall"`` (no
            check); None: a floor mount, not declared (a tilt is warned, never refused).
        expected_gravity: Expected gravity direction in the base frame; overrides ``base_mount``.
        g: Gravity [m/s²] (for the linear fit's reported mass only).
        linear_fit: The two-step fit of the readings with the assumed convention, when at hand
            (``estimate_mount="none"`` only; the orientation check of
            :mod:`ftkin.calibration.orientation_mistakes` returns it); None fits it.

    Raises:
        UnobservableParameters: the poses cannot determine the tool weight at all.
    """
    poses = samples.pose_averages() if isinstance(samples, Samples) else samples
    estimate_mount = MountMode.of(estimate_mount)  # a MountMode from calibrate passes as is
    expected = expected_gravity_direction(base_mount, expected_gravity)
    # reading_signs checks sensor_sign and flip_axis before any result is formed
    alternatives = FLIP_AXES if len(poses) >= MIN_POSES_FOR_FLIP else (flip_axis,)
    force_sets = [poses.wrenches[:, :3] * reading_signs(sensor_sign, a)[:3] for a in alternatives]
    step_costs, _ = force_step_costs(poses.rotations, np.array(force_sets), estimate_mount)
    costs = {alternative: float(cost) for alternative, cost in zip(alternatives, step_costs)}
    best = min(costs, key=costs.get)
    corrected = replace(poses, wrenches=poses.wrenches * reading_signs(sensor_sign, flip_axis))
    mount = np.eye(3) if estimate_mount == "none" else mount_start(corrected, g)[0]
    if linear_fit is None or estimate_mount != "none":
        fit = fit_linear(replace(corrected, rotations=corrected.rotations @ mount.T), g)
    else:
        fit = SensorModel.from_vector(linear_fit.to_vector(), g)
    residuals = corrected.wrenches - fit.predict(corrected.rotations @ mount.T)
    # a weight fitted to readings it does not explain has no direction to judge
    explained = explained_share(corrected.wrenches, residuals) >= MIN_EXPLAINED
    gravity, angle = fit.gravity_in_base, np.nan
    if explained and expected is not None and np.linalg.norm(gravity) > 0.0:
        cosine = float(gravity @ expected / np.linalg.norm(gravity))
        angle = float(np.rad2deg(np.arccos(np.clip(cosine, -1.0, 1.0))))
    # with a yaw estimated, a reversed x axis reads as a reversed y axis turned 180° about z
    equivalent = {"x": ("y",), "y": ("x",)}.get(best, ()) if estimate_mount != "none" else ()
    declared = base_mount is not None or expected_gravity is not None
    return ConventionCheck(
        costs, flip_axis, best, angle, gravity, equivalent, estimate_mount, declared, expected, fit
    )


def check_conventions(
    check: ConventionCheck,
    sensor_sign: int = 1,
    base_mount: str | None = None,
    allow_tilt: bool = False,
) -> tuple[str, ...]:
    """Raise :class:`~ftkin.exceptions.SuspectConvention` for a suspected reversed axis or sign, or
    a tilt beyond :data:`TILT_REFUSAL_DEG` from a declared gravity direction (unless
    ``allow_tilt``); return the warning of a tilt beyond :data:`TILT_WARNING_DEG` (else ``()``).
    """
    if check.flip_suspected:
        found = (
            f"the sensor's {check.best_flip} axis reversed"
            if check.best_flip
            else "no axis reversed"
        )
        flag = f"--flip-axis {check.best_flip}" if check.best_flip else "no --flip-axis"
        if check.equivalent_flips:
            found += (
                " (or, the same readings with the mount turned 180° about z, the "
                + " or ".join(check.equivalent_flips)
                + " axis)"
            )
        raise SuspectConvention(
            f"the data fit with {found}: {flag} (flip_axis={check.best_flip!r}); force residual "
            f"{np.sqrt(check.flip_costs[check.best_flip]):.3g} N against "
            f"{np.sqrt(check.flip_costs[check.assumed_flip]):.3g} N as assumed (root sum of "
            "squares over the poses). A mirrored axis "
            "(left-handed sensor frame) fits no rotation of the model; recalibrate with that "
            "setting",
            explanations=[
                f"the sensor's {check.best_flip} axis is reversed"
                if check.best_flip
                else "no axis is reversed"
            ],
            fixes=[flag],
            flip_axis=check.best_flip,
        )
    if check.sign_suspected:
        other = "floor" if base_mount == "ceiling" else "ceiling"
        sign_fix = f"--sensor-sign {-sensor_sign}"
        if check.estimate_mount != "none" and check.assumed_flip is None:
            # −I = diag(1, 1, −1) · Rz(π): with the yaw estimated, a reversed z axis reads the same
            sign_fix += " (or, the same readings with the mount turned 180° about z, --flip-axis z)"
        raise SuspectConvention(
            "the fitted tool weight gravity_in_base = "
            f"[{', '.join(f'{value:+.3g}' for value in check.gravity_in_base)}] N points "
            f"{check.gravity_angle_deg:.0f}° away from "
            "the expected gravity direction (base -z for a floor mount, +z for a ceiling mount). "
            "Either the sensor "
            f"reports the reaction instead of the load on the sensor: recalibrate with {sign_fix} "
            f"(sensor_sign={-sensor_sign}), which negates every reading; or the robot is mounted "
            f"on the {other}: "
            f"--base-mount {other} (base_mount={other!r}), or give the expected gravity direction. "
            "Admittance "
            "control with a reversed sign moves toward a contact instead of away from it",
            explanations=[
                "the sensor reports the reaction (opposite sign)",
                f"the robot is mounted on the {other}",
            ],
            fixes=[sign_fix, f"--base-mount {other}"],
            sensor_sign=-sensor_sign,
        )
    if not check.tilt_warned:
        return ()
    text = tilt_text(check.gravity_angle_deg, check.gravity_in_base, check.expected_direction)
    if not check.expectation_declared:
        text += " (the default floor mount: base_mount and expected_gravity not given)"
    if check.tilt_refused and not allow_tilt:
        raise SuspectConvention(
            f"{text}; refused because the direction was declared (base_mount, expected_gravity): "
            f"beyond {TILT_REFUSAL_DEG:g}° from it the data contradict the declaration. "
            f"{TILT_CAUSES}. If the base really is tilted so far, say so: --allow-tilt "
            "(allow_tilt=True)",
            explanations=list(TILT_EXPLANATIONS),
            fixes=list(TILT_FIXES) + ["--allow-tilt"],
        )
    return (f"{text}. {TILT_CAUSES}",)


TILT_EXPLANATIONS = (
    "the orientations are in another frame than the robot base (a world or tool frame)",
    "the kinematic model disagrees with the arm (another robot or URDF, joint offsets, signs or "
    "order)",
    "the base really is tilted or mounted on a wall",
)
"""The likely causes of a tool weight far from the expected gravity direction, most likely first."""
TILT_FIXES = ("--robot/--urdf", "--expected-gravity GX GY GZ", "--base-mount wall")
"""The options that answer each of :data:`TILT_EXPLANATIONS`."""
TILT_CAUSES = (
    "A floor is rarely more than 1-2° off level: are the orientations in another frame than the "
    "robot base, or does the kinematic model (--robot, --urdf, joint order, offsets, signs) "
    "disagree with the arm? If the base really is tilted, give the direction of gravity in the "
    "base frame (--expected-gravity GX GY GZ, expected_gravity=) or --base-mount wall "
    "(base_mount='wall', no direction check)"
)
"""What a tilt warning or refusal advises, after the angle."""


def tilt_text(angle_deg: float, gravity_in_base, expected_direction=None) -> str:
    """One clause: the fitted weight [N, base frame], the expected direction [base frame, unit;
    None: base −z] and the angle [deg] between them."""
    direction = [0.0, 0.0, -1.0] if expected_direction is None else expected_direction
    expected = "[" + ", ".join(f"{value + 0.0:+.3g}" for value in direction) + "]"
    return (
        "the fitted tool weight gravity_in_base = "
        f"[{', '.join(f'{value:+.3g}' for value in gravity_in_base)}] N points "
        f"{angle_deg:.1f}° away from the expected gravity direction {expected} (base frame)"
    )


def as_real_sensor(samples: Samples, calibration) -> Samples:
    """``samples`` as the calibrated real sensor sees them: readings corrected, rotations mounted.

    Multiplies every reading by the calibration's ``reading_signs`` and, for
    samples read from joint angles, turns the URDF's ``R_BS`` into the real
    sensor's ``R_BS · R_Mᵀ`` (``calibration``: a
    :class:`~ftkin.calibration.result.CalibrationResult`).
    """
    mounted = samples.joint_positions is not None and calibration.has_mount
    if not mounted and np.all(calibration.reading_signs == 1.0):
        return samples
    rotations = samples.rotations @ calibration.mount_rotation.T if mounted else samples.rotations
    return replace(
        samples, wrenches=samples.wrenches * calibration.reading_signs, rotations=rotations
    )
