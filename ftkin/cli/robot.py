"""``ftkin robot calibrate|payload|guide|sim|demo``: ftkin on a robot (a Franka through franky).

* ``calibrate --franka HOST --sensor SENSOR -o CALIB.json``: the calibration session
  (:func:`~ftkin.robot.session.calibrate_on_robot`) at planned poses (``--n``) or a plan file
  (``--poses FILE``), then the compensated force at a few other poses; ``--dry-run`` plans and
  prints without moving; ``--resume`` finishes an interrupted session;
* ``payload CALIB.json --franka HOST``: the load below the sensor, minus the configured end
  effector, plus the sensor body, sent with ``set_load`` and read back;
* ``guide CALIB.json --franka HOST --sensor SENSOR``: hand-guiding until Ctrl-C; with
  ``--track-load`` the load in the hand is identified and removed as it is taken (events printed
  as they happen), with ``--send-load`` also sent to the controller with the tool;
* ``sim``: franky-sim's FR3 with its sensor served on a loopback address until Ctrl-C, with the
  ``--franka`` and ``--sensor`` options to use from another terminal;
* ``demo``: all of it on franky-sim with a simulated sensor and a push.

Ctrl-C anywhere stops the arm, prints one line (and, for a session, how to finish it) and exits
130.
"""

import logging
import shlex
import time
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, SessionInterrupted
from ..robot.stillness import Stillness
from .arg_types import add_options, bounded_int, finite_float, option, positive_float
from .common import add_arm_arguments, arm_from_args
from .declared import add_declared, declared_values
from .pose_options import (
    add_constraint_arguments,
    add_readings_argument,
    constraints_from_args,
)
from .shared_options import (
    DEFAULT_POSES,
    DURATION,
    END_EFFECTOR_OPTION,
    FRANKA,
    GRAVITY,
    NO_REALTIME,
    NOISE_FORCE,
    NOISE_TORQUE,
    POSES,
    POSES_FILE,
    RESUME,
    SEED,
    SENSOR,
    SENSOR_BODY_OPTION,
    SENSOR_OPTION,
    SPEED,
    STATE_TIMEOUT,
    TOOL_MASS,
    TRACK_LOAD,
    as_required,
    noise_from_args,
    open_named_sensor,
    resolved,
)

logger = logging.getLogger("ftkin.cli")

GUIDING_HOME = (0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785)
"""The demo's hand-guiding start pose [rad] (the hand above the table, pointing down)."""
SIM_TIMEOUT = 2.0
"""The stale-sensor and robot-state limits [s] for franky-sim (0.1 s on a real robot): a loaded
machine pauses the simulated physics for longer than 0.1 s (0.73 s was seen at load 2, 1.9 s at
load 3.6)."""
SIM_ARM_OPTIONS = "--no-realtime --state-timeout 2 --stale-after 2"
"""What a command pointed at ``ftkin robot sim`` adds for the simulator."""


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "robot",
        help="on the robot (Franka via franky): calibration session, payload, hand-guiding",
        description="Drive a Franka FR3/Panda through franky-control (the franka extra: pip "
        "install -e '.[franka]' from the checkout): run the calibration session, give the "
        "payload to the controller, hand-guide the arm. 'sim' serves a simulated FR3 to try "
        "them on; 'demo' runs everything on franky-sim.",
    )
    commands = parser.add_subparsers(dest="robot_command", metavar="ACTION")
    _calibrate_parser(commands)
    _payload_parser(commands)
    _guide_parser(commands)
    _sim_parser(commands)
    _demo_parser(commands)
    parser.set_defaults(func=lambda args: (parser.print_help(), 2)[1])


def _robot_options(parser, sensor: bool = True, required: bool = True) -> None:
    group = parser.add_argument_group("robot and sensor")
    add_options(group, as_required(FRANKA, required), NO_REALTIME, SPEED, STATE_TIMEOUT)
    if sensor:
        add_options(group, SENSOR, SENSOR_OPTION)
    add_arm_arguments(parser)


def _stillness_options(parser) -> None:
    add_declared(
        parser,
        Stillness,
        skip=("poll_period",),
        group="when a pose is still (a loaded simulator needs a larger --stale-after)",
    )


