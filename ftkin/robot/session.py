"""A calibration session on a robot: plan, visit, wait, record, calibrate, save, verify.

:func:`calibrate_on_robot` is what practitioners otherwise script by hand:

1. plan the poses (:func:`~ftkin.planning.plan.plan_poses`: D-optimal, joint limits, floor and
   self-collision checks) unless given, and visit them in the plan's order;
2. at each pose wait until the arm is still and the readings stationary, never recording while
   a joint moves (:mod:`ftkin.robot.stillness`);
3. check the pose against the others (:mod:`ftkin.calibration.pose_consistency`: a fit of the
   others predicts its reading), then append its readings to the samples CSV, flushed and synced
   before the arm moves on (:mod:`ftkin.robot.samples_log`); ``resume=True`` skips the poses
   already in it. A pose that does not fit (something touched the tool or the arm) is not
   written, or is taken out of the file, and is measured again after the others; one that still
   does not fit stops the session (:class:`~ftkin.exceptions.InconsistentPoses`);
4. calibrate (:func:`ftkin.calibrate`) from that file, save the calibration
   (:func:`~ftkin.io.calibration_file.save_calibration`), and check it at a few other poses:
   the compensated force there should be the sensor's noise (:func:`verify_on_robot`).

Any failure (a sensor fault, a robot error or a lost connection, Ctrl-C) stops the arm at once
and raises :class:`~ftkin.exceptions.SessionInterrupted`, the samples file complete up to the last
recorded pose.
"""

from __future__ import annotations

import logging
from collections import Counter, deque
from collections.abc import Mapping
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..calibration.fit_registry import calibrate
from ..calibration.model import STANDARD_GRAVITY
from ..calibration.pose_consistency import PoseConsistency, check_pose_consistency
from ..calibration.result import CalibrationResult
from ..calibration.samples import PoseAverages, Samples
from ..control.compensation import Compensator
from ..exceptions import FtkinError, InconsistentPoses, InvalidInput, SessionInterrupted
from ..io.calibration_file import save_calibration
from ..io.samples_csv import load_samples
from ..io.stream_join import ACCEL_COLUMNS, GYRO_COLUMNS
from ..kinematics.record import KinematicsRecord
from ..planning.constraints import DEFAULT_FLOOR_HEIGHT, FeasibilityChecker, PoseConstraints
from ..planning.plan import plan_poses
from ..progress import Progress
from .samples_log import SamplesLog
from .stillness import CheckedSensor, SampleTap, Stillness, record_still

logger = logging.getLogger(__name__)

RESUME_TOLERANCE = 0.02
"""A recorded pose matches the plan when every joint is within this of it [rad]."""
DEFAULT_TOOL_WEIGHT = 15.0
"""Tool weight the planner assumes on a Franka-sized arm when none is given [N]."""


@dataclass(frozen=True)
class Verification:
    """Compensated readings at poses the calibration did not use.

    Attributes:
        joint_positions: ``(k, nq)`` poses [rad].
        contact_wrenches: ``(k, 6)`` mean compensated wrench per pose [N, N·m], sensor frame.
    """

    joint_positions: np.ndarray
    contact_wrenches: np.ndarray

    @property
    def force_norms(self) -> np.ndarray:
        """``(k,)`` norm of the compensated force per pose [N]."""
        return np.linalg.norm(self.contact_wrenches[:, :3], axis=1)

    @property
    def torque_norms(self) -> np.ndarray:
        """``(k,)`` norm of the compensated torque per pose [N·m]."""
        return np.linalg.norm(self.contact_wrenches[:, 3:], axis=1)

    def report(self) -> str:
        """One line per pose: the compensated force and torque norms [N, N·m]."""
        lines = [f"verification at {len(self.force_norms)} pose(s) not used by the fit:"]
        for i, (force, torque) in enumerate(zip(self.force_norms, self.torque_norms)):
            lines.append(f"  pose {i}: |F'| = {force:.3f} N, |M'| = {torque:.4f} N·m")
        return "\n".join(lines)


def session_poses(
    arm,
    n_poses: int,
    *,
    seed: int = 0,
    readings_per_pose: int = 50,
    plan_options: Mapping | None = None,
) -> np.ndarray:
    """The planned poses ``(n, nq)`` [rad] of a session, in visiting order (deterministic)."""
    options = {
        "floor_height": DEFAULT_FLOOR_HEIGHT,
        "tool_weight": DEFAULT_TOOL_WEIGHT,
        **(plan_options or {}),
    }
    plan = plan_poses(
        arm, n_poses, seed=seed, readings_per_pose=readings_per_pose, progress=False, **options
    )
    return plan.joint_positions


