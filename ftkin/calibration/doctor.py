"""Convention mistakes diagnosed instead of fitted: refit the data under the common mistakes.

A data set read with the wrong convention (Euler angles in radians, a
quaternion in x,y,z,w order, the wrench in the base frame, ...) still gives a
fit; only a poor one, or an implausible one. :func:`diagnose_readings` fits
the data as given and under each alternative reading with the closed-form
linear estimator (:func:`~ftkin.calibration.linear.fit_linear`, milliseconds
each), and names the alternative that explains the data:

* **fit**: the residual chi-square of every reading is computed with one
  per-channel noise level, that of the best-fitting reading; an alternative
  whose chi-square is at least :data:`MISTAKE_RATIO` times smaller than the
  given reading's is the mistake, between :data:`SUSPECT_RATIO` and that a
  suspicion (warned, not refused). Residuals of a reading in other units are
  converted back to the given units first, so a change of unit alone never
  looks like a better fit.
* **explained variation**: a reading is only named when its fit explains at
  least :data:`EXPLAINED` of the variation across poses (pure noise is never
  "explained" by some convention).
* **plausibility** (readings that fit exactly as well, by construction): a
  centre of mass metres away that becomes millimetres when the torques are
  read as N·mm (a doubt only, said as such, when the header declares the torques' unit: what
  the file declares wins); a tool that weighs nothing as given but the expected weight
  when the wrench is read in the sensor frame; gravity pointing up that points
  down when the readings are negated (the sensor reports the reaction, or the
  arm hangs from a ceiling: a suspicion only).

The readings themselves are built by the caller (:mod:`ftkin.io.table_readings`
builds them from a samples table); :func:`wrench_readings` adds the
alternatives that only change the wrench.
"""

from dataclasses import dataclass, field, replace

import numpy as np

from ..exceptions import UnobservableParameters
from ..kinematics.rotations import wrenches_base_to_sensor
from .conventions import (
    MAX_GRAVITY_ANGLE_DEG,
    TILT_CAUSES,
    TILT_WARNING_DEG,
    reading_signs,
    tilt_text,
)
from .linear import fit_linear, two_step
from .model import STANDARD_GRAVITY, WRENCH_CHANNELS, SensorModel, predict
from .observability import MIN_POSES
from .samples import PoseAverages, Samples

MISTAKE_RATIO = 20.0
"""Chi-square ratio (given / alternative) from which the alternative is named as the mistake."""
SUSPECT_RATIO = 4.0
"""Chi-square ratio from which the alternative is a suspicion (a warning)."""
EXPLAINED = (0.5, 0.8)
"""Share of the variation a reading must explain to be a suspicion, and to be named as the
mistake.
"""
MISFIT_RATIO = 30.0
"""Pose residuals (RMS) over the noise of a pose mean beyond which, when the data as given also
explain less than ``EXPLAINED[1]`` of the variation, the doctor is suspicious of them."""
COLUMN_MIX_UPS = {
    "force and torque columns swapped": (3, 4, 5, 0, 1, 2),
    "the columns in the order fx,mx,fy,my,fz,mz": (0, 2, 4, 1, 3, 5),
    "the header in the order fx,mx,fy,my,fz,mz": (0, 3, 1, 4, 2, 5),
}
"""Column mix-ups tried: ``{reading: the given channel each true channel fx..mz is in}`` (the
columns in that order under a header fx..mz; the header in that order over columns fx..mz)."""
FAR_COM = (0.5, 2.0)
"""Centre-of-mass distance [m]: beyond the first a suspicion, beyond the second implausible."""


@dataclass(frozen=True)
class Reading:
    """One way to read a data set.

    Attributes:
        name: What this reading assumes, e.g. ``"Euler angles in radians"`` (``"as given"`` for the
        data as read).
        fix: What the user should change when this reading is the right one.
        poses: The pose-averaged readings under this assumption, or None when they cannot be formed.
        unit_scale: ``(6,)`` factors that turn this reading's wrench units into the given ones.
        failure: Why the readings could not be formed, when ``poses`` is None.
        channels: ``(6,)`` the given channel each of this reading's channels was read from (a
            reading that mixes up the columns); residuals are compared in the given channels.
    """

    name: str
    fix: str
    poses: PoseAverages | None
    unit_scale: np.ndarray = field(default_factory=lambda: np.ones(6))
    failure: str | None = None
    channels: tuple[int, ...] = (0, 1, 2, 3, 4, 5)


