"""``ftkin record``: calibration data from an arm ftkin does not drive.

* ``record --franka HOST --sensor SENSOR --n N -o SAMPLES.csv [--resume] [--calibrate CALIB.json]``:
  the arm is moved by hand (or by its own program) and each still phase at a new pose is
  recorded (:func:`~ftkin.robot.recorder.record_poses`), then calibrated;
* ``record --sensor SENSOR -o SAMPLES.csv``: no joint source, the wrench and the sensor's IMU
  only (the calibration from the IMU);
* ``record --raw --sensor SENSOR -o STREAM.csv [--duration S]``: the sensor's stream with its
  stamps, IMU and temperature (:func:`~ftkin.robot.stream_log.log_stream`);
* ``--ur HOST``: a UR controller's joints (and its built-in sensor unless ``--sensor``) through
  ``ftkin.robot.ur.UrArm`` (the UR support of issue 32, imported when asked for). The arm's model
  is ``--robot``, else what the controller's dashboard says it is
  (:func:`~ftkin.robot.ur_dashboard.ask_controller_model`; a ``--robot`` it contradicts is
  refused); with neither, the poses are recorded with the flange orientation any UR shares
  (:class:`~ftkin.kinematics.ur_flange.UrFlange`), not calibrated, and the ``ftkin calibrate``
  command that finishes the job is printed, its ``--robot`` the model whose kinematics reproduce
  the controller's TCP poses (:func:`~ftkin.kinematics.ur_flange.identify_ur_arm`).

Ctrl-C keeps whole poses, calibrates from them when it can, says how to continue (``--resume``)
and exits 130; a sensor fault or a lost joint source exits 2 with the same advice. The robot
commands' helpers (the sensor by name, the bundled FR3, the resume advice) are shared with
:mod:`ftkin.cli.robot`.
"""

import logging
import shlex
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import ConventionMistake, InvalidInput, RecordingInterrupted, SensorError
from ..robot.stillness import Stillness
from .arg_types import add_options, finite_float, option, refuse
from .common import add_arm_arguments, arm_from_args
from .declared import add_declared, declared_values
from .pose_options import add_readings_argument
from .robot import _arm, _closes_sensor, _resume_advice, _sensor
from .shared_options import (
    DEFAULT_POSES,
    DURATION,
    FRANKA,
    GRAVITY,
    NO_REALTIME,
    POSES,
    RESUME,
    SENSOR,
    SENSOR_OPTION,
    STATE_TIMEOUT,
    UR,
    WRENCH_FRAME,
    resolved,
)

logger = logging.getLogger("ftkin.cli")

INDENTED = ("coverage", "unsettled")
"""Events printed indented under the pose they are about."""


def min_pose_angle(text: str) -> float:
    """argparse type: an angle in degrees, 0 to 90."""
    value = finite_float(text)
    if not 0.0 <= value <= 90.0:
        import argparse

        raise argparse.ArgumentTypeError(f"expected 0 to 90 degrees, got {text}")
    return value


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "record",
        help="record calibration poses from an arm ftkin does not drive (moved by hand)",
        description="Read the sensor (and the arm's joints, where there is a joint source) while "
        "the arm is moved by hand, by its pendant or by its own program; record each still phase "
        "at a new pose, say what the poses so far leave undetermined, write the samples CSV as it "
        "goes, then calibrate. --raw logs the sensor's stream instead.",
    )
    joints = parser.add_argument_group("joint source (none: the wrench and the sensor's IMU)")
    add_options(
        joints,
        FRANKA,
        NO_REALTIME,
        STATE_TIMEOUT,
        UR,
        WRENCH_FRAME,
    )
    add_options(parser.add_argument_group("sensor"), SENSOR, SENSOR_OPTION)
    add_arm_arguments(parser)
    add_options(
        parser,
        option("-o", "--output", required=True, metavar="SAMPLES.csv"),
        RESUME,
        option(
            "--calibrate",
            dest="calibration_output",
            metavar="CALIB.json",
            help="save the calibration from the recorded poses here (default: print it only)",
        ),
        POSES,
        GRAVITY,
        option(
            "--min-pose-angle",
            type=min_pose_angle,
            default=5.0,
            metavar="DEG",
            help="a pose whose gravity direction in the sensor frame is within this of a recorded "
            "one is refused [deg] (default: %(default)s)",
        ),
        option(
            "--raw",
            action="store_true",
            help="log the sensor's stream (wrench, IMU, temperature, stamps) to -o instead",
        ),
        DURATION,
    )
    add_readings_argument(parser)
    add_declared(
        parser,
        Stillness,
        skip=("poll_period",),
        group="when a pose is still (a loaded simulator needs a larger --stale-after)",
    )
    parser.set_defaults(func=run)


