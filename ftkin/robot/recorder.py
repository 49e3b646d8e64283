"""Calibration data from an arm ftkin does not drive: still phases found live, one pose each.

:func:`record_poses` is ``ftkin record``. The arm is moved by hand, by its pendant or by its own
program; ftkin only reads it:

1. it polls the sensor and, where there is one, a :class:`~ftkin.robot.protocols.JointStateSource`
   (a :class:`~ftkin.robot.franka.FrankaRobot` that nobody commands, a UR controller's RTDE);
   without joints the sensor's gyro stands for the joint speeds and its accelerometer for the
   orientation (the calibration from the IMU, :mod:`ftkin.calibration.imu_fit`);
2. a phase is still when the test of :func:`~ftkin.robot.stillness.record_still` passes (joint
   speeds, settle time, a stationary window: :class:`~ftkin.robot.stillness.StillnessDetector`);
   then ``readings_per_pose`` readings are one pose;
3. a pose whose gravity direction in the sensor frame is within ``min_pose_angle`` of one
   already recorded adds nothing: it is refused ("same pose as pose 2: move to another");
4. each pose is appended to the samples CSV in one flushed, synced write, Ctrl-C held off while
   it is written (:class:`~ftkin.robot.samples_log.SamplesLog`): the file holds whole poses only,
   and ``resume=True`` continues it;
5. after each pose the standard errors of a calibration from the poses so far are predicted, the
   weakest direction named and the gravity direction that would help most suggested
   (:func:`~ftkin.planning.coverage.assess_coverage`, for the tool a linear fit of the readings
   so far suggests);
6. at ``n_poses`` poses, or on Ctrl-C, it calibrates (:func:`ftkin.calibrate`)
   and saves (``calibrate=False``: it records only, for an arm whose model is not known yet, such
   as a UR read with :class:`~ftkin.kinematics.ur_flange.UrFlange`). A sensor fault or a lost
   joint source stops it with :class:`~ftkin.exceptions.RecordingInterrupted`, the poses recorded
   kept.

What it says goes to ``on_event`` (a :class:`RecorderEvent` each; the CLI prints them), else to
the log.
"""

from __future__ import annotations

import logging
import time
from collections import deque
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..calibration.model import STANDARD_GRAVITY, WRENCH_CHANNELS
from ..calibration.observability import MIN_POSES
from ..calibration.result import CalibrationResult
from ..exceptions import (
    FtkinError,
    InvalidInput,
    RecordingInterrupted,
    RobotError,
    SensorError,
)
from ..io.csv_table import read_table
from ..io.samples_csv import POSE_COLUMN
from ..io.stream_join import ACCEL_COLUMNS, GYRO_COLUMNS
from ..planning.coverage import PoseCoverage, assess_coverage
from ..validation import whole_number
from .recorded_poses import RecordedPose, expected_calibration, nearest_pose, recorded_pose
from .samples_log import TIME_COLUMN, SamplesLog, interrupts_held
from .session import calibrate_recording
from .stillness import (
    CheckedSensor,
    PoseReadings,
    SampleTap,
    Stillness,
    StillnessDetector,
    stationary,
)

logger = logging.getLogger(__name__)

MIN_POSE_ANGLE = np.deg2rad(5.0)
"""Two poses whose gravity directions in the sensor frame are closer than this [rad] are one."""
CREEP = 10.0
"""An arm whose joints are all slower than this many times the stillness limit has arrived at a
pose: from then on it has ``Stillness.timeout`` to give one (else a joint that creeps, a hold
that does not settle, or readings that are not stationary stop the recording, said why)."""


@dataclass(frozen=True)
class RecorderEvent:
    """What the recorder says.

    Attributes:
        kind: ``"start"``, ``"recorded"``, ``"coverage"``, ``"same_pose"``, ``"unsettled"`` or
            ``"done"``.
        message: The sentence (``"pose 4 of 12 recorded: move on"``).
        pose: The pose id it is about, or None.
        coverage: With ``"coverage"``: the assessment.
    """

    kind: str
    message: str
    pose: int | None = None
    coverage: PoseCoverage | None = None


@dataclass(frozen=True)
class Recording:
    """The outcome of :func:`record_poses`.

    Attributes:
        samples_path: The samples CSV (whole poses only).
        poses_recorded: Poses in it.
        poses_total: Poses asked for.
        interrupted: True when Ctrl-C ended it before ``poses_total``.
        coverage: The assessment of the poses recorded (None before the first).
        calibration: The calibration from them, or None (see ``note``).
        note: Why there is no calibration, or ``""``.
    """

    samples_path: Path
    poses_recorded: int
    poses_total: int
    interrupted: bool
    coverage: PoseCoverage | None
    calibration: CalibrationResult | None
    note: str = ""