@dataclass(frozen=True)
class ReadingFit:
    """The linear fit of one reading: model, residual sum of squares per channel (given units), or
    why it failed.

    ``explained`` is the share of the variation across poses that the fit explains, the smaller of
    the
    force and the torque channels' (1: all of it; a reading that explains little is never named).
    """

    reading: Reading
    model: SensorModel | None
    rss: np.ndarray | None
    chi_square: float = np.inf
    failure: str | None = None
    explained: float = 0.0


@dataclass(frozen=True)
class ConventionReport:
    """What the data say about the convention they were written in.

    Attributes:
        fits: One per reading; the first is the data as given.
        verdict: ``"ok"``, ``"suspect"`` (warn), ``"mistake"`` (refuse), or ``"undetermined"`` (the
        data
            cannot be fitted under any reading, e.g. too few poses: the fit itself says why).
        culprit: The alternative that explains the data, when the verdict is not ok.
        reason: One sentence of evidence for the verdict.
        by_fit: The culprit fits better than the data as given (by the chi-square); False when
            it only makes the result plausible, fitting no better (a unit, a sign).
        tilted: The suspicion is the tool weight's direction alone: more than
            :data:`~ftkin.calibration.conventions.TILT_WARNING_DEG` from base −z (the floor mount
            the doctor assumes), which ``calibrate`` warns of itself.
    """

    fits: tuple[ReadingFit, ...]
    verdict: str
    culprit: ReadingFit | None
    reason: str
    by_fit: bool = True
    tilted: bool = False

    @property
    def message(self) -> str:
        """The sentence an error or warning prints: the reading that fits and the fix."""
        if self.culprit is None:
            return "the data fit as given" if self.verdict == "ok" else self.reason
        if not self.by_fit:  # plausible, fitting no better: say so, not "it fits"
            return (
                f"the data are plausible only when read with {self.culprit.reading.name}, which "
                f"fits them no better than as given ({self.reason}): {self.culprit.reading.fix}"
            )
        return (
            f"the data fit when read with {self.culprit.reading.name} ({self.reason}): "
            f"{self.culprit.reading.fix}"
        )

    def table(self) -> str:
        """Every reading with its chi-square relative to the best, tool weight and centre of mass
        distance.
        """
        finite = [fit.chi_square for fit in self.fits if np.isfinite(fit.chi_square)]
        best = max(min(finite), 1e-300) if finite else 1.0
        lines = [
            f"  {'reading':<46}{'chi² / best':>12}{'G [N]':>10}{'|P| [m]':>10}{'gravity z':>11}"
        ]
        for fit in self.fits:
            if fit.model is None:
                lines.append(
                    f"  {fit.reading.name:<46}{'-':>12}  {fit.failure or fit.reading.failure}"
                )
            else:
                lines.append(
                    "  "
                    f"{fit.reading.name:<46}{fit.chi_square / best:>12.3g}"
                    f"{fit.model.tool_weight:>10.4g}{np.linalg.norm(fit.model.center_of_mass):>10.4g}"
                    f"{'up' if fit.model.gravity_in_base[2] > 0 else 'down':>11}"
                )
        return "\n".join(lines)