def check_given_poses(arm, poses, plan_options: Mapping | None = None) -> np.ndarray:
    """Poses given to a session (a plan file), checked before the arm moves to any: ``(n >= 3,
    nq)`` finite joint positions [rad] within the joint limits, each meeting the session's
    constraints (floor, tilt, joint ranges, no self-collision).

    Raises:
        InvalidInput: the first pose that fails, and why (degrees, another arm, the floor, ...).
    """
    try:
        poses = np.asarray(poses, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"poses must be joint positions [rad], got {poses!r}") from None
    if poses.ndim != 2 or poses.shape[1] != arm.nq or len(poses) < 3:
        raise InvalidInput(
            f"poses must be (n >= 3, {arm.nq}) joint positions [rad] of "
            f"{', '.join(arm.joint_names)}, got shape {poses.shape}"
        )
    if not np.all(np.isfinite(poses)):
        raise InvalidInput("poses must be finite joint positions [rad]")
    low, high = arm.lower_limits, arm.upper_limits
    for index, q in enumerate(poses):
        outside = np.flatnonzero((q < low) | (q > high))
        if outside.size:
            j = int(outside[0])
            degrees = " (degrees? poses are in radians)" if abs(q[j]) > 2 * np.pi else ""
            raise InvalidInput(
                f"pose {index}: {arm.joint_names[j]} = {q[j]:.6g} is outside its limits "
                f"[{low[j]:.4g}, {high[j]:.4g}] rad{degrees}: the arm will not move there"
            )
    options = {"floor_height": DEFAULT_FLOOR_HEIGHT, **(plan_options or {})}
    keys = {"floor_height", "max_tilt", "joint_ranges", "self_collision", "clearance"}
    constraints = PoseConstraints(
        margin=0.0,
        **{key: value for key, value in options.items() if key in keys and value is not None},
    )
    checker = FeasibilityChecker(arm, constraints)
    for index, q in enumerate(poses):
        for name, lower, upper in constraints.joint_ranges:
            value = q[arm.joint_names.index(name)]
            if not lower <= value <= upper:
                raise InvalidInput(
                    f"pose {index}: {name} = {value:.6g} is outside --joint-range "
                    f"{name}:{lower:g}:{upper:g} [rad]"
                )
        before = dict(checker.rejected)
        if checker.check(q) is None:
            reasons = [
                name for name, count in checker.rejected.items() if count > before.get(name, 0)
            ]
            raise InvalidInput(
                f"pose {index} does not meet the session's constraints ({constraints.describe()}): "
                f"rejected by {', '.join(reasons) or 'a joint range'}; plan the poses for this arm "
                "with the same constraints (ftkin plan) or loosen them"
            )
    return poses


def verification_poses(
    arm, count: int, *, seed: int = 1, plan_options: Mapping | None = None
) -> np.ndarray:
    """``count`` random configurations ``(count, nq)`` [rad] that meet the planner's constraints."""
    options = {"floor_height": DEFAULT_FLOOR_HEIGHT, **(plan_options or {})}
    keys = {"margin", "floor_height", "max_tilt", "joint_ranges", "self_collision", "clearance"}
    constraints = PoseConstraints(
        **{key: value for key, value in options.items() if key in keys and value is not None}
    )
    checker = FeasibilityChecker(arm, constraints)
    rng = np.random.default_rng(seed)
    found = []
    for _ in range(200):
        for q in checker.sample(100, rng):
            if checker.check(q) is not None:
                found.append(q)
                if len(found) == count:
                    return np.array(found)
    raise InvalidInput(f"found only {len(found)} feasible verification poses of {count}")