def _print_event(event) -> None:
    print(("  " if event.kind in INDENTED else "") + event.message, flush=True)


@dataclass
class JointSource:
    """What ``record`` reads: the joints, the arm model, the sensor, ``close()`` to release them;
    for a UR also what is known of the arm (comments for the samples file), whether the model is
    known (else record only), and the ``(actual_q, actual_TCP_pose)`` seen (the model's check)."""

    joints: object
    arm: object
    sensor: object
    close: object
    comments: tuple = ()
    calibrate: bool = True
    tcp_poses: list = field(default_factory=list)


def _ur_arm(args):
    """``--ur HOST``: the joints (and the built-in sensor, in ``--wrench-frame``) through
    :class:`ftkin.robot.ur.UrArm`; its stale limit is ``--stale-after``."""
    from ..robot.ur import UrArm

    return UrArm(args.ur, wrench_frame=args.wrench_frame or "base", stale_after=args.stale_after)


def _ur_model(args, controller):
    """``(arm, comments)`` of ``--ur``: ``--robot``/``--urdf`` (checked against the controller's
    dashboard), else the dashboard's model, else None (record with the flange orientation)."""
    from ..io.recorded_robot import robot_comment
    from ..kinematics.robots import load_robot

    arm = arm_from_args(args)
    said = f"the controller's dashboard: {controller.describe()}"
    if arm is not None:
        controller.check_robot(arm.robot_name)
        if arm.robot_name is None:  # a URDF: kept as given, the controller's word noted
            return arm, (said,)
        agrees = f"; {said}" if controller.robot is not None else ""
        return arm, (robot_comment(arm.robot_name, f"--robot{agrees}"),)
    if controller.robot is not None:
        print(f"the arm's model from {said}", flush=True)
        return load_robot(controller.robot), (robot_comment(controller.robot, said),)
    print(
        f"no --robot and no model from the controller ({controller.reason}): recording with the "
        "flange orientation, the same for every UR; the controller's TCP poses name the model "
        "after the recording",
        flush=True,
    )
    return None, (said,)


def _joint_source(args) -> JointSource:
    """The joint source, arm and sensor the options name (``close()`` releases them)."""
    if args.franka and args.ur:
        raise InvalidInput("give one joint source: --franka HOST or --ur HOST")
    if args.wrench_frame is not None and not args.ur:
        raise InvalidInput(
            "--wrench-frame is the axes of a UR's built-in sensor: it goes with --ur"
        )
    if args.ur:
        from ..kinematics.ur_flange import UrFlange
        from ..robot.ur_dashboard import ask_controller_model

        arm, comments = _ur_model(args, ask_controller_model(args.ur))
        ur = _ur_arm(args)
        sensor = _sensor(args) if args.sensor else ur.sensor
        # the command ends with the process: no 0.5 s wait for ur_rtde's destructor
        close = lambda: ur.close(wait=False)  # noqa: E731
        if arm is None:
            return JointSource(ur, UrFlange(), sensor, close, comments, calibrate=False)
        return JointSource(ur, arm, sensor, close, comments)
    if not args.sensor:
        raise InvalidInput("give the sensor: --sensor NAME|MODULE:FACTORY (and --sensor-option)")
    if args.franka:
        from ..robot.franka import FrankaRobot

        arm = _arm(args)
        sensor = _sensor(args)
        robot = FrankaRobot(
            args.franka, realtime=not args.no_realtime, state_timeout=args.state_timeout
        )
        return JointSource(robot, arm, sensor, lambda: None)
    return JointSource(None, None, _sensor(args), lambda: None)