def wrench_readings(given: Samples | PoseAverages, joints: bool = True) -> list[Reading]:
    """Alternatives that change only the wrench: base frame, reaction, N·mm, columns mixed up,
    the sensor turned, one axis reversed.

    ``joints``: the orientations come from joint angles (a turned sensor is then fixed by
    estimating the mount; given directly, by turning the readings).
    """
    poses = given.pose_averages() if isinstance(given, Samples) else given
    wrenches = poses.wrenches
    out = [
        Reading(
            "the wrench in the base frame",
            "give the wrench in the sensor frame (rotate it by R_BS^T)",
            replace(poses, wrenches=wrenches_base_to_sensor(poses.rotations, wrenches)),
        ),
        Reading(
            "the readings negated (the reaction)",
            "calibrate with --sensor-sign -1 (the sensor reports the reaction, not the "
            "load), or with --base-mount ceiling if the robot hangs from a ceiling",
            replace(poses, wrenches=-wrenches),
        ),
        Reading(
            "torques in N·mm",
            "give the torques in N·m (divide mx, my, mz by 1000) or declare their unit in the "
            "header (mx [N·mm], my [N·mm], mz [N·mm]); if they are in N·m and the centre of mass "
            "is that far, declare that instead (mx [N·m], ...)",
            replace(poses, wrenches=wrenches * [1, 1, 1, 1e-3, 1e-3, 1e-3]),
            np.array([1, 1, 1, 1e3, 1e3, 1e3], dtype=float),
        ),
    ]
    for name, channels in COLUMN_MIX_UPS.items():  # the columns hold other channels
        held = ", ".join(
            f"{WRENCH_CHANNELS[given]} holds {WRENCH_CHANNELS[true]}"
            for true, given in enumerate(channels)
            if given != true
        )
        out.append(
            Reading(
                name,
                f"the columns hold other channels than their names: rename them in the header "
                f"(the column named {held})",
                replace(poses, wrenches=wrenches[:, list(channels)]),
                channels=channels,
            )
        )
    for axis in "xyz":  # a proper turn: the two other axes' forces and torques negated
        signs = np.array([-1.0 if a != axis else 1.0 for a in "xyz"] * 2)
        others = ", ".join(f"{kind}{a}" for kind in "fm" for a in "xyz" if a != axis)
        fix = (
            f"the sensor is mounted turned 180° about {axis} against the sensor frame the "
            f"URDF (or --sensor-offset) gives: correct that frame, or estimate the mount "
            f"(--estimate-mount {'yaw' if axis == 'z' else 'full'})"
            if joints
            else f"the orientations are of a frame turned 180° about {axis} against the "
            f"sensor's: negate the columns {others} (the readings turned into that frame), or "
            f"give the sensor's own orientation"
        )
        out.append(
            Reading(
                f"the sensor turned 180° about its {axis} axis",
                fix,
                replace(poses, wrenches=wrenches * signs),
            )
        )
    for axis in "xyz":
        others = [a for a in "xyz" if a != axis]
        out.append(
            Reading(
                f"the sensor's {axis} axis reversed",
                f"calibrate with --flip-axis {axis} (flip_axis={axis!r}: negates f{axis} and "
                f"m{axis}; a true mirror image negates f{axis}, m{others[0]} and m{others[1]} "
                "instead: static data cannot tell "
                "the two apart, they differ in the sign of the centre of mass)",
                # a mirror image: the axis reversed (its force and torque), every torque negated
                replace(poses, wrenches=wrenches * reading_signs(1, axis) * [1, 1, 1, -1, -1, -1]),
            )
        )
    return out


def fit_reading(reading: Reading, g: float = STANDARD_GRAVITY) -> ReadingFit:
    """The paper's two-step linear fit (:func:`~ftkin.calibration.linear.fit_linear`) of one
    reading, with its residual sum of squares per channel in the given units; a pose set that
    cannot determine the parameters fails that reading.
    """
    poses = reading.poses
    if poses is None:
        return ReadingFit(reading, None, None, failure=reading.failure)
    if len(poses) < MIN_POSES:
        return ReadingFit(reading, None, None, failure=f"fewer than {MIN_POSES} poses")
    try:
        model = fit_linear(poses, g)
    except UnobservableParameters as error:
        what = "centre of mass" if "center_of_mass" in error.names else "tool's weight"
        return ReadingFit(reading, None, None, failure=f"the poses cannot determine the {what}")
    measured = poses.wrenches
    residuals = (measured - predict(poses.rotations, model.to_vector())) * reading.unit_scale
    if not np.all(np.isfinite(residuals)):
        return ReadingFit(reading, None, None, failure="non-finite residuals")
    rss = _rss(reading, residuals)
    spread = np.sum(((measured - measured.mean(axis=0)) * reading.unit_scale) ** 2, axis=0)
    explained = min(
        1.0 - rss[part].sum() / max(spread[part].sum(), 1e-300) for part in (slice(3), slice(3, 6))
    )
    return ReadingFit(reading, model, rss, explained=float(explained))