def _calibrate_parser(commands) -> None:
    parser = commands.add_parser(
        "calibrate", help="plan, visit, record, calibrate, save, verify (the session)"
    )
    _robot_options(parser, required=False)
    add_options(
        parser,
        option("-o", "--output", required=True, metavar="CALIB.json"),
        option(
            "--samples",
            metavar="SAMPLES.csv",
            help="samples file written as the session goes (default: CALIB.samples.csv)",
        ),
        RESUME,
        POSES_FILE,
        POSES,
        option(
            "--dry-run",
            action="store_true",
            help="plan (or read) the poses, print them with their predicted standard errors and "
            "write them to CALIB.poses.csv; connect to nothing, move nothing",
        ),
        option(
            "--verify",
            type=bounded_int(0, 50, "verification poses"),
            default=3,
            help="extra poses to check the calibration at (default: %(default)s); a fault there "
            "stops the arm and exits 1, the calibration saved",
        ),
        SEED,
        GRAVITY,
    )
    add_readings_argument(parser)
    add_constraint_arguments(parser)
    _stillness_options(parser)
    parser.set_defaults(func=run_calibrate)


def _payload_parser(commands) -> None:
    parser = commands.add_parser(
        "payload", help="send the measured load (minus the end effector) to the controller"
    )
    parser.add_argument("calibration", metavar="CALIB.json")
    _robot_options(parser, sensor=False)
    _payload_options(parser)
    parser.set_defaults(func=run_payload)


def _payload_options(parser) -> None:
    group = parser.add_argument_group("payload hand-off (flange frame fr3_link8)")
    add_options(group, END_EFFECTOR_OPTION, SENSOR_BODY_OPTION)


def _guide_parser(commands) -> None:
    parser = commands.add_parser("guide", help="hand-guide the arm until Ctrl-C")
    parser.add_argument("calibration", metavar="CALIB.json")
    _robot_options(parser)
    add_options(
        parser,
        DURATION,
        option(
            "--loop-rate",
            type=positive_float,
            default=250.0,
            metavar="HZ",
            help="control loop rate [Hz] (default: %(default)s)",
        ),
        option("--rotation", action="store_true", help="let the hand turn the tool"),
        option("--gain", type=positive_float, help="translation gain [m/(s·N)] (default: 0.0035)"),
    )
    add_declared(parser, Stillness, only=("stale_after",))
    load = parser.add_argument_group("the load in the hand (docs/load.md)")
    add_options(
        load,
        TRACK_LOAD,
        option(
            "--send-load",
            action="store_true",
            help="with --track-load: send the tool's payload at the start and the tool and the "
            "held load on each settled grasp (again once the wrist turned), the tool alone on a "
            "release (franky set_load, flange frame fr3_link8)",
        ),
        NOISE_FORCE,
        NOISE_TORQUE,
    )
    _payload_options(parser)
    parser.set_defaults(func=run_guide)


def _sim_parser(commands) -> None:
    parser = commands.add_parser(
        "sim",
        help="serve franky-sim's FR3 with a wrist sensor on a loopback address until Ctrl-C",
        description="Serve a simulated FR3 (franky-sim: the libfranka protocol on a loopback "
        "address) with a wrist sensor and a tool, and print the --franka and --sensor options "
        "that point 'ftkin robot calibrate', 'payload' and 'guide' at it from another terminal.",
    )
    add_options(
        parser,
        TOOL_MASS,
        SEED,
    )
    parser.set_defaults(func=run_sim)


def _demo_parser(commands) -> None:
    parser = commands.add_parser(
        "demo", help="franky-sim: session, payload hand-off, hand-guiding with a push"
    )
    add_options(
        parser,
        POSES,
        SPEED,
        option("--push", type=finite_float, default=15.0, metavar="N", help="push force [N]"),
        option(
            "-o", "--output", metavar="CALIB.json", help="keep the calibration (and its samples)"
        ),
    )
    parser.set_defaults(func=run_demo)


