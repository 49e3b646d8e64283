"""Calibration samples: raw wrenches paired with sensor orientations.

A :class:`Samples` holds ``N`` raw readings ``[fx, fy, fz, mx, my, mz]`` [N, N·m]
in the sensor frame, the sensor orientation ``R_BS`` of each (canonical
``(N, 3, 3)`` form), and an optional pose id grouping repeated readings of one
static pose, and optional reading times ``t`` [s] (needed to model a
bias that drifts, :mod:`ftkin.calibration.drift`). Build it from whichever orientation input you
have: joint angles
through an :class:`~ftkin.kinematics.arm.Arm`, rotation matrices, quaternions, or the
paper's commanded Euler angles.
"""

import logging
from dataclasses import dataclass, fields, replace

import numpy as np

from ..exceptions import InvalidInput, InvalidSamples
from ..kinematics.joint_units import degrees_for_radians
from ..kinematics.record import KinematicsRecord
from ..kinematics.rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix
from ..validation import (
    as_batch,
    as_float_array,
    as_integers,
    as_rotation_batch,
    check_wrench_magnitude,
)

logger = logging.getLogger(__name__)

LONGEST_TIME_SPAN = 365.25 * 86400.0
"""Longest span of reading times accepted [s] (a year): beyond, ``t`` is not in seconds."""
LONG_TIME_SPAN = 7 * 86400.0
"""Span of reading times [s] (a week) beyond which a warning asks whether ``t`` is in seconds."""


_UNITS = (("milliseconds", 1e3), ("microseconds", 1e6), ("nanoseconds", 1e9))


def check_time_span(times: np.ndarray) -> None:
    """Refuse reading times spanning more than a year, warn beyond a week: ``t`` is in seconds, not
    ms, µs or ns.

    The hint names the unit in which every ``|t|`` is an epoch stamp (seconds since 1970 in
    2001–2286), else the unit bringing the span nearest ten minutes (in decades) within a week.
    """
    span = float(np.ptp(times))
    if span <= LONG_TIME_SPAN:
        return
    smallest, largest = float(np.min(np.abs(times))), float(np.max(np.abs(times)))
    epoch = [(name, f) for name, f in _UNITS if 1e9 <= smallest / f and largest / f < 1e10]
    near = sorted(
        ((name, f) for name, f in _UNITS if span / f <= LONG_TIME_SPAN),
        key=lambda unit: abs(np.log10(span / unit[1] / 600.0)),
    )
    message = (
        f"the reading times span {span:.4g} s ({span / 86400.0:.4g} days): t must be in seconds"
    )
    for name, factor in (epoch or near)[:1]:  # the likely unit, if any
        message += f"; they look like {name} (divide by {factor:g}: {span / factor:.4g} s)"
    if span > LONGEST_TIME_SPAN:
        raise InvalidSamples(message)
    logger.warning(message)


def check_joint_radians(arm, joint_positions: np.ndarray) -> None:
    """Refuse joint angles ``(N, nq)`` that can only be degrees
    (:func:`~ftkin.kinematics.joint_units.degrees_for_radians`), and warn once per joint with
    values outside the arm's limits (the first reading named).

    Raises:
        InvalidSamples: joint angles in degrees, naming the joint and the reading.
    """
    found = degrees_for_radians(arm, joint_positions)
    if found is not None:
        row, _, message = found
        raise InvalidSamples(f"reading {row}: {message}")
    lower, upper = np.asarray(arm.lower_limits, float), np.asarray(arm.upper_limits, float)
    if lower.shape != (joint_positions.shape[1],):
        return
    outside = (joint_positions < lower - 1e-9) | (joint_positions > upper + 1e-9)
    for column in np.flatnonzero(outside.any(axis=0)):
        row = int(np.argmax(outside[:, column]))
        logger.warning(
            "joint %r has %d value(s) outside the URDF limits [%g, %g] rad (first %g, reading %d)",
            arm.joint_names[column],
            int(np.count_nonzero(outside[:, column])),
            lower[column],
            upper[column],
            joint_positions[row, column],
            row,
        )


ORIENTATION_KINDS = ("joints", "euler", "quaternion", "matrix")
"""How a :class:`Samples`' orientations may have been given (``Samples.orientation``)."""

MAX_POSE_SPREAD = np.deg2rad(2.0)
"""Largest accepted angle [rad] between a reading's orientation and its pose's mean."""


@dataclass(frozen=True)
class PoseAverages:
    """Readings averaged per static pose.

    Attributes:
        pose_ids: ``(P,)`` pose identifiers, in order of first appearance.
        rotations: ``(P, 3, 3)`` mean sensor orientation ``R_BS`` per pose.
        wrenches: ``(P, 6)`` mean raw wrench per pose [N, N·m].
        counts: ``(P,)`` readings per pose.
        spread: ``(P, 6)`` sample standard deviation of the readings per pose
            and channel (NaN for a pose with a single reading).
        times: ``(P,)`` mean time of each pose's readings [s], or None when
            the samples carry no times.
    """

    pose_ids: np.ndarray
    rotations: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    spread: np.ndarray
    times: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.pose_ids)

    def subset(self, keep: np.ndarray) -> "PoseAverages":
        """The poses ``keep`` selects (a boolean mask or indices), every per-pose field alike."""
        values = {f.name: getattr(self, f.name) for f in fields(self)}
        return replace(self, **{k: v[keep] for k, v in values.items() if v is not None})


