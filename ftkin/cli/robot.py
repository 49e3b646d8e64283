"""``ftkin robot calibrate|payload|guide|demo``: ftkin on a robot (a Franka through franky).

* ``calibrate --franka HOST --sensor MODULE:FACTORY -o CALIB.json``: the calibration session
  (:func:`~ftkin.robot.session.calibrate_on_robot`), then the compensated force at a few other
  poses; ``--resume`` finishes an interrupted session;
* ``payload CALIB.json --franka HOST``: the load below the sensor, minus the configured end
  effector, plus the sensor body, sent with ``set_load`` and read back;
* ``guide CALIB.json --franka HOST --sensor MODULE:FACTORY``: hand-guiding until Ctrl-C;
* ``demo``: all of it on franky-sim with a simulated sensor and a push.
"""

import time
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput
from .arg_types import add_options, bounded_int, finite_float, option, positive_float, seed

GUIDING_HOME = (0.0, -0.3, 0.0, -2.2, 0.0, 1.9, 0.785)
"""The demo's hand-guiding start pose [rad] (the hand above the table, pointing down)."""
SIM_TIMEOUT = 0.5
"""The demo's stale-sensor and robot-state limits [s] (0.1 s on a real robot): a busy machine
pauses franky-sim's physics for longer than that."""


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "robot",
        help="on the robot (Franka via franky): calibration session, payload, hand-guiding",
        description="Drive a Franka FR3/Panda through franky-control (pip install "
        "'ftkin[franka]'): run the calibration session, give the payload to the controller, "
        "hand-guide the arm. 'demo' runs everything on franky-sim.",
    )
    commands = parser.add_subparsers(dest="robot_command", metavar="ACTION")
    _calibrate_parser(commands)
    _payload_parser(commands)
    _guide_parser(commands)
    _demo_parser(commands)
    parser.set_defaults(func=lambda args: (parser.print_help(), 2)[1])


def _robot_options(parser, sensor: bool = True) -> None:
    group = parser.add_argument_group("robot and sensor")
    add_options(
        group,
        option("--franka", required=True, metavar="HOST", help="the robot's FCI address"),
        option(
            "--no-realtime",
            action="store_true",
            help="do not require a real-time kernel (franky RealtimeConfig.Ignore: simulators)",
        ),
        option(
            "--speed",
            type=positive_float,
            default=0.3,
            help="fraction of the joint velocity/acceleration limits for moves (default: "
            "%(default)s)",
        ),
    )
    if sensor:
        add_options(
            group,
            option(
                "--sensor",
                required=True,
                metavar="NAME|MODULE:FACTORY",
                help="a built-in sensor (ati: ATI Net F/T, bota: Bota Systems; see "
                "docs/ati-netft.md and docs/bota.md), or an importable factory returning an "
                "object with read() -> (t, wrench)",
            ),
            option(
                "--sensor-option",
                action="append",
                default=[],
                metavar="KEY=VALUE",
                help="an option of the built-in sensor (e.g. host=192.168.1.1, config=bota.json; "
                "an unknown one is refused naming the known ones), or a keyword argument (a "
                "string) for the factory; repeatable",
            ),
        )
    arm = parser.add_argument_group("robot model (default: the bundled FR3, sensor at fr3_hand)")
    add_options(
        arm,
        option("--urdf", metavar="PATH", help="URDF of the arm"),
        option("--sensor-frame", metavar="NAME", help="sensor frame (with --urdf)"),
        option("--tool-frame", metavar="NAME", help="tool frame (with --urdf)"),
    )


def _calibrate_parser(commands) -> None:
    parser = commands.add_parser(
        "calibrate", help="plan, visit, record, calibrate, save, verify (the session)"
    )
    _robot_options(parser)
    add_options(
        parser,
        option("-o", "--output", required=True, metavar="CALIB.json"),
        option(
            "--samples",
            metavar="SAMPLES.csv",
            help="samples file written as the session goes (default: CALIB.samples.csv)",
        ),
        option(
            "--resume", action="store_true", help="continue the samples file of a stopped session"
        ),
        option("--poses", type=bounded_int(3, 200, "poses"), default=12),
        option("--readings", type=bounded_int(1, 100_000, "readings"), default=50),
        option(
            "--verify",
            type=bounded_int(0, 50, "verification poses"),
            default=3,
            help="extra poses to check the calibration at (default: %(default)s); a fault there "
            "stops the arm and exits 1, the calibration saved",
        ),
        option("--seed", type=seed, default=0),
        option(
            "--floor",
            type=finite_float,
            default=0.1,
            metavar="Z",
            help="sensor and tool stay above this height in the base frame [m] (default: 0.1)",
        ),
        option(
            "--joint-range",
            nargs=3,
            action="append",
            default=[],
            metavar=("JOINT", "LOW", "HIGH"),
            help="restrict a joint to [LOW, HIGH] rad; repeatable",
        ),
    )
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
    group = parser.add_argument_group("payload hand-off (flange frame)")
    add_options(
        group,
        option(
            "--end-effector",
            type=finite_float,
            nargs=4,
            metavar=("MASS", "CX", "CY", "CZ"),
            help="the end effector the controller models [kg, m] (default: what the robot reports)",
        ),
        option(
            "--sensor-body",
            type=finite_float,
            nargs=4,
            metavar=("MASS", "CX", "CY", "CZ"),
            help="the sensor's own mass and centre of mass above its measuring plane [kg, m] "
            "(datasheet; default: none)",
        ),
    )