# ------------------------------------------------------------------------------------ helpers
def _arm(args):
    """The arm the options name (``--robot``, ``--urdf``, ...), else the bundled FR3 (its tool
    frame ``--tool-frame``, its sensor frame ``fr3_hand``)."""
    from ..kinematics.fr3 import FR3_SENSOR_FRAME, FR3_TOOL_FRAME, fr3_arm

    if args.urdf is None and args.robot is None:
        if args.sensor_frame not in (None, FR3_SENSOR_FRAME) or args.sensor_offset is not None:
            raise InvalidInput(
                "the bundled FR3's sensor frame is fr3_hand: --sensor-frame and --sensor-offset "
                "go with --urdf (or --robot for a robot without a sensor frame)"
            )
        return fr3_arm(args.tool_frame or FR3_TOOL_FRAME)
    return arm_from_args(args)


def _robot(args):
    from ..robot.franka import FrankaRobot

    return FrankaRobot(
        args.franka,
        realtime=not args.no_realtime,
        speed=resolved(args.speed, 0.3),
        state_timeout=args.state_timeout,
    )


def _sensor(args):
    if args.sensor is None:
        raise InvalidInput("give --sensor SENSOR (a built-in sensor or MODULE:FACTORY)")
    sensor = open_named_sensor(args)
    if callable(getattr(sensor, "close", None)):  # a built-in adapter: closed by _closes_sensor
        vars(args).setdefault("opened_sensors", []).append(sensor)
    return sensor


def _closes_sensor(run):
    """``run(args)``, then close the sensors ``_sensor`` opened for it (a built-in adapter
    releases its vendor's client: a Bota driver is deactivated and shut down)."""

    def command(args) -> int:
        try:
            return run(args)
        finally:
            for sensor in vars(args).pop("opened_sensors", []):
                sensor.close()

    command.__doc__ = run.__doc__
    return command


def _body(values):
    from ..io.payload_inertia import RigidBody

    return None if values is None else RigidBody.point(values[0], values[1:])


def _print_load(label: str, mass: float, com) -> None:
    print(
        f"{label}: {mass:.4f} kg at [{', '.join(f'{v:+.4f}' for v in com)}] m (flange frame "
        "fr3_link8)"
    )


def _plan_options(args) -> dict:
    constraints = constraints_from_args(args)
    return {
        "margin": constraints.margin,
        "floor_height": constraints.floor_height,
        "max_tilt": constraints.max_tilt,
        "joint_ranges": constraints.joint_ranges,
        "self_collision": constraints.self_collision,
        "clearance": constraints.clearance,
    }


def _resume_advice(args, error: SessionInterrupted) -> str:
    """The command that finishes an interrupted session: this one with --resume."""
    words = [word for word in shlex.split(getattr(args, "command_line", "")) if word]
    if not words:
        words = ["ftkin", "robot", "calibrate", "..."]
    if "--resume" not in words:
        words.append("--resume")
    return (
        f"{error.poses_recorded} of {error.poses_total} poses are in {error.samples_path}; "
        f"finish the session with: {shlex.join(words)}"
    )


# ------------------------------------------------------------------------------------ commands
@_closes_sensor
def run_calibrate(args) -> int:
    from ..robot.session import (
        calibrate_on_robot,
        check_given_poses,
        default_samples_path,
        session_poses,
        verify_session,
    )

    arm = _arm(args)
    plan_options = _plan_options(args)
    stillness = Stillness(**declared_values(Stillness, args))
    if args.poses is not None:
        from ..io.csv_table import read_table
        from ..io.samples_csv import configurations_from_table

        poses = check_given_poses(
            arm, configurations_from_table(read_table(args.poses), arm), plan_options
        )
    else:
        poses = session_poses(
            arm,
            resolved(args.n, DEFAULT_POSES),
            seed=args.seed,
            readings_per_pose=args.readings_per_pose,
            plan_options=plan_options,
        )
    if args.dry_run:
        return _dry_run(args, arm, poses)
    if not args.franka or not args.sensor:
        raise InvalidInput("give --franka HOST and --sensor SENSOR (or --dry-run to only plan)")
    samples = args.samples or str(default_samples_path(args.output))
    sensor = _sensor(args)
    robot = _robot(args)
    try:
        result = calibrate_on_robot(
            robot,
            sensor,
            arm,
            poses=poses,
            readings_per_pose=args.readings_per_pose,
            samples_path=samples,
            resume=args.resume,
            output=args.output,
            verify_poses=0,
            seed=args.seed,
            plan_options=plan_options,
            stillness=stillness,
            g=args.g,
        )
    except SessionInterrupted as error:
        return _interrupted(args, error)
    print(result.summary())
    print(f"wrote {args.output} (samples in {samples})")
    if args.verify:  # the session's verification, printed here (the library logs it)
        verification = verify_session(
            robot,
            sensor,
            arm,
            result,
            args.verify,
            seed=args.seed,
            plan_options=plan_options,
            stillness=stillness,
        )
        if verification is None:  # stopped: said in a warning; the calibration stands
            return 1
        print(verification.report())
    return 0