def calibrate_recording(
    samples_path,
    arm=None,
    *,
    g: float = STANDARD_GRAVITY,
    output=None,
    calibrate_options: Mapping | None = None,
    wrench_frame: str | None = None,
) -> CalibrationResult:
    """Calibrate from a recorded samples CSV: from the joints with ``arm``
    (:func:`~ftkin.io.samples_csv.load_samples`, the arm's kinematics record kept; with the IMU
    columns too, the fused fit that checks the mount:
    :func:`~ftkin.io.imu_columns.with_imu_columns`), else from the IMU columns alone
    (:func:`~ftkin.io.imu_columns.load_imu_samples`); save it to ``output`` if given.

    ``wrench_frame`` (``"base"`` or ``"sensor"``, with ``arm``): the axes a driver gave the
    wrench in before it was turned into the sensor frame (a UR's ``ft_raw_wrench``), checked
    against the poses first (:func:`~ftkin.calibration.wrench_frame.check_wrench_frame`).

    Raises:
        ConventionMistake: the poses fit the other ``wrench_frame`` (the message names
            ``--wrench-frame`` and its value).
    """
    options = dict(calibrate_options or {})
    if arm is not None:
        loaded = load_samples(samples_path, arm)
        if wrench_frame is not None:
            from ..calibration.wrench_frame import check_wrench_frame

            check = check_wrench_frame(loaded.samples, wrench_frame)
            logger.info("%s", check.message)
        from ..io.imu_columns import with_imu_columns  # the IMU's modules load when used

        samples = with_imu_columns(loaded, g=g)
        if isinstance(samples, Samples):
            options["g"] = g  # fused samples carry their own g
        result = calibrate(samples, **options)
        result = replace(result, kinematics=KinematicsRecord.from_arm(arm))
    else:
        from ..io.imu_columns import load_imu_samples

        samples, _ = load_imu_samples(samples_path, g=g)
        result = calibrate(samples, **options)
    if output is not None:
        save_calibration(result, output)
        logger.info("saved the calibration to %s", output)
    return result