def _guide_parser(commands) -> None:
    parser = commands.add_parser("guide", help="hand-guide the arm until Ctrl-C")
    parser.add_argument("calibration", metavar="CALIB.json")
    _robot_options(parser)
    add_options(
        parser,
        option("--duration", type=positive_float, metavar="S", help="stop after S s"),
        option("--rate", type=positive_float, default=250.0, help="loop rate [Hz]"),
        option("--rotation", action="store_true", help="let the hand turn the tool"),
        option("--gain", type=positive_float, help="translation gain [m/(s·N)] (default: 0.0035)"),
    )
    parser.set_defaults(func=run_guide)


def _demo_parser(commands) -> None:
    parser = commands.add_parser(
        "demo", help="franky-sim: session, payload hand-off, hand-guiding with a push"
    )
    add_options(
        parser,
        option("--poses", type=bounded_int(3, 50, "poses"), default=12),
        option("--speed", type=positive_float, default=0.8),
        option("--push", type=finite_float, default=15.0, metavar="N", help="push force [N]"),
        option(
            "-o", "--output", metavar="CALIB.json", help="keep the calibration (and its samples)"
        ),
    )
    parser.set_defaults(func=run_demo)


# ------------------------------------------------------------------------------------ helpers
def _arm(args):
    from ..kinematics.arm import Arm
    from ..kinematics.fr3 import fr3_arm

    if args.urdf is None:
        if args.sensor_frame or args.tool_frame:
            raise InvalidInput("--sensor-frame and --tool-frame go with --urdf")
        return fr3_arm()
    if not args.sensor_frame:
        raise InvalidInput("--urdf needs --sensor-frame")
    return Arm.from_urdf(args.urdf, args.sensor_frame, args.tool_frame)


def _robot(args):
    from ..robot.franka import FrankaRobot

    return FrankaRobot(args.franka, realtime=not args.no_realtime, speed=args.speed)


def _sensor(args):
    from ..sensors.registry import open_sensor

    options = {}
    for item in args.sensor_option:
        key, equals, value = item.partition("=")
        if not equals or not key.isidentifier():
            raise InvalidInput(f"--sensor-option takes KEY=VALUE, got {item!r}")
        options[key] = value
    sensor = open_sensor(args.sensor, options)
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
    print(f"{label}: {mass:.4f} kg at [{', '.join(f'{v:+.4f}' for v in com)}] m (flange frame)")


# ------------------------------------------------------------------------------------ commands
@_closes_sensor
def run_calibrate(args) -> int:
    from ..robot.session import calibrate_on_robot, default_samples_path, verify_session

    arm = _arm(args)
    plan_options = {"floor_height": args.floor}
    if args.joint_range:
        ranges = {}
        for name, low, high in args.joint_range:
            try:
                ranges[name] = (float(low), float(high))
            except ValueError:
                raise InvalidInput(f"--joint-range {name} needs two numbers [rad]") from None
        plan_options["joint_ranges"] = ranges
    samples = args.samples or str(default_samples_path(args.output))
    sensor = _sensor(args)
    robot = _robot(args)
    result = calibrate_on_robot(
        robot,
        sensor,
        arm,
        n_poses=args.poses,
        readings_per_pose=args.readings,
        samples_path=samples,
        resume=args.resume,
        output=args.output,
        verify_poses=0,
        seed=args.seed,
        plan_options=plan_options,
    )
    print(result.summary())
    print(f"wrote {args.output} (samples in {samples})")
    if args.verify:  # the session's verification, printed here (the library logs it)
        verification = verify_session(
            robot, sensor, arm, result, args.verify, seed=args.seed, plan_options=plan_options
        )
        if verification is None:  # stopped: said in a warning; the calibration stands
            return 1
        print(verification.report())
    return 0


def run_payload(args) -> int:
    from ..io.calibration_file import load_calibration

    calibration = load_calibration(args.calibration)
    arm = _arm(args)
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
    controller = hand_guiding(
        arm, calibration, rotation=args.rotation, force_gain=args.gain or GUIDING_FORCE_GAIN
    )
    sensor = _sensor(args)
    robot = _robot(args)
    print("hand-guiding: push the tool; Ctrl-C to stop")
    stats = run_admittance(robot, sensor, controller, duration=args.duration, rate_hz=args.rate)
    print(stats.report())
    return 0 if stats.stop_reason in ("duration", "interrupt") else 1


def run_demo(args) -> int:
    import tempfile

    from ..io.calibration_file import load_calibration
    from ..kinematics.fr3 import fr3_arm
    from ..robot.franka import FrankaRobot
    from ..robot.franka_sim import FrankaSim
    from ..robot.session import calibrate_on_robot, default_samples_path
    from ..robot.stillness import Stillness

    arm = fr3_arm()
    with tempfile.TemporaryDirectory(prefix="ftkin-robot-demo-") as folder:
        output = args.output or str(Path(folder) / "calib.json")
        samples = default_samples_path(output)
        print("starting franky-sim (FR3, wrist sensor between flange and hand, a 1.2 kg tool)")
        with FrankaSim() as sim:
            robot = FrankaRobot(
                sim.hostname,
                realtime=False,
                speed=args.speed,
                state_timeout=SIM_TIMEOUT,
            )
            started = time.monotonic()
            result = calibrate_on_robot(
                robot,
                sim.sensor,
                arm,
                n_poses=args.poses,
                samples_path=samples,
                output=output,
                g=sim.truth.g,
                plan_options={"joint_ranges": {"fr3_joint1": (-0.8, 0.8)}},
                stillness=Stillness(stale_after=SIM_TIMEOUT),
            )
            truth = sim.truth
            print(f"session: {args.poses} poses in {time.monotonic() - started:.1f} s")
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