class PoseRecorder:
    """The recording loop of :func:`record_poses` (its arguments; see there)."""

    def __init__(
        self,
        sensor,
        joints,
        arm,
        *,
        samples_path,
        n_poses: int,
        readings_per_pose: int,
        resume: bool,
        stillness: Stillness,
        min_pose_angle: float,
        on_event: Callable[[RecorderEvent], None] | None,
        comments=(),
    ):
        if joints is not None and not callable(getattr(joints, "joint_state", None)):
            raise InvalidInput(
                f"joints must have joint_state() -> (q, dq), got {type(joints).__name__}"
            )
        if joints is not None and arm is None:
            raise InvalidInput("an arm model is needed with a joint source (its kinematics)")
        if not isinstance(stillness, Stillness):
            raise InvalidInput(f"stillness must be an ftkin Stillness, got {stillness!r}")
        if not (isinstance(min_pose_angle, (int, float)) and 0.0 <= min_pose_angle < np.pi):
            raise InvalidInput(f"min_pose_angle must be in [0, π) rad, got {min_pose_angle!r}")
        self.joints, self.arm, self.stillness = joints, arm, stillness
        self.n_poses = whole_number(n_poses, "n_poses", MIN_POSES)
        self.readings = whole_number(readings_per_pose, "readings_per_pose", 1)
        self.min_pose_angle = float(min_pose_angle)
        self.on_event = on_event
        self.frame = "sensor" if joints is not None else "IMU"
        self.tap = SampleTap(sensor)
        self.sensor = CheckedSensor(self.tap, stillness.stale_after)
        self.sensor.read()  # the first sample says which columns the file has
        imu = self.tap.imu()
        self.has_gyro = imu is not None and len(imu) == 6
        self.speeds = joints is not None or self.has_gyro  # else motion and noise look alike
        if joints is None and imu is None:
            raise InvalidInput(
                "without a joint source the recorder needs a sensor with an IMU (read_sample() "
                "with a specific force, e.g. a Bota sensor); give the arm's joint source "
                "(--franka, --ur), or log the stream with --raw"
            )
        columns = () if imu is None else ACCEL_COLUMNS + (GYRO_COLUMNS * self.has_gyro)
        self.log = SamplesLog(
            samples_path,
            () if joints is None else arm.joint_names,
            resume=resume,
            extra_columns=columns,
            comments=[
                f"ftkin record: {self.n_poses} poses, {self.readings} readings each, from an arm "
                "ftkin does not drive",
                "joints [rad], wrench [N, N·m] in the sensor frame (raw), pose = order recorded, "
                "t = sensor stamp [s], ax..az specific force [m/s², IMU frame], wx..wz [rad/s]",
                *comments,
            ],
        )
        self.poses = self._recorded_poses()
        self.coverage: PoseCoverage | None = None

    # ------------------------------------------------------------------ what it says
    def say(self, kind: str, message: str, pose=None, coverage=None) -> None:
        event = RecorderEvent(kind, message, pose, coverage)
        if self.on_event is not None:
            self.on_event(event)
        else:
            logger.info("%s", message)

    # ------------------------------------------------------------------ poses
    def _pose(self, pose_id: int, q, wrenches, imu) -> RecordedPose:
        arm = self.arm if self.joints is not None else None
        return recorded_pose(pose_id, wrenches, arm, q, imu)

    def _recorded_poses(self) -> list[RecordedPose]:
        """The poses already in the file (a resumed recording), in the order recorded."""
        ids = sorted(self.log.recorded_poses())
        if not ids:
            return []
        table = read_table(self.log.path)
        nq = 0 if self.joints is None else self.arm.nq
        values = table.floats(self.log.header)
        pose_column = values[:, self.log.header.index(POSE_COLUMN)]
        last = float(values[:, self.log.header.index(TIME_COLUMN)].max())
        if self.sensor.last_stamp is not None and self.sensor.last_stamp <= last:
            logger.warning(
                "the sensor's clock (%.6g s) is behind the last stamp in %s (%.6g s): it "
                "restarted, and the resumed poses' times overlap the recorded ones; calibrate "
                "with drift 'none' (--drift none)",
                self.sensor.last_stamp,
                self.log.path,
                last,
            )
        poses = []
        for pose_id in ids:
            rows = values[np.abs(pose_column - pose_id) < 0.5]
            extra = rows[:, nq + 8 :]
            poses.append(self._pose(pose_id, rows[:, :nq], rows[:, nq : nq + 6], extra))
        return poses

    def _assess(self) -> None:
        rotations = np.array([pose.rotation for pose in self.poses])
        expected = expected_calibration(self.poses, self.readings)
        self.coverage = assess_coverage(rotations, expected, frame=self.frame)
        self.say("coverage", self.coverage.describe(), coverage=self.coverage)

    # ------------------------------------------------------------------ the loop
    def _poll(self) -> tuple[float, np.ndarray, float, np.ndarray, bool, np.ndarray | None]:
        """``(speed [rad/s], q, stamp, wrench, new, imu)`` of one poll."""
        if self.joints is None:
            q, speed = np.zeros(0), 0.0
        else:
            try:
                q, dq = self.joints.joint_state()
            except FtkinError:
                raise
            except Exception as error:  # a duck-typed source may raise anything
                raise RobotError(
                    f"the joint source failed: {type(error).__name__}: {error}"
                ) from None
            q, dq = np.asarray(q, dtype=float), np.asarray(dq, dtype=float)
            if q.shape != (self.arm.nq,) or dq.shape != q.shape:
                raise InvalidInput(
                    f"the joint source gives {q.shape} positions and {dq.shape} velocities; the "
                    f"arm has {self.arm.nq} joints ({', '.join(self.arm.joint_names)})"
                )
            speed = float(np.max(np.abs(dq)))
        stamp, wrench, new = self.sensor.read()
        imu = self.tap.imu()
        if imu is not None and self.joints is None and self.has_gyro:
            speed = float(np.max(np.abs(imu[3:])))
        if (imu is None) != (not self.log.extra_columns) or (
            imu is not None and len(imu) != len(self.log.extra_columns)
        ):
            raise SensorError("imu", "the sensor's samples changed their IMU channels mid-way")
        return speed, q, stamp, wrench, new, imu

    def record(self) -> bool:
        """Record until ``n_poses`` poses are in the file; False when Ctrl-C stopped it.

        Raises:
            RecordingInterrupted: a sensor fault or a joint-source failure (whole poses kept).
        """
        done = len(self.poses)
        what = f"{self.n_poses} poses to {self.log.path}"
        if done:
            self.say("start", f"resuming {what}: {done} recorded; move the arm to another pose")
        else:
            self.say("start", f"recording {what}: move the arm to a pose and hold it still")
        if self.poses:
            self._assess()
        try:
            first = True  # the first pose may be where the arm stands now
            while len(self.poses) < self.n_poses:
                self._next_pose(moved=first)
                first = False
        except KeyboardInterrupt:
            return False
        except (SensorError, RobotError) as error:
            raise RecordingInterrupted(
                str(error), len(self.poses), self.n_poses, self.log.path
            ) from error
        self.say("done", f"{self.n_poses} of {self.n_poses} poses recorded in {self.log.path}")
        return True

    def _next_pose(self, moved: bool) -> None:
        """Wait for the next still phase at a new pose and record it (a phase at a pose already
        recorded is refused, once, and the arm must move before the next try). ``moved``: look
        for a still phase at once, without waiting for the arm to move first.

        Waiting for the arm to be moved is not bounded (the operator's pace; Ctrl-C ends it).
        An arm that has arrived (every joint slower than ``CREEP`` times the stillness limit)
        but gives no pose is: one ``"unsettled"`` event after half ``stillness.timeout``, and
        :class:`~ftkin.exceptions.RecordingInterrupted` at ``stillness.timeout``, naming the
        pose and why (the joint speed or the readings' spread against their limits). Without
        joints or a gyro there is no speed: a sensor carried about and a noisy one look alike,
        and only the event is given.
        """
        detector = StillnessDetector(self.readings, self.stillness)
        motion: deque = deque(maxlen=self.stillness.window)
        hinted = False
        start = time.monotonic()
        arrived: float | None = None  # since when the arm, moved, is slower than CREEP × limit
        fastest = 0.0  # the largest joint speed since then [rad/s]
        while True:
            now = time.monotonic()
            speed, q, stamp, wrench, new, imu = self._poll()
            if not moved or speed >= CREEP * self.stillness.joint_speed:
                arrived, fastest, hinted = None, 0.0, False
            elif arrived is None:
                arrived, fastest = now, speed
            else:
                fastest = max(fastest, speed)
            if not moved:
                if new:
                    motion.append(wrench)
                full = len(motion) == motion.maxlen
                if speed > self.stillness.joint_speed or (
                    full and not stationary(np.array(motion), self.stillness)
                ):
                    moved, start = True, now
                    detector.reset()
            elif detector.update(now, speed, q, stamp, wrench, new, imu):
                if self._take(detector.readings(now - start)):
                    return
                moved, hinted, arrived = False, False, None
                motion.clear()
                detector.reset()
            elif arrived is not None and now - arrived > self.stillness.timeout and self.speeds:
                raise RecordingInterrupted(
                    f"pose {len(self.poses) + 1} did not settle within {self.stillness.timeout:g} "
                    f"s (Stillness.timeout, --pose-timeout): {self._unsettled(detector, fastest)}",
                    len(self.poses),
                    self.n_poses,
                    self.log.path,
                )
            elif not hinted and arrived is not None and now - arrived > self.stillness.timeout / 2:
                hinted = True
                self.say(
                    "unsettled",
                    f"pose {len(self.poses) + 1} of {self.n_poses}: "
                    f"{self._unsettled(detector, fastest)}",
                )
            time.sleep(self.stillness.poll_period)

    def _unsettled(self, detector: StillnessDetector, fastest: float) -> str:
        """Why an arm that has arrived gives no pose: its joints creep, or it is still and the
        readings are not stationary."""
        still = self.stillness
        if detector.still_since is None or detector.speed > still.joint_speed:
            return (
                f"the arm has crept at about {fastest:.3g} rad/s, above the limit of "
                f"{still.joint_speed:g}: it is not still; if this is as still as it gets, raise "
                "--still-joint-speed"
            )
        spread = np.round(detector.spread(), 4).tolist()
        return (
            f"the arm is still but the readings are not stationary: spread {spread} (limits "
            f"{still.force_std:g} N, {still.torque_std:g} N·m); a noisier sensor needs larger "
            "--still-force-std/--still-torque-std"
        )

    def _take(self, readings: PoseReadings) -> bool:
        """Record ``readings`` as the next pose unless it repeats one; True when recorded."""
        pose_id = max((pose.pose_id for pose in self.poses), default=-1) + 1
        pose = self._pose(pose_id, readings.joint_positions, readings.wrenches, readings.extra)
        nearest = nearest_pose(pose, self.poses)
        if nearest is not None and nearest[1] < self.min_pose_angle:
            other, angle = nearest
            self.say(
                "same_pose",
                f"same pose as pose {other.pose_id} (gravity {np.rad2deg(angle):.1f}° from it in "
                f"the {self.frame} frame, {np.rad2deg(self.min_pose_angle):g}° needed): move to "
                "another",
                other.pose_id,
            )
            return False
        with interrupts_held():  # the file and self.poses agree, whatever Ctrl-C does
            self.log.append_pose(
                pose_id, readings.joint_positions, readings.wrenches, readings.times, readings.extra
            )
            self.poses.append(pose)
        self.say(
            "recorded",
            f"pose {len(self.poses)} of {self.n_poses} recorded"
            + (": move on" if len(self.poses) < self.n_poses else ""),
            pose_id,
        )
        self._assess()
        return True