def calibrate_on_robot(
    robot,
    sensor,
    arm,
    *,
    n_poses: int = 12,
    poses=None,
    readings_per_pose: int = 50,
    samples_path,
    resume: bool = False,
    output=None,
    verify_poses: int = 3,
    seed: int = 0,
    plan_options: Mapping | None = None,
    stillness: Stillness | None = None,
    g: float = STANDARD_GRAVITY,
    calibrate_options: Mapping | None = None,
    progress: bool | None = None,
    remeasure: int = 2,
) -> CalibrationResult:
    """Calibrate the wrist sensor on the robot (see the module docstring).

    Args:
        robot: A :class:`~ftkin.robot.protocols.Robot` (e.g. :class:`FrankaRobot`).
        sensor: A :class:`~ftkin.robot.protocols.ForceTorqueSensor`.
        arm: The robot's :class:`~ftkin.kinematics.arm.Arm` (same joints, in the same order).
        n_poses: Poses to plan (with ``poses`` None).
        poses: ``(n, nq)`` poses [rad] to visit instead of planning.
        readings_per_pose: Readings recorded at each pose.
        samples_path: The samples CSV written as the session goes.
        resume: Continue ``samples_path``: poses already in it are skipped (they must match
            the plan: same ``n_poses``, ``seed`` and options).
        output: Save the calibration there (atomically); None: not saved.
        verify_poses: Extra poses for :func:`verify_on_robot` (logged; 0: none). A fault there
            stops the arm and is logged; the calibration is returned all the same.
        seed: Seed of the planner (and of the verification poses, ``seed + 1``).
        plan_options: More :func:`~ftkin.planning.plan.plan_poses` keywords (default floor
            height 0.1 m, tool weight 15 N), e.g. ``joint_ranges``.
        stillness: When the arm is still (default :class:`Stillness`).
        g: Gravity for the tool mass [m/s²].
        calibrate_options: More :func:`ftkin.calibrate` keywords.
        progress: Draw a progress bar (default: when stderr is a terminal).
        remeasure: Times a pose whose readings do not fit the others is measured again before
            the session stops (:mod:`ftkin.calibration.pose_consistency`).

    Returns:
        The calibration (with the arm's kinematics record).

    Raises:
        SessionInterrupted: a sensor fault, a robot error or Ctrl-C stopped the session (the arm
            is stopped; the samples file keeps every recorded pose).
        InvalidInput: bad arguments, an existing samples file without ``resume``, or a
            resumed file recorded with another plan.
        InconsistentPoses: a pose still does not fit the others after ``remeasure`` more
            visits (nothing calibrated or written; the samples file holds the poses that fit).
    """
    if isinstance(remeasure, bool) or not isinstance(remeasure, int) or remeasure < 0:
        raise InvalidInput(f"remeasure must be a whole number >= 0 of visits, got {remeasure!r}")
    stillness = stillness if stillness is not None else Stillness()
    if not isinstance(stillness, Stillness):
        raise InvalidInput(f"stillness must be an ftkin Stillness, got {stillness!r}")
    if poses is None:
        poses = session_poses(
            arm, n_poses, seed=seed, readings_per_pose=readings_per_pose, plan_options=plan_options
        )
    else:
        poses = check_given_poses(arm, poses, plan_options)
    tap = SampleTap(sensor)
    checked = CheckedSensor(tap, stillness.stale_after)
    checked.read()  # the first sample says whether the sensor has an IMU to record
    imu = tap.imu()
    imu_columns = () if imu is None else (ACCEL_COLUMNS + GYRO_COLUMNS)[: len(imu)]
    log = SamplesLog(
        samples_path,
        arm.joint_names,
        resume=resume,
        comments=[
            f"ftkin calibration session: {len(poses)} poses, {readings_per_pose} readings each",
            "joints [rad], wrench [N, N·m] in the sensor frame (raw), pose = index in the plan, "
            "t = sensor stamp [s]"
            + (
                ", the IMU's ax,ay,az [m/s²] and wx,wy,wz [rad/s] (IMU frame)"
                if imu_columns
                else ""
            ),
        ],
        extra_columns=imu_columns,
    )
    todo = _poses_to_visit(log, poses)
    means = _recorded_means(log, arm) if len(todo) < len(poses) else {}
    queue, attempts = deque(todo), Counter()

    def take_out(check: PoseConsistency, pose_ids) -> None:
        """Count a visit of each flagged pose; measured too often: stop, nothing calibrated."""
        attempts.update(pose_ids)
        failed = [pose for pose in pose_ids if attempts[pose] > remeasure]
        if failed:
            raise InconsistentPoses(failed, [check.describe(pose) for pose in failed], log.path)
        for pose in pose_ids:
            logger.warning(
                "%s: measuring it again (something touched the tool or the arm?)",
                check.describe(pose),
            )

    def revisit(check: PoseConsistency, pose_ids) -> None:
        """Take flagged poses out of the file and queue them to be measured again."""
        pose_ids = list(check.flagged if pose_ids is None else pose_ids)
        if pose_ids:
            take_out(check, pose_ids)
        for pose in pose_ids:
            log.remove_pose(pose, "did not fit the other poses; measured again")
            del means[pose]
            queue.append(pose)

    if not queue:  # a finished file, resumed: checked as well
        revisit(_consistency(means, g), None)
    with Progress(len(poses), "calibration poses", enabled=progress) as bar:
        bar.advance(len(poses) - len(todo))
        while queue:
            pose_id = queue.popleft()
            with _stopping(robot, log, len(poses)):  # Ctrl-C anywhere here: resumable
                robot.move_to(poses[pose_id], while_moving=checked.read)
                readings = record_still(robot, checked, readings_per_pose, stillness, tap)
                mean = _pose_mean(arm, readings)
                check = _consistency({**means, pose_id: mean}, g)
                if pose_id in check.flagged:  # not written; measured again after the others
                    take_out(check, [pose_id])  # (a contact that ends, ends meanwhile)
                    queue.append(pose_id)
                    continue
                log.append_pose(
                    pose_id,
                    readings.joint_positions,
                    readings.wrenches,
                    readings.times,
                    readings.extra if imu_columns else None,
                )
                means[pose_id] = mean
                logger.info("pose %d recorded (waited %.2f s to settle)", pose_id, readings.wait)
                if not attempts[pose_id]:
                    bar.advance()
                # poses recorded before there were enough to check them, now out of line
                revisit(check, [pose for pose in check.flagged if pose != pose_id])
                if not queue:  # the whole file, resumed poses too: a calibration if it holds
                    revisit(_consistency(means, g), None)
    result = calibrate_recording(
        log.path, arm, g=g, output=output, calibrate_options=calibrate_options
    )
    if verify_poses:
        verification = verify_session(
            robot,
            sensor,
            arm,
            result,
            verify_poses,
            seed=seed,
            plan_options=plan_options,
            stillness=stillness,
        )
        if verification is not None:
            logger.info("%s", verification.report())
    return result


def _pose_mean(arm, readings) -> tuple[np.ndarray, np.ndarray]:
    """``(R_BS (3, 3), mean raw wrench (6,) [N, N·m])`` of one pose's readings."""
    q = readings.joint_positions.mean(axis=0)
    return arm.rotation_sensor_to_base(q), readings.wrenches.mean(axis=0)