def _interrupted(args, error: SessionInterrupted) -> int:
    """Ctrl-C: exit 130 and say how to finish; any other stop: the error (exit 2)."""
    if error.reason.startswith("interrupted"):
        print(f"ftkin: interrupted: the arm is stopped; {_resume_advice(args, error)}")
        return 130
    raise InvalidInput(f"{error.reason}; the arm is stopped; {_resume_advice(args, error)}")


def _dry_run(args, arm, poses: np.ndarray) -> int:
    from ..io.csv_table import write_csv
    from ..planning.evaluation import ExpectedCalibration, evaluate_poses
    from ..robot.session import DEFAULT_TOOL_WEIGHT, default_samples_path

    expected = ExpectedCalibration(
        tool_weight=DEFAULT_TOOL_WEIGHT, readings_per_pose=args.readings_per_pose
    )
    print(f"dry run: {len(poses)} poses for {arm!r}; nothing moves")
    print(evaluate_poses(arm.rotation_sensor_to_base(poses), expected).report())
    for index, q in enumerate(poses):
        print(f"  pose {index:>3}  " + " ".join(f"{value:+.4f}" for value in q))
    path = Path(default_samples_path(args.output)).with_name(Path(args.output).stem + ".poses.csv")
    write_csv(path, ["pose", *arm.joint_names], [[i, *q] for i, q in enumerate(poses.tolist())])
    print(f"wrote {path} (ftkin robot calibrate --poses {path} visits them)")
    return 0


def run_payload(args) -> int:
    from ..io.calibration_file import load_calibration
    from ..io.export import recorded_arm

    calibration = load_calibration(args.calibration)
    arm = _arm(args)  # the options checked; none given: the calibration's arm, else the FR3
    if args.urdf is None and args.robot is None:
        arm = recorded_arm(calibration) or arm
    robot = _robot(args)
    load = robot.set_payload(
        calibration,
        arm=arm,
        end_effector=_body(args.end_effector),
        sensor_mass=0.0 if args.sensor_body is None else args.sensor_body[0],
        sensor_com=(0.0, 0.0, 0.0) if args.sensor_body is None else args.sensor_body[1:],
    )
    _print_load("sent", load.mass, load.center_of_mass)
    mass, com, _ = robot.payload()
    _print_load("the robot reports", mass, com)
    return 0


@_closes_sensor
def run_guide(args) -> int:
    from ..io.calibration_file import load_calibration
    from ..robot.guiding import GUIDING_FORCE_GAIN, hand_guiding
    from ..robot.loop import run_admittance

    calibration = load_calibration(args.calibration)
    arm = _arm(args)
    tracker = _load_tracker(args, calibration)  # its options checked before a sensor opens
    sensor = _sensor(args)
    # a calibration with the IMU's parameters and a sensor that gives its IMU: compensate with it
    from ..calibration.imu_result import ImuCalibrationResult

    imu = isinstance(calibration, ImuCalibrationResult) and callable(
        getattr(sensor, "read_sample", None)
    )
    if imu:
        print("compensating with the sensor's IMU (the tool's acceleration removed)")
    controller = hand_guiding(
        arm,
        calibration,
        rotation=args.rotation,
        force_gain=args.gain or GUIDING_FORCE_GAIN,
        imu=imu,
        load=tracker,
    )
    robot = _robot(args)
    on_tick = None
    if tracker is not None:
        on_tick = _LoadReport(tracker, _load_handoff(args, robot, arm, calibration, tracker))
    mass, _, _ = robot.payload()
    if not mass > 0.0:
        logger.warning(
            "the robot reports no payload: its gravity model misses the tool, and the arm will "
            "creep; send it first with: ftkin robot payload %s --franka %s",
            args.calibration,
            args.franka,
        )
    print("hand-guiding: push the tool; Ctrl-C to stop")
    stats = run_admittance(
        robot,
        sensor,
        controller,
        duration=args.duration,
        rate_hz=args.loop_rate,
        stale_after=args.stale_after,
        on_tick=on_tick,
    )
    print(stats.report())
    if stats.stop_reason == "interrupt":
        return 130
    return 0 if stats.stop_reason == "duration" else 1


