"""Orientations given in the wrong convention, refused by :func:`~ftkin.calibration.calibrate`
whichever door they came in by.

Samples whose orientations were given directly (not through an arm's joint angles) are read the
ways people get them wrong, from their ``R_BS`` alone:

* Euler angles (:meth:`Samples.from_euler_zyx_deg`, ``alpha,beta,gamma``) holding radians;
* quaternions (:meth:`Samples.from_quaternions`, ``qw,qx,qy,qz``) holding ``x,y,z,w``;
* rotation matrices (:meth:`Samples.from_rotations`, ``r11..r33``) transposed (``R_SB``, the
  base in the sensor frame, or the entries column-major); Euler angles and quaternions of
  ``R_SB`` likewise (the orientation inverted).

Each reading is a :class:`~ftkin.calibration.doctor.Reading` with the name and the fix that
``ftkin doctor`` and ``ftkin calibrate`` print for a samples CSV (:mod:`ftkin.io.table_readings`
builds that file's readings with these names and fixes), so the API and the command line refuse
the same data with the same words. The verdict is the doctor's
(:func:`~ftkin.calibration.doctor.diagnose_readings`, with the wrench's alternatives beside);
:func:`refuse_orientation_mistakes` refuses only when an orientation reading is the mistake (the
wrench's own mistakes are :func:`calibrate`'s other checks).
"""

import numpy as np

from ..exceptions import ConventionMistake, FtkinError
from ..kinematics.rotations import (
    euler_zyx_to_matrix,
    matrix_to_euler_zyx,
    matrix_to_quaternion,
    quaternion_to_matrix,
)
from .doctor import (
    MISTAKE_RATIO,
    Reading,
    ReadingFit,
    diagnose_readings,
    fit_reading,
    unchecked_rss,
    wrench_readings,
)
from .model import SensorModel
from .samples import PoseAverages, Samples

EULER_RADIANS = (
    "Euler angles in radians",
    "give alpha, beta, gamma in degrees (multiply by 180/π; Samples.from_euler_zyx_deg takes "
    "degrees)",
)
QUATERNION_XYZW = (
    "the quaternion as x,y,z,w",
    "name the columns qx,qy,qz,qw (the order they hold); in Python give [qw, qx, qy, qz] to "
    "Samples.from_quaternions (quaternions[:, [3, 0, 1, 2]])",
)
MATRIX_TRANSPOSED = (
    "the matrix transposed (R_SB, or the entries column-major)",
    "write R_BS row-major: r12 is row 1, column 2 (swap rIJ and rJI); in Python give R_BS, the "
    "sensor's orientation in the base frame (R_SB.transpose(0, 2, 1))",
)
ORIENTATION_INVERTED = (
    "the orientation inverted (R_SB: base in the sensor frame)",
    "give the sensor's orientation in the base frame, R_BS",
)
CONJUGATE = " (conjugate the quaternion: negate qx,qy,qz)"
"""Appended to :data:`ORIENTATION_INVERTED`'s fix for quaternions."""


def _xyzw(rotations: np.ndarray) -> np.ndarray:
    """``R_BS`` of quaternions that were read ``w,x,y,z`` but held ``x,y,z,w``."""
    read = matrix_to_quaternion(rotations).reshape(-1, 4)  # ± the four numbers as given
    return quaternion_to_matrix(read[:, [3, 0, 1, 2]]).reshape(-1, 3, 3)


def _euler_radians(rotations: np.ndarray) -> np.ndarray:
    """``R_BS`` of Euler angles that were read in degrees but held radians."""
    given = np.rad2deg(matrix_to_euler_zyx(rotations).reshape(-1, 3))  # the numbers as given
    return euler_zyx_to_matrix(given).reshape(-1, 3, 3)


def _inverted(rotations: np.ndarray) -> np.ndarray:
    return np.transpose(rotations, (0, 2, 1))


def orientation_alternatives(kind: str) -> list[tuple[str, str, object]]:
    """``[(name, fix, mistaken R_BS → true R_BS)]``: the wrong readings tried for orientations
    given as ``kind`` (none for joint angles: forward kinematics has no inverse; their degrees
    are :mod:`ftkin.kinematics.joint_units`').
    """
    if kind == "euler":
        return [(*EULER_RADIANS, _euler_radians), (*ORIENTATION_INVERTED, _inverted)]
    if kind == "quaternion":
        name, fix = ORIENTATION_INVERTED
        return [(*QUATERNION_XYZW, _xyzw), (name, fix + CONJUGATE, _inverted)]
    if kind == "matrix":
        return [(*MATRIX_TRANSPOSED, _inverted)]
    return []


def orientation_kind(samples: Samples) -> str:
    """How ``samples``' orientations were given: their ``orientation``, else ``"joints"`` with
    joint positions and ``"matrix"`` without (rotations given directly)."""
    if samples.orientation is not None:
        return samples.orientation
    return "joints" if samples.joint_positions is not None else "matrix"