def _recorded_means(log: SamplesLog, arm) -> dict:
    """``{pose id: (R_BS, mean wrench)}`` of the poses already in a resumed samples file."""
    averages = load_samples(log.path, arm).samples.pose_averages()
    return {
        int(pose): (rotation, wrench)
        for pose, rotation, wrench in zip(averages.pose_ids, averages.rotations, averages.wrenches)
    }


def _consistency(means: Mapping, g: float) -> PoseConsistency:
    """The leave-one-out check (:mod:`ftkin.calibration.pose_consistency`) of pose means."""
    ids = np.array(sorted(means))
    rotations = np.array([means[pose][0] for pose in ids]).reshape(-1, 3, 3)
    wrenches = np.array([means[pose][1] for pose in ids]).reshape(-1, 6)
    count = np.ones(len(ids))
    averages = PoseAverages(ids, rotations, wrenches, count, np.full((len(ids), 6), np.nan))
    return check_pose_consistency(averages, g=g)


def verify_session(
    robot,
    sensor,
    arm,
    calibration,
    count: int,
    *,
    seed: int = 0,
    plan_options: Mapping | None = None,
    stillness: Stillness | None = None,
) -> Verification | None:
    """The verification step of a session: :func:`verify_on_robot` at ``count`` new poses
    (:func:`verification_poses` with seed ``seed + 1``, the session's ``plan_options``).

    The calibration is done (and saved) by then: a fault here stops the arm, is logged as a
    warning and returns None; it does not undo the calibration. Ctrl-C stops the arm and is
    raised again (the caller ends as an interrupted command does).
    """
    poses = verification_poses(arm, count, seed=seed + 1, plan_options=plan_options)
    try:
        return verify_on_robot(robot, sensor, arm, calibration, poses, stillness=stillness)
    except FtkinError as error:
        logger.warning("verification stopped (the arm is stopped): %s", error)
        return None


def _poses_to_visit(log: SamplesLog, poses: np.ndarray) -> list[int]:
    recorded = log.recorded_poses()
    for pose_id, q in recorded.items():
        if not 0 <= pose_id < len(poses) or np.max(np.abs(q - poses[pose_id])) > RESUME_TOLERANCE:
            raise InvalidInput(
                f"{log.path} holds pose {pose_id}, which is not this session's plan (another "
                "n_poses, seed or plan option?): resume with the same ones, or start a new file"
            )
    if recorded:
        logger.info("resuming: %d of %d poses already recorded", len(recorded), len(poses))
    return [i for i in range(len(poses)) if i not in recorded]


class _stopping:
    """Stop the robot on any failure in the block and raise :class:`SessionInterrupted`."""

    def __init__(self, robot, log: SamplesLog, total: int):
        self.robot, self.log, self.total = robot, log, total

    def __enter__(self):
        return self

    def __exit__(self, kind, error, traceback):
        if error is None:
            return False
        self.robot.stop()
        if isinstance(error, KeyboardInterrupt):
            reason = "interrupted (Ctrl-C)"
        elif isinstance(error, FtkinError) and not isinstance(
            error, InvalidInput | InconsistentPoses
        ):
            reason = str(error)
        else:
            return False  # a programming error, bad input or poses that do not fit: stays
        raise SessionInterrupted(
            reason, len(self.log.recorded_poses()), self.total, self.log.path
        ) from error


def verify_on_robot(
    robot,
    sensor,
    arm,
    calibration,
    poses,
    *,
    readings: int = 50,
    stillness: Stillness | None = None,
) -> Verification:
    """Visit ``poses`` and compensate the still readings there with ``calibration``.

    Without contact the compensated wrench is the sensor's noise plus the calibration's error.
    Any failure stops the arm and is raised.
    """
    stillness = stillness if stillness is not None else Stillness()
    compensator = Compensator(calibration, arm)
    checked = CheckedSensor(sensor, stillness.stale_after)
    poses = np.asarray(poses, dtype=float).reshape(-1, arm.nq)
    wrenches = []
    try:
        for q in poses:
            robot.move_to(q, while_moving=checked.read)
            taken = record_still(robot, checked, readings, stillness)
            contact = compensator.compensate_batch(taken.joint_positions, taken.wrenches)
            wrenches.append(contact.mean(axis=0))
    except BaseException:
        robot.stop()
        raise
    return Verification(poses, np.array(wrenches))


def default_samples_path(output) -> Path:
    """The samples file beside a calibration output: ``calib.json`` → ``calib.samples.csv``."""
    output = Path(output)
    return output.with_name(output.stem + ".samples.csv")