def _load_tracker(args, calibration):
    """The guide's load tracker (``--track-load``), its noise the flags' or the calibration's."""
    from ..control.load_events import LoadTracker

    noise = noise_from_args(args)
    if not args.track_load:
        if args.send_load or noise is not None:
            raise InvalidInput("--send-load, --noise-force and --noise-torque go with --track-load")
        return None
    tracker = LoadTracker.for_calibration(calibration, noise, period=1.0 / args.loop_rate)
    print(
        f"load tracking: noise per reading {np.array2string(tracker.noise.force_std, precision=4)}"
        f" N, {np.array2string(tracker.noise.torque_std, precision=5)} N·m; bounds "
        f"{tracker.thresholds.k_sigma:g}σ"
    )
    return tracker


def _load_handoff(args, robot, arm, calibration, tracker):
    """``--send-load``: the hand-off, after sending the tool alone; None without the flag."""
    if not args.send_load:
        return None
    from ..robot.load_handoff import LoadHandoff

    handoff = LoadHandoff(
        robot,
        calibration,
        tracker,
        arm,
        end_effector=_body(args.end_effector),
        sensor_mass=0.0 if args.sensor_body is None else args.sensor_body[0],
        sensor_com=(0.0, 0.0, 0.0) if args.sensor_body is None else args.sensor_body[1:],
    )
    load = handoff.send("start", robot.joint_positions())
    _print_load("sent the tool", load.mass, load.center_of_mass)
    return handoff


class _LoadReport:
    """The guide loop's ``on_tick`` with ``--track-load``: each event printed as it is decided
    (seconds since the loop's first tick), and with ``--send-load`` the load sent."""

    def __init__(self, tracker, handoff):
        from ..robot.load_handoff import MotionFlag

        self.tracker, self.handoff, self.motion = tracker, handoff, MotionFlag(tracker)
        self.seen, self.start, self.holding, self.refreshed = 0, None, None, -1.0

    def __call__(self, now: float, q, command) -> None:
        if self.start is None:
            self.start = now
        self.motion.update(now, command)  # the hand moves the arm: not a still reading
        if self.tracker.state == "holding" and now - self.refreshed > 0.5:
            self.holding, self.refreshed = self.tracker.estimate(), now  # for a release's line
        events = self.tracker.events
        for event in events[self.seen :]:
            print(f"t {now - self.start:.3f} s: {event.kind} ({self._mass(event)})", flush=True)
        self.seen = len(events)
        if self.handoff is not None:
            count = len(self.handoff.sent)
            load = self.handoff.update(q)
            if load is not None:
                why = self.handoff.sent[count][0]
                _print_load(f"sent the tool and the load ({why})", load.mass, load.center_of_mass)

    def _mass(self, event) -> str:
        estimate = self.tracker.estimate()
        if event.kind == "grasp" and estimate is not None:
            self.holding, self.refreshed = estimate, -1.0
            return f"mass {estimate.mass:.4f} ± {estimate.mass_std:.2g} kg"
        if event.kind == "release" and self.holding is not None:
            held, self.holding = self.holding, None
            return f"the load of {held.mass:.4f} ± {held.mass_std:.2g} kg set down"
        return f"mass step {event.mass:.4f} kg: {event.reason}"