@_closes_sensor
def run(args) -> int:
    if args.raw:
        return _run_raw(args)
    if args.duration is not None:
        raise InvalidInput("--duration goes with --raw (a recording ends at --n poses)")
    from ..robot.recorder import record_poses

    source = _joint_source(args)
    on_event = _print_event if source.calibrate else _tcp_pose_keeper(source)
    try:
        recording = record_poses(
            source.sensor,
            source.joints,
            source.arm,
            samples_path=args.output,
            n_poses=resolved(args.n, DEFAULT_POSES),
            readings_per_pose=args.readings_per_pose,
            resume=args.resume,
            stillness=Stillness(**declared_values(Stillness, args)),
            min_pose_angle=float(np.deg2rad(args.min_pose_angle)),
            output=args.calibration_output,
            g=args.g,
            on_event=on_event,
            # the built-in sensor's wrench came in --wrench-frame axes: checked before the fit
            wrench_frame=(args.wrench_frame or "base") if args.ur and not args.sensor else None,
            calibrate=source.calibrate,
            comments=source.comments,
        )
    except RecordingInterrupted as error:
        raise InvalidInput(f"{error.reason}; {_resume_advice(args, error)}") from None
    except ConventionMistake as error:  # the built-in sensor's axes (--wrench-frame)
        raise InvalidInput(
            f"{error}; the readings in {args.output} were turned into the sensor frame under "
            f"--wrench-frame {args.wrench_frame or 'base'}: record again with {error.fix} "
            "(to another -o)"
        ) from None
    finally:
        source.close()
    if not source.calibrate:
        _print_calibrate_command(args, recording, source)
    elif recording.calibration is not None:
        print(recording.calibration.summary())
        if args.calibration_output:
            print(f"wrote {args.calibration_output} (samples in {recording.samples_path})")
    elif recording.note:
        print(f"no calibration: {recording.note}")
    if recording.interrupted:
        print(f"ftkin: interrupted: {_resume_advice(args, recording)}", flush=True)
        return 130
    return 0


def _tcp_pose_keeper(source: JointSource):
    """``on_event`` that prints the event and keeps the UR's ``(actual_q, actual_TCP_pose)`` of
    one package (at the pose or on the way: any package will do)."""

    def on_event(event) -> None:
        _print_event(event)
        if event.kind in ("start", "recorded", "same_pose"):
            state = source.joints.state()
            source.tcp_poses.append((state.q, state.tcp_pose))

    return on_event


def _print_calibrate_command(args, recording, source: JointSource) -> None:
    """Without a model: which UR the controller's TCP poses say it is (written to the samples
    file), and the ``ftkin calibrate`` command that finishes the job."""
    from ..calibration.model import STANDARD_GRAVITY
    from ..io.recorded_robot import robot_comment
    from ..kinematics.ur_eseries import UR_DH
    from ..kinematics.ur_flange import identify_ur_arm
    from ..robot.samples_log import append_comment

    if recording.poses_recorded < 3:
        return
    robot = None
    if len(source.tcp_poses) >= 3:
        q, tcp = (np.array(column) for column in zip(*source.tcp_poses))
        identification = identify_ur_arm(q, tcp)
        print(identification.describe())
        robot = identification.robot
        if robot is not None:
            append_comment(
                recording.samples_path,
                robot_comment(robot, f"actual_TCP_pose: {identification.describe()}"),
            )
    words = ["ftkin", "calibrate", str(recording.samples_path), "--robot", robot or "ur5e"]
    if args.calibration_output:
        words += ["-o", args.calibration_output]
    if args.g is not None and args.g != STANDARD_GRAVITY:
        words += ["--g", repr(float(args.g))]
    if robot is None:
        others = ", ".join(name for name in UR_DH if name != "ur5e")
        print(
            "not calibrated: the arm's model is not known; calibrate with its --robot: "
            f"{shlex.join(words)} on a UR5e (--robot {others} for the others, --urdf for a "
            "model of your own)"
        )
    else:
        print(f"not calibrated here (no --robot); finish with: {shlex.join(words)}")


def _run_raw(args) -> int:
    from ..robot.stream_log import log_stream

    refuse(
        InvalidInput,
        (
            bool(args.franka or args.ur),
            "--raw logs the sensor's stream only: leave out --franka/--ur",
        ),
        (not args.sensor, "--raw needs the sensor: --sensor NAME|MODULE:FACTORY"),
        (
            args.resume or args.calibration_output,
            "--raw writes a new stream: no --resume, no --calibrate",
        ),
    )
    sensor = _sensor(args)
    print(
        f"logging the sensor's stream to {args.output}"
        + ("" if args.duration else "; Ctrl-C to stop"),
        flush=True,
    )
    log = log_stream(sensor, args.output, duration=args.duration, stale_after=args.stale_after)
    print(log.report())
    if log.stop_reason == "fault":
        raise SensorError(
            log.fault.kind, f"{log.fault} (the {log.rows} samples before it are in {log.path})"
        )
    return 130 if log.stop_reason == "interrupt" else 0
