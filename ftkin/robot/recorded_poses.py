"""The poses a recording holds, as its checks and predictions need them.

Each pose of ``ftkin record`` (:mod:`ftkin.robot.recorder`) is kept as a :class:`RecordedPose`:
gravity's unit direction in the sensor frame (from the joints through the arm model; without
joints from the accelerometer, ``−a/|a|`` in the IMU frame), an orientation ``R_BS`` that sees
it (the arm's, or :func:`~ftkin.planning.coverage.rotations_from_gravity`'s), the mean reading
and its spread. From them: the recorded pose nearest to a new one (:func:`nearest_pose`: two
poses whose gravity directions are closer than the recorder's ``min_pose_angle`` are one), and
the calibration to predict for (:func:`expected_calibration`: the tool a linear fit of the poses
so far gives, the noise their spread shows).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.linear import fit_linear
from ..calibration.observability import MIN_POSES
from ..calibration.samples import PoseAverages
from ..exceptions import FtkinError, SensorError
from ..planning.coverage import DOWN, rotations_from_gravity
from ..planning.evaluation import PAPER_CENTER_OF_MASS, ExpectedCalibration
from .session import DEFAULT_TOOL_WEIGHT

NOISE_FLOOR = (1e-6, 1e-8)
"""Smallest noise [N, N·m] assumed in the predictions (a simulated sensor may have none)."""


@dataclass(frozen=True)
class RecordedPose:
    """One recorded pose.

    Attributes:
        pose_id: Its id in the samples file.
        direction: ``(3,)`` gravity's unit direction, sensor frame (IMU frame without joints).
        rotation: ``(3, 3)`` an orientation ``R_BS`` that sees gravity so.
        wrench: ``(6,)`` mean raw reading [N, N·m].
        spread: ``(6,)`` standard deviation of the readings [N, N·m] (0 for one reading).
        count: Readings.
    """

    pose_id: int
    direction: np.ndarray
    rotation: np.ndarray
    wrench: np.ndarray
    spread: np.ndarray
    count: int


def recorded_pose(pose_id: int, wrenches, arm=None, joint_positions=None, imu=None):
    """A :class:`RecordedPose` from its readings ``(n, 6)``: with ``arm``, the orientation of the
    mean ``joint_positions`` ``(n, nq)``; else gravity from the mean ``imu`` ``(n, 3+)``
    (``[ax, ay, az, ...]``, the specific force: ``+g`` up at rest).

    Raises:
        SensorError: the accelerometer reads zero (no gravity direction).
    """
    wrenches = np.asarray(wrenches, dtype=float)
    if arm is not None:
        rotation = arm.rotation_sensor_to_base(np.mean(joint_positions, axis=0))
        direction = rotation.T @ DOWN
    else:
        up = np.mean(np.asarray(imu, dtype=float), axis=0)[:3]
        norm = float(np.linalg.norm(up))
        if not norm > 0.0:
            raise SensorError("not_finite", "the accelerometer reads zero: no gravity direction")
        direction = -up / norm
        rotation = rotations_from_gravity(direction)[0]
    spread = wrenches.std(axis=0, ddof=1) if len(wrenches) > 1 else np.zeros(6)
    return RecordedPose(
        int(pose_id), direction, rotation, wrenches.mean(axis=0), spread, len(wrenches)
    )


def nearest_pose(pose: RecordedPose, poses) -> tuple[RecordedPose, float] | None:
    """The pose of ``poses`` whose gravity direction is nearest ``pose``'s, and the angle between
    them [rad]; None without poses."""
    if not poses:
        return None
    angles = [
        float(np.arccos(np.clip(pose.direction @ other.direction, -1.0, 1.0))) for other in poses
    ]
    nearest = int(np.argmin(angles))
    return poses[nearest], angles[nearest]


def expected_calibration(poses, readings_per_pose: int) -> ExpectedCalibration:
    """The calibration to predict for after ``poses``: the pooled spread of their readings as
    the noise, and the tool of a linear fit of their mean readings once they determine it
    (:func:`~ftkin.calibration.linear.fit_linear`; before, the session's default tool, 15 N with
    the paper's centre of mass)."""
    spread = np.array([pose.spread for pose in poses])
    pooled = np.sqrt(np.mean(spread**2, axis=0))
    noise = SensorNoise(*np.split(np.maximum(pooled, np.repeat(NOISE_FLOOR, 3)), 2))
    weight, com = DEFAULT_TOOL_WEIGHT, PAPER_CENTER_OF_MASS
    if len(poses) >= MIN_POSES:
        averages = PoseAverages(
            np.array([pose.pose_id for pose in poses]),
            np.array([pose.rotation for pose in poses]),
            np.array([pose.wrench for pose in poses]),
            np.array([pose.count for pose in poses]),
            spread,
        )
        try:
            fitted = fit_linear(averages)
        except FtkinError:  # not determined yet: the defaults
            fitted = None
        plausible = fitted is not None and 0.01 < fitted.tool_weight < 1e5
        if plausible and np.linalg.norm(fitted.center_of_mass) < 2.0:
            weight, com = fitted.tool_weight, fitted.center_of_mass
    return ExpectedCalibration(
        tool_weight=weight, center_of_mass=com, noise=noise, readings_per_pose=readings_per_pose
    )
