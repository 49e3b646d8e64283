"""``ftkin record``: calibration data from an arm ftkin does not drive.

* ``record --franka HOST --sensor SENSOR --n N -o SAMPLES.csv [--resume] [--calibrate CALIB.json]``:
  the arm is moved by hand (or by its own program) and each still phase at a new pose is
  recorded (:func:`~ftkin.robot.recorder.record_poses`), then calibrated;
* ``record --sensor SENSOR -o SAMPLES.csv``: no joint source, the wrench and the sensor's IMU
  only (the calibration from the IMU);
* ``record --raw --sensor SENSOR -o STREAM.csv [--duration S]``: the sensor's stream with its
  stamps, IMU and temperature (:func:`~ftkin.robot.stream_log.log_stream`);
* ``--ur HOST``: a UR controller's joints (and its built-in sensor unless ``--sensor``) through
  ``ftkin.robot.ur.UrArm`` (the UR support of issue 32, imported when asked for).

Ctrl-C keeps whole poses, calibrates from them when it can, says how to continue (``--resume``)
and exits 130; a sensor fault or a lost joint source exits 2 with the same advice. The robot
commands' helpers (the sensor by name, the bundled FR3, the resume advice) are shared with
:mod:`ftkin.cli.robot`.
"""

import logging

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
        skip=("poll_period", "timeout"),
        group="when a pose is still (a loaded simulator needs a larger --stale-after)",
    )
    parser.set_defaults(func=run)


def _print_event(event) -> None:
    print(("  " if event.kind in INDENTED else "") + event.message, flush=True)


def _ur_arm(args):
    """``--ur HOST``: the joints (and the built-in sensor, in ``--wrench-frame``) through
    :class:`ftkin.robot.ur.UrArm`; its stale limit is ``--stale-after``."""
    from ..robot.ur import UrArm

    return UrArm(args.ur, wrench_frame=args.wrench_frame or "base", stale_after=args.stale_after)


def _joint_source(args):
    """``(joints, arm, sensor, close)`` named by the options (``close()`` releases them)."""
    if args.franka and args.ur:
        raise InvalidInput("give one joint source: --franka HOST or --ur HOST")
    if args.wrench_frame is not None and not args.ur:
        raise InvalidInput(
            "--wrench-frame is the axes of a UR's built-in sensor: it goes with --ur"
        )
    if args.ur:
        arm = arm_from_args(args)
        if arm is None:
            raise InvalidInput("--ur needs the arm's kinematics: --robot ur5e (or --urdf)")
        ur = _ur_arm(args)
        sensor = _sensor(args) if args.sensor else ur.sensor
        # the command ends with the process: no 0.5 s wait for ur_rtde's destructor
        return ur, arm, sensor, lambda: ur.close(wait=False)
    if not args.sensor:
        raise InvalidInput("give the sensor: --sensor NAME|MODULE:FACTORY (and --sensor-option)")
    if args.franka:
        from ..robot.franka import FrankaRobot

        arm = _arm(args)
        sensor = _sensor(args)
        robot = FrankaRobot(
            args.franka, realtime=not args.no_realtime, state_timeout=args.state_timeout
        )
        return robot, arm, sensor, lambda: None
    return None, None, _sensor(args), lambda: None


@_closes_sensor
def run(args) -> int:
    if args.raw:
        return _run_raw(args)
    if args.duration is not None:
        raise InvalidInput("--duration goes with --raw (a recording ends at --n poses)")
    from ..robot.recorder import record_poses

    joints, arm, sensor, close = _joint_source(args)
    try:
        recording = record_poses(
            sensor,
            joints,
            arm,
            samples_path=args.output,
            n_poses=resolved(args.n, DEFAULT_POSES),
            readings_per_pose=args.readings_per_pose,
            resume=args.resume,
            stillness=Stillness(**declared_values(Stillness, args)),
            min_pose_angle=float(np.deg2rad(args.min_pose_angle)),
            output=args.calibration_output,
            g=args.g,
            on_event=_print_event,
            # the built-in sensor's wrench came in --wrench-frame axes: checked before the fit
            wrench_frame=(args.wrench_frame or "base") if args.ur and not args.sensor else None,
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
        close()
    if recording.calibration is not None:
        print(recording.calibration.summary())
        if args.calibration_output:
            print(f"wrote {args.calibration_output} (samples in {recording.samples_path})")
    elif recording.note:
        print(f"no calibration: {recording.note}")
    if recording.interrupted:
        print(f"ftkin: interrupted: {_resume_advice(args, recording)}", flush=True)
        return 130
    return 0


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