def check_recorded_wrench_frame(log: SamplesLog, arm, wrench_frame: str) -> None:
    """:func:`~ftkin.calibration.wrench_frame.check_wrench_frame` on every reading of ``log``,
    the orientations from ``arm.rotation_sensor_to_base`` (an orientation-only model will do).

    Raises:
        ConventionMistake: the poses fit the other ``wrench_frame``.
    """
    from ..calibration.samples import Samples
    from ..calibration.wrench_frame import check_wrench_frame

    table = read_table(log.path)
    joints = table.floats(log.header[: arm.nq])
    samples = Samples(
        table.floats(WRENCH_CHANNELS),
        arm.rotation_sensor_to_base(joints).reshape(-1, 3, 3),
        table.floats([POSE_COLUMN])[:, 0].astype(int),
    )
    logger.info("%s", check_wrench_frame(samples, wrench_frame).message)


def record_poses(
    sensor,
    joints=None,
    arm=None,
    *,
    samples_path,
    n_poses: int = 12,
    readings_per_pose: int = 50,
    resume: bool = False,
    stillness: Stillness | None = None,
    min_pose_angle: float = MIN_POSE_ANGLE,
    output=None,
    g: float = STANDARD_GRAVITY,
    calibrate_options: Mapping | None = None,
    on_event: Callable[[RecorderEvent], None] | None = None,
    wrench_frame: str | None = None,
    calibrate: bool = True,
    comments=(),
) -> Recording:
    """Record calibration poses from an arm ftkin does not drive, then calibrate (module
    docstring).

    Args:
        sensor: A :class:`~ftkin.robot.protocols.ForceTorqueSensor`; with ``read_sample()``
            (the adapters of :mod:`ftkin.sensors`) its IMU is recorded too.
        joints: A :class:`~ftkin.robot.protocols.JointStateSource`, or None: the wrench and the
            IMU only (the sensor must have an accelerometer).
        arm: The arm's :class:`~ftkin.kinematics.arm.Arm` (with ``joints``: same joints, same
            order).
        samples_path: The samples CSV written as it goes.
        n_poses: Poses to record (with ``resume``: in all, those in the file included).
        readings_per_pose: Readings recorded at each pose.
        resume: Continue ``samples_path`` (same columns); False refuses an existing file.
        stillness: When a phase is still (default :class:`Stillness`). Its ``timeout`` bounds
            the wait at a pose the arm has arrived at (every joint slower than :data:`CREEP`
            times ``joint_speed``) and that gives none: halfway an ``"unsettled"`` event says
            why (a joint creeps, the readings are not stationary), at ``timeout`` the recording
            stops (``RecordingInterrupted``, the poses kept; not for a sensor without a gyro
            and no joints, whose motion and noise look alike). Waiting for the arm to be moved
            is not bounded (Ctrl-C ends it).
        min_pose_angle: A pose whose gravity direction is within this of a recorded one is
            refused [rad].
        output: Save the calibration there (atomically); None: not saved.
        g: Gravity [m/s²].
        calibrate_options: More :func:`ftkin.calibrate` keywords.
        on_event: Called with each :class:`RecorderEvent` (default: logged).
        wrench_frame: The axes the sensor's driver gave the wrench in before it was turned into
            the sensor frame (``"base"`` for a UR's built-in sensor read by
            :class:`~ftkin.robot.ur.UrArm`), checked against the poses before calibrating
            (:func:`~ftkin.robot.session.calibrate_recording`); None: not checked.
        calibrate: False records only (``arm`` may then be an orientation-only model such as
            :class:`~ftkin.kinematics.ur_flange.UrFlange`: a UR whose model is not known yet);
            ``wrench_frame`` is checked all the same, and ``Recording.note`` says it was not
            calibrated.
        comments: More ``#`` lines above the header of a new file (what is known of the arm:
            :func:`~ftkin.io.recorded_robot.robot_comment`).

    Returns:
        The :class:`Recording`; Ctrl-C ends it early (``interrupted``), calibrated when the
        poses so far allow it.

    Raises:
        RecordingInterrupted: a sensor fault, a failed joint source, or a pose that did not
            settle within ``stillness.timeout`` (whole poses kept).
        InvalidInput: bad arguments, an existing file without ``resume``, or one whose columns
            are not this recording's.
    """
    recorder = PoseRecorder(
        sensor,
        joints,
        arm,
        samples_path=samples_path,
        n_poses=n_poses,
        readings_per_pose=readings_per_pose,
        resume=resume,
        stillness=Stillness() if stillness is None else stillness,
        min_pose_angle=min_pose_angle,
        on_event=on_event,
        comments=comments,
    )
    complete = recorder.record()
    count = len(recorder.poses)
    calibration, note = None, ""
    if count < MIN_POSES:
        note = f"{count} pose(s) recorded: a calibration needs at least {MIN_POSES}"
    elif not calibrate:
        if wrench_frame is not None and joints is not None:
            check_recorded_wrench_frame(recorder.log, arm, wrench_frame)
        note = f"recorded only (calibrate=False): the {count} poses are in {recorder.log.path}"
    else:
        try:
            calibration = calibrate_recording(
                recorder.log.path,
                arm if joints is not None else None,
                g=g,
                output=output,
                calibrate_options=calibrate_options,
                wrench_frame=wrench_frame,
            )
        except FtkinError as error:
            if complete:
                raise
            note = f"no calibration from the {count} poses recorded: {error}"
    return Recording(
        recorder.log.path,
        count,
        recorder.n_poses,
        not complete,
        recorder.coverage,
        calibration,
        note,
    )