def _rss(reading: Reading, residuals: np.ndarray) -> np.ndarray:
    """``(6,)`` residual sums of squares of ``reading``'s ``residuals`` ``(N, 6)`` (given units),
    in the given channels."""
    rss = np.empty(6)
    rss[list(reading.channels)] = np.sum(residuals**2, axis=0)  # in the given channels
    return rss


def unchecked_rss(reading: Reading) -> np.ndarray | None:
    """The :attr:`ReadingFit.rss` :func:`fit_reading` gives ``reading`` when it fits it, from
    the two-step fit without the observability checks (:func:`~ftkin.calibration.linear.two_step`);
    None when its poses could not be formed or are too few. A reading the checks would fail gets
    a number all the same (possibly NaN): only for a bound that such a reading cannot
    tighten (:func:`~ftkin.calibration.orientation_mistakes.cannot_name_a_mistake`).
    """
    poses = reading.poses
    if poses is None or len(poses) < MIN_POSES:
        return None
    predicted = predict(poses.rotations, two_step(poses.rotations, poses.wrenches))
    return _rss(reading, (poses.wrenches - predicted) * reading.unit_scale)


def diagnose_readings(
    readings: list[Reading], declared_torque_unit: str | None = None
) -> ConventionReport:
    """Fit every reading (the first is the data as given) and name the one that explains the data.

    ``declared_torque_unit``: the torques' unit as the file's header declares it (``"N·m"``),
    None when it declares none; a declared unit is doubted aloud, never overridden. See the
    module docstring for the rules.
    """
    fits = [fit_reading(reading) for reading in readings]
    valid = [fit for fit in fits if fit.rss is not None]
    if not valid:
        return ConventionReport(
            tuple(fits),
            "undetermined",
            None,
            "no reading could be fitted: " + (fits[0].failure or "?"),
        )
    channel_dof = max(len(valid[0].reading.poses) - 2, 1)
    scale = max(
        float(np.max(np.abs(valid[0].reading.poses.wrenches * valid[0].reading.unit_scale))), 1e-12
    )
    floor = (1e-9 * scale) ** 2
    # the best reading by a scale-free measure sets the per-channel noise of all
    best = min(valid, key=lambda fit: float(np.sum(np.log(fit.rss / channel_dof + floor))))
    variance = best.rss / channel_dof + floor
    return _verdict(
        tuple(
            fit if fit.rss is None else replace(fit, chi_square=float(np.sum(fit.rss / variance)))
            for fit in fits
        ),
        declared_torque_unit,
    )


def _verdict(fits: tuple[ReadingFit, ...], declared_torque_unit=None) -> ConventionReport:
    given, alternatives = fits[0], [fit for fit in fits[1:] if fit.model is not None]
    plausible = [
        fit
        for fit in alternatives
        if np.linalg.norm(fit.model.center_of_mass) < FAR_COM[0] and fit.explained >= EXPLAINED[0]
    ]
    if plausible:
        # readings that fit alike (a mirror and a turn differ by the sign of the forces, which
        # the fitted gravity absorbs): the one whose gravity points down, as on a floor
        least = min(fit.chi_square for fit in plausible)
        alike = [fit for fit in plausible if fit.chi_square <= 1.01 * least]
        best = min(alike, key=lambda fit: (fit.model.gravity_in_base[2] > 0, fit.chi_square))
        ratio = given.chi_square / max(best.chi_square, 1e-300)
        if ratio >= SUSPECT_RATIO:
            return ConventionReport(
                fits,
                "mistake"
                if ratio >= MISTAKE_RATIO and best.explained >= EXPLAINED[1]
                else "suspect",
                best,
                "the data as given cannot be fitted"
                if given.model is None
                else f"{ratio:.3g} times smaller chi-square than as given",
            )
    if given.model is None:
        return ConventionReport(
            fits, "undetermined", None, f"the data as given cannot be fitted: {given.failure}"
        )
    return _plausibility(fits, given, alternatives, declared_torque_unit)