def run_sim(args) -> int:
    from ..robot.franka_sim import FrankaSim, SimTool

    mass = resolved(args.tool_mass, 1.2)
    tool = SimTool(mass=mass)
    print(f"starting franky-sim (FR3, wrist sensor between flange and hand, a {mass:g} kg tool)")
    with FrankaSim(tool) as sim:
        truth = sim.truth
        com = ", ".join(f"{v:+.4f}" for v in truth.center_of_mass)
        print(
            f"serving the simulated FR3 at {sim.hostname} until Ctrl-C; below the sensor: "
            f"{truth.mass:.4f} kg, centre of mass [{com}] m (fr3_hand), g = {truth.g} m/s²"
        )
        robot = f"--franka {sim.hostname} {SIM_ARM_OPTIONS}"
        body = " ".join(f"{v:g}" for v in (truth.sensor_mass, *truth.sensor_com_flange))
        print("from another terminal:")
        print(f"  ftkin robot calibrate {robot} {sim.sensor_spec()} --g {truth.g} -o calib.json")
        print(
            f"  ftkin robot payload calib.json --franka {sim.hostname} --no-realtime "
            f"--state-timeout 2 --sensor-body {body}"
        )
        print(f"  ftkin robot guide calib.json {robot} {sim.sensor_spec()}", flush=True)
        try:
            while sim.alive:
                time.sleep(0.2)
        except KeyboardInterrupt:
            print("stopping the simulation")
            return 130
    print("ftkin: error: the simulation stopped", flush=True)
    return 1


def run_demo(args) -> int:
    import tempfile

    from ..io.calibration_file import load_calibration
    from ..kinematics.fr3 import fr3_arm
    from ..robot.franka import FrankaRobot
    from ..robot.franka_sim import FrankaSim
    from ..robot.session import calibrate_on_robot, default_samples_path

    arm = fr3_arm()
    with tempfile.TemporaryDirectory(prefix="ftkin-robot-demo-") as folder:
        output = args.output or str(Path(folder) / "calib.json")
        samples = default_samples_path(output)
        print("starting franky-sim (FR3, wrist sensor between flange and hand, a 1.2 kg tool)")
        with FrankaSim() as sim:
            robot = FrankaRobot(
                sim.hostname,
                realtime=False,
                speed=resolved(args.speed, 0.8),
                state_timeout=SIM_TIMEOUT,
            )
            started = time.monotonic()
            try:
                result = calibrate_on_robot(
                    robot,
                    sim.sensor,
                    arm,
                    n_poses=resolved(args.n, DEFAULT_POSES),
                    samples_path=samples,
                    output=output,
                    g=sim.truth.g,
                    plan_options={"joint_ranges": {"fr3_joint1": (-0.8, 0.8)}},
                    stillness=Stillness(stale_after=SIM_TIMEOUT),
                )
            except SessionInterrupted as error:
                if not error.reason.startswith("interrupted"):
                    raise
                kept = (
                    f"the samples are in {samples} (ftkin calibrate {samples} --robot fr3)"
                    if args.output
                    else "the demo kept nothing (give -o CALIB.json to keep its samples)"
                )
                print(f"ftkin: interrupted: the arm is stopped; {kept}")
                return 130
            truth = sim.truth
            seconds = time.monotonic() - started
            print(f"session: {resolved(args.n, DEFAULT_POSES)} poses in {seconds:.1f} s")
            print(f"  mass {result.tool_mass:.4f} kg (truth {truth.mass:.4f})")
            com_error = np.linalg.norm(result.center_of_mass - truth.center_of_mass) * 1e3
            bias_error = np.abs(result.force_offset - truth.bias[:3]).max()
            print(f"  centre of mass error {com_error:.3f} mm, force bias error {bias_error:.4f} N")
            load = robot.set_payload(
                load_calibration(output),
                sensor_mass=truth.sensor_mass,
                sensor_com=truth.sensor_com_flange,
            )
            _print_load("payload sent", load.mass, load.center_of_mass)
            _print_load("robot reports", *robot.payload()[:2])
            _demo_guiding(args, sim, robot, arm, result)
    return 0


def _demo_guiding(args, sim, robot, arm, result) -> None:
    """The demo's last act: a push on the simulated hand while the hand-guiding loop runs."""
    from ..robot.guiding import hand_guiding
    from ..robot.loop import run_admittance
    from ..robot.stillness import wait_still

    robot.move_to(GUIDING_HOME)
    wait_still(robot)
    controller = hand_guiding(arm, result)
    start = sim.hand_position()
    sim.push([args.push, 0.0, 0.0], 1.0, delay=0.3)
    stats = run_admittance(robot, sim.sensor, controller, duration=2.5, stale_after=SIM_TIMEOUT)
    moved = (sim.hand_position() - start) * 1e3
    print(
        f"hand-guiding: a {args.push:g} N push along x for 1 s moved the hand "
        f"[{', '.join(f'{v:+.1f}' for v in moved)}] mm"
    )
    print(stats.report())