def orientation_readings(samples: Samples, signs=None) -> list[Reading]:
    """``samples`` as given (first), under each orientation mistake of their kind, and under the
    wrench's mistakes (:func:`~ftkin.calibration.doctor.wrench_readings`). ``signs``: ``(6,)``
    factors of the readings (a stated sensor sign or flipped axis), applied first.
    """
    readings = _orientation_readings(samples, signs)
    return readings + wrench_readings(readings[0].poses, joints=samples.joint_positions is not None)


def _orientation_readings(samples: Samples, signs=None, poses=None) -> list[Reading]:
    """``samples`` as given (first; ``poses`` when at hand) and under each orientation mistake of
    their kind."""
    wrenches = samples.wrenches if signs is None else samples.wrenches * signs
    given = _poses(samples.rotations, wrenches, samples) if poses is None else poses
    readings = [Reading("the data as given", "", given)]
    for name, fix, true_rotations in orientation_alternatives(orientation_kind(samples)):
        try:
            poses = _poses(true_rotations(samples.rotations), wrenches, samples)
        except (FtkinError, ValueError) as error:
            readings.append(Reading(name, fix, None, failure=str(error).split(": ")[-1][:80]))
            continue
        readings.append(Reading(name, fix, poses))
    return readings


def _poses(rotations, wrenches, samples: Samples):
    return Samples(wrenches, rotations, samples.pose_ids).pose_averages()


def refuse_orientation_mistakes(
    samples: Samples, signs=None, poses: PoseAverages | None = None
) -> SensorModel | None:
    """Refuse samples whose orientations fit only when read in another convention (see the
    module docstring); nothing for joint angles or when another reading is the doctor's.

    ``poses``: ``samples.pose_averages()`` with ``signs`` applied, when at hand. Returns the
    two-step linear fit of the data as given (:func:`~ftkin.calibration.linear.fit_linear`, at
    standard gravity) when the check fitted one, else None (joint angles, or poses it cannot
    determine): :func:`~ftkin.calibration.estimate.calibrate` fits it only once.

    Raises:
        ConventionMistake: the reading that explains the data and its fix.
    """
    kind = orientation_kind(samples)
    if kind == "joints":
        return None
    names = {name for name, _, _ in orientation_alternatives(kind)}
    readings = _orientation_readings(samples, signs, poses)
    given = fit_reading(readings[0])
    # the alternatives' checks unrun: one they would fail is never named, so its number can only
    # make the bound ask the doctor
    others = [ReadingFit(reading, None, unchecked_rss(reading)) for reading in readings[1:]]
    if cannot_name_a_mistake([given, *others]):
        return given.model  # nor can the doctor's other readings: not fitted (the hot path)
    joints = samples.joint_positions is not None
    report = diagnose_readings(readings + wrench_readings(readings[0].poses, joints=joints))
    culprit = report.culprit
    if report.verdict == "mistake" and culprit is not None and culprit.reading.name in names:
        raise ConventionMistake(report.message, None, culprit.reading.name, culprit.reading.fix)
    return given.model


def cannot_name_a_mistake(fits: list[ReadingFit]) -> bool:
    """True when none of ``fits[1:]`` can be the doctor's mistake against ``fits[0]`` (the data as
    given), whatever other readings the doctor fits beside them.

    The doctor (:func:`~ftkin.calibration.doctor.diagnose_readings`) names an alternative a
    mistake only when the given reading's chi-square is at least
    :data:`~ftkin.calibration.doctor.MISTAKE_RATIO` times the alternative's. Both chi-squares
    weigh the channels' residual sums of squares ``rss_c`` with one positive variance ``v_c`` per
    channel (set by whichever reading fits best), and ``Σ_c g_c / v_c ÷ Σ_c a_c / v_c`` is at most
    ``max_c g_c / a_c`` for every positive ``v``: an alternative no channel of which fits
    ``MISTAKE_RATIO`` times better than as given is never named, and the other readings need not
    be fitted to know it. False (ask the doctor) when the data as given cannot be fitted. An
    alternative's ``rss`` may come from its fit without the observability checks
    (:func:`~ftkin.calibration.doctor.unchecked_rss`): one the checks would fail is never named,
    so its number can only send the question to the doctor.
    """
    given = fits[0]
    if given.rss is None:
        return False
    for fit in fits[1:]:
        if fit.rss is None:  # a reading that cannot be fitted is never the culprit
            continue
        with np.errstate(divide="ignore", invalid="ignore"):
            bound = np.max(given.rss / fit.rss)  # inf or nan (0/0) when a channel fits exactly
        if not bound < MISTAKE_RATIO:
            return False
    return True