def _plausibility(fits, given: ReadingFit, alternatives, declared_torque_unit) -> ConventionReport:
    by_name = {fit.reading.name: fit for fit in alternatives}
    distance = float(np.linalg.norm(given.model.center_of_mass))
    millimetres = by_name.get("torques in N·mm")
    far = distance >= FAR_COM[0] and given.explained >= EXPLAINED[0]
    if millimetres is not None and far and declared_torque_unit is not None:
        reason = (
            f"the header declares the torques in {declared_torque_unit}, and they are read so; "
            f"but the centre of mass is then {distance:.3g} m from the sensor ({distance:.3g} mm "
            "were the torques 1000 times smaller, in N·mm: the data fit equally well either "
            "way). If the tool does not reach that far, the declared unit is wrong: declare "
            "N·mm (mx [N·mm], ...)"
        )
        return ConventionReport(fits, "suspect", None, reason)
    if millimetres is not None and far:
        return ConventionReport(
            fits,
            "mistake" if distance >= FAR_COM[1] and given.explained >= EXPLAINED[1] else "suspect",
            millimetres,
            f"the centre of mass would be {distance:.3g} m from the sensor, {distance:.3g} mm in "
            "N·mm, and the header declares no unit",
            by_fit=False,
        )
    base = by_name.get("the wrench in the base frame")
    if (
        base is not None
        and given.model.tool_weight < 0.05 * base.model.tool_weight
        and base.explained >= EXPLAINED[1]
    ):
        if given.chi_square / max(base.chi_square, 1e-300) >= 0.5:
            reason = (
                f"as given the tool weighs {given.model.tool_weight:.3g} N, in the sensor frame "
                f"{base.model.tool_weight:.3g} N"
            )
            by_fit = given.chi_square / max(base.chi_square, 1e-300) >= SUSPECT_RATIO
            return ConventionReport(fits, "mistake", base, reason, by_fit=by_fit)
    reaction = by_name.get("the readings negated (the reaction)")
    if (
        reaction is not None
        and given.explained >= EXPLAINED[1]
        and given.model.gravity_in_base[2] > 0 > reaction.model.gravity_in_base[2]
    ):
        reason = "gravity points up in the base frame as given (or the arm hangs from a ceiling)"
        return ConventionReport(fits, "suspect", reaction, reason, by_fit=False)
    misfit = _misfit_beyond_spread(given)
    if misfit is not None and given.explained < EXPLAINED[1]:
        reason = (
            f"no alternative reading fits better, but the data as given explain only "
            f"{100 * max(given.explained, 0.0):.0f} % of the variation across poses, with "
            f"residuals {misfit:.3g}× the spread of repeated readings: a wrong URDF, sensor frame "
            "or mount, a contact, or a convention not tried here"
        )
        return ConventionReport(fits, "suspect", None, reason)
    gravity = given.model.gravity_in_base
    weight = float(np.linalg.norm(gravity))
    angle = np.rad2deg(np.arccos(np.clip(-gravity[2] / max(weight, 1e-300), -1.0, 1.0)))
    explained = given.explained >= EXPLAINED[1]  # a direction fitted to noise means nothing
    if explained and weight > 0.0 and TILT_WARNING_DEG < angle <= MAX_GRAVITY_ANGLE_DEG:
        reason = f"{tilt_text(angle, gravity)} (a floor mount assumed). {TILT_CAUSES}"
        return ConventionReport(fits, "suspect", None, reason, tilted=True)
    return ConventionReport(fits, "ok", None, "no alternative reading fits better")


def _misfit_beyond_spread(fit: ReadingFit) -> float | None:
    """The RMS ratio of the pose residuals to the noise of a pose mean (from the spread of its
    repeated readings), when it is beyond :data:`MISFIT_RATIO`; None without repeated readings
    or within it."""
    poses = fit.reading.poses
    spread = poses.spread * fit.reading.unit_scale
    if not np.any(np.isfinite(spread)):
        return None
    noise = np.nanmedian(spread / np.sqrt(np.asarray(poses.counts))[:, None], axis=0)
    dof = max(len(poses) - 2, 1)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = float(np.sqrt(np.median(fit.rss / dof / np.maximum(noise, 1e-300) ** 2)))
    return ratio if np.isfinite(ratio) and ratio > MISFIT_RATIO else None