@dataclass(frozen=True)
class Samples:
    """Raw readings with their sensor orientations.

    Attributes:
        wrenches: ``(N, 6)`` raw readings in the sensor frame [N, N·m].
        rotations: ``(N, 3, 3)`` sensor orientations ``R_BS``.
        pose_ids: ``(N,)`` integer pose id of each reading (each reading is its
            own pose when not given).
        joint_positions: ``(N, nq)`` joint angles [rad] when the orientations
            came from an arm, else None.
        urdf: The URDF of that arm, recorded in the calibration file.
        sensor_frame: The arm's sensor frame, recorded likewise.
        times: ``(N,)`` time of each reading [s] (any origin; need not be
            sorted), or None when not recorded.
        kinematics: The arm's record (:class:`~ftkin.kinematics.record.KinematicsRecord`)
            when the orientations came from its joint angles, else None: every calibration
            made from these samples records it.
        orientation: How the orientations were given, one of :data:`ORIENTATION_KINDS`
            (``"joints"``, ``"euler"``, ``"quaternion"``, ``"matrix"``; set by each
            constructor and the CSV reader), or None: rotations given directly. ``calibrate``
            reads them under that input's common mistakes
            (:mod:`ftkin.calibration.orientation_mistakes`).
    """

    wrenches: np.ndarray
    rotations: np.ndarray
    pose_ids: np.ndarray | None = None
    joint_positions: np.ndarray | None = None
    urdf: str | None = None
    sensor_frame: str | None = None
    times: np.ndarray | None = None
    kinematics: KinematicsRecord | None = None
    orientation: str | None = None

    def __post_init__(self):
        if self.orientation is not None and self.orientation not in ORIENTATION_KINDS:
            raise InvalidSamples(
                f"orientation must be one of {', '.join(ORIENTATION_KINDS)} or None, got "
                f"{self.orientation!r}"
            )
        wrenches, _ = as_batch(self.wrenches, 6, "wrenches [fx, fy, fz, mx, my, mz]")
        try:  # before any fit: an absurd load is a unit mistake, not an unobservable parameter
            check_wrench_magnitude(wrenches, "wrenches")
        except InvalidInput as error:
            raise InvalidSamples(str(error)) from None
        rotations, _ = as_rotation_batch(self.rotations)
        if len(rotations) != len(wrenches):
            raise InvalidSamples(
                f"{len(wrenches)} wrenches but {len(rotations)} orientations; expected one each"
            )
        if len(wrenches) == 0:
            raise InvalidSamples("no samples")
        try:
            given = np.arange(len(wrenches)) if self.pose_ids is None else self.pose_ids
            pose_ids = as_integers(given, "pose ids")
        except InvalidInput as error:
            raise InvalidSamples(str(error)) from None
        if pose_ids.shape != (len(wrenches),):
            raise InvalidSamples(
                f"pose_ids must have shape ({len(wrenches)},), got {pose_ids.shape}"
            )
        arrays = {"wrenches": wrenches, "rotations": rotations, "pose_ids": pose_ids}
        if self.times is not None:
            times = as_float_array(self.times, "times [s]")
            if times.shape != (len(wrenches),):
                raise InvalidSamples(
                    f"times must have shape ({len(wrenches)},) (one per reading) [s], got "
                    f"{times.shape}"
                )
            if not np.all(np.isfinite(times)):
                raise InvalidSamples(
                    f"times must be finite [s]; reading {int(np.argmin(np.isfinite(times)))} is not"
                )
            check_time_span(times)
            arrays["times"] = times
        for name, array in arrays.items():
            # Frozen copies: freezing the caller's own arrays (or sharing them) would change them
            # behind their back.
            if array.base is not None or array is self.__dict__[name]:
                array = array.copy()
            array.setflags(write=False)
            object.__setattr__(self, name, array)

    def __len__(self) -> int:
        return len(self.wrenches)

    # ---------------------------------------------------------- constructors
    @classmethod
    def from_rotations(
        cls, rotation_sensor_to_base, wrenches, pose_ids=None, times=None
    ) -> "Samples":
        """From ``(N, 3, 3)`` sensor orientations ``R_BS`` (and optional times ``(N,)`` [s])."""
        return cls(wrenches, rotation_sensor_to_base, pose_ids, times=times, orientation="matrix")

    @classmethod
    def from_joint_positions(
        cls, arm, joint_positions, wrenches, pose_ids=None, rotations=None, times=None
    ) -> "Samples":
        """From ``(N, nq)`` joint angles [rad] through the arm's forward kinematics.

        ``rotations``: their ``R_BS`` ``(N, 3, 3)`` when the caller computed them
        already (forward kinematics is then skipped). ``times``: ``(N,)`` [s].

        Raises:
            InvalidSamples: joint angles in degrees: a value beyond ±2π, or one outside the arm's
                limits where every value read as degrees is within them
                (:mod:`ftkin.kinematics.joint_units`; a samples CSV is read by the same rule).
                Other values outside the limits are warned (a URDF narrower than the robot).
        """
        configurations, _ = as_batch(joint_positions, arm.nq, "joint positions q")
        check_joint_radians(arm, configurations)
        if rotations is None:
            rotations = arm.rotation_sensor_to_base(configurations)
        urdf = None if arm.urdf_path is None else str(arm.urdf_path)
        record = KinematicsRecord.from_arm(arm)  # the calibration records the arm it came from
        return cls(
            wrenches,
            rotations,
            pose_ids,
            configurations,
            urdf,
            arm.sensor_frame,
            times,
            record,
            orientation="joints",
        )

    @classmethod
    def from_quaternions(cls, quaternions_wxyz, wrenches, pose_ids=None, times=None) -> "Samples":
        """From ``(N, 4)`` unit quaternions ``[qw, qx, qy, qz]`` of the sensor in the base frame."""
        return cls(
            wrenches,
            quaternion_to_matrix(quaternions_wxyz).reshape(-1, 3, 3),
            pose_ids,
            times=times,
            orientation="quaternion",
        )

    @classmethod
    def from_euler_zyx_deg(cls, angles_deg, wrenches, pose_ids=None, times=None) -> "Samples":
        """From the paper's commanded ``(N, 3)`` Euler angles ``[α, β, γ]`` [deg], ``R = Rz Ry
        Rx``.
        """
        return cls(
            wrenches,
            euler_zyx_deg_to_matrix(angles_deg).reshape(-1, 3, 3),
            pose_ids,
            times=times,
            orientation="euler",
        )

    # -------------------------------------------------------------- grouping
    def pose_averages(self) -> PoseAverages:
        """Average the readings of each pose (vectorized).

        The mean orientation is the rotation nearest (Frobenius) to the mean
        matrix, so small joint-encoder jitter inside a pose averages out.
        """
        unique, first, inverse, counts = np.unique(
            self.pose_ids, return_index=True, return_inverse=True, return_counts=True
        )
        order = np.argsort(first)  # keep order of first appearance
        group, counts = np.argsort(order)[inverse], counts[order]

        def total(values: np.ndarray) -> np.ndarray:  # the sum of values over each pose
            out = np.zeros((len(unique),) + values.shape[1:])
            np.add.at(out, group, values)
            return out

        means = total(self.wrenches) / counts[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            spread = np.sqrt(total((self.wrenches - means[group]) ** 2) / (counts[:, None] - 1))
        u, _, vt = np.linalg.svd(total(self.rotations))
        u[:, :, 2] *= np.linalg.det(u @ vt)[:, None]
        mean_rotations = u @ vt
        cosines = (np.einsum("nij,nij->n", mean_rotations[group], self.rotations) - 1.0) / 2.0
        deviation = np.arccos(np.clip(cosines, -1.0, 1.0))
        worst = int(np.argmax(deviation))
        if deviation[worst] > MAX_POSE_SPREAD:
            raise InvalidSamples(
                f"the readings of pose {self.pose_ids[worst]} differ in orientation by up to "
                f"{np.rad2deg(deviation[worst]):.2f}° (more than "
                f"{np.rad2deg(MAX_POSE_SPREAD):.0f}°): a pose id must "
                "group readings of one static pose; check the pose column, or, for poses found "
                "from the still phases of a recording, the time unit and the stillness "
                "thresholds (--speed-threshold, --settle-time)"
            )
        pose_times = None if self.times is None else total(self.times) / counts
        return PoseAverages(unique[order], mean_rotations, means, counts, spread, pose_times)


def check_one_visit_per_pose(samples: Samples) -> None:
    """Refuse a pose id whose readings come in separate visits (another pose recorded in between),
    for a drift model.

    A drift model gives each pose one time (the mean of its readings); a pose
    revisited minutes later under the same id would average two biases at a
    time in between. Visits are runs of the same id in time order.
    """
    if samples.times is None or len(samples.times) < 2:
        return
    order = np.argsort(samples.times, kind="stable")
    ids, times = samples.pose_ids[order], samples.times[order]
    starts = np.flatnonzero(np.concatenate([[True], ids[1:] != ids[:-1]]))
    run_ids = ids[starts]
    unique, counts = np.unique(run_ids, return_counts=True)
    if np.all(counts == 1):
        return
    pose = unique[np.argmax(counts > 1)]
    ends = np.concatenate([starts[1:], [len(ids)]]) - 1
    spans = [f"{times[a]:g}–{times[b]:g} s" for a, b, i in zip(starts, ends, run_ids) if i == pose]
    raise InvalidSamples(
        f"pose {int(pose)} was recorded in {len(spans)} separate visits ({', '.join(spans[:4])}"
        f"{', ...' if len(spans) > 4 else ''}; {int(np.sum(counts > 1))} pose id(s) revisited): a "
        "drift model needs one "
        "time per pose; give each visit its own pose id, or calibrate with drift='none' (--drift "
        "none)"
    )
