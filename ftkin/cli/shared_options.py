"""The options several commands take: one definition each, so that every command spells,
defaults and explains them identically (``tests/cli/test_flags.py`` walks the parsers).

Where commands need different values for an option, the definition's default is None and its
help names each command's value (``--duration``: 30 s for an excitation, 5 s for a placement);
the command resolves None with :func:`resolved`. The pose constraints and readings per pose are
in :mod:`ftkin.cli.pose_options`; options of a library type come from its declarations
(:mod:`ftkin.cli.declared`).
"""

import argparse
import logging
import os

from ..calibration.fit_options import CalibrationOptions
from ..io.payload_export import END_EFFECTOR, SENSOR_BODY
from ..planning.evaluation import PAPER_CENTER_OF_MASS
from .arg_types import (
    number_list,
    option,
    positive_float,
    refuse,
    seed,
    whole_number,
)
from .declared import declared_option

logger = logging.getLogger("ftkin.cli")

DEFAULT_POSES = 12
"""Poses when ``--n`` is not given (``plan`` asks for it: it has ``--excitation`` besides)."""
MAX_POSES = 500
"""Largest ``--n``: beyond a few dozen poses the standard errors only fall as 1/√n."""


def pose_count(text: str) -> int:
    """argparse type: a number of poses, 3 to :data:`MAX_POSES`."""
    value = whole_number(text, "poses")
    refuse(
        argparse.ArgumentTypeError,
        (value < 3, f"at least 3 poses are needed to determine the calibration, got {text}"),
        (
            value > MAX_POSES,
            f"expected 3 to {MAX_POSES} poses, got {text}: beyond a few dozen poses the standard "
            "errors only fall as 1/√n (average readings with --readings-per-pose instead)",
        ),
    )
    return value


def poses_file(text: str) -> str:
    """argparse type: the name of a poses file (``--poses``). A whole number that names no file
    is refused with ``--n`` named: the number of poses is ``--n N``, not ``--poses N``."""
    if text.strip().isdigit() and not os.path.exists(text):
        raise argparse.ArgumentTypeError(
            f"{text!r} is no file: --poses names a poses file (ftkin plan -o POSES.csv); the "
            f"number of poses is --n {text.strip()}"
        )
    return text


POSES = option(
    "--n",
    type=pose_count,
    default=None,
    metavar="N",
    help=f"number of poses, 3 to {MAX_POSES} (default: {DEFAULT_POSES}; plan: required without "
    "--excitation)",
)
POSES_FILE = option(
    "--poses",
    type=poses_file,
    metavar="POSES.csv",
    help="a poses file (ftkin plan -o POSES.csv): simulate writes readings at these poses, robot "
    "calibrate visits them, checked against the constraints before the arm moves (default: "
    "--n random or planned poses)",
)
SEED = option(
    "--seed",
    type=seed,
    default=0,
    help="seed of the random draws (poses, the planner's search, simulated noise): the same seed "
    "gives the same result (default: %(default)s)",
)
GRAVITY = declared_option(CalibrationOptions, "g")
METHOD = declared_option(CalibrationOptions, "method")
TRACK_LOAD = option(
    "--track-load",
    action="store_true",
    help="identify the load in the hand as it is taken and remove it with the tool "
    "(ftkin.control.LoadTracker; docs/load.md): compensate adds load_mass, load_mass_std [kg], "
    "load_com_x/y/z [m, sensor frame] and load_event (empty, grasp, holding, release, contact, "
    "tool_change) per row and writes the contact after tool and load (a 'gripper' column, 1 "
    "closed, 0 open, is used when the log has one); live, the events print as they happen",
)
NOISE_FORCE = option(
    "--noise-force",
    type=positive_float,
    default=None,
    metavar="N",
    help="noise (standard deviation) of one force reading [N], with --noise-torque (default: "
    "calibrate estimates it from the readings; plan and evaluate-poses assume the paper's 0.02 N)",
)
NOISE_TORQUE = option(
    "--noise-torque",
    type=positive_float,
    default=None,
    metavar="NM",
    help="noise of one torque reading [N·m], with --noise-force (default: calibrate estimates "
    "it; plan and evaluate-poses assume the paper's 0.002 N·m)",
)


def noise_from_args(args, default=None):
    """The :class:`~ftkin.SensorNoise` of ``--noise-force`` and ``--noise-torque`` (both, or
    neither: then ``default``); one without the other is refused, by every command alike."""
    from ..calibration.information import SensorNoise
    from ..exceptions import InvalidInput

    if (args.noise_force is None) != (args.noise_torque is None):
        raise InvalidInput(
            "give both --noise-force [N] and --noise-torque [N·m], or neither (calibrate: "
            "estimated; plan and evaluate-poses: the paper's)"
        )
    return default if args.noise_force is None else SensorNoise(args.noise_force, args.noise_torque)


CENTER_OF_MASS = option(
    "--com",
    type=number_list,
    default=None,
    metavar="X Y Z",
    help="tool centre of mass in the sensor frame [m] (default: the paper's tool, "
    + " ".join(f"{v:g}" for v in PAPER_CENTER_OF_MASS)
    + ")",
)
TOOL_MASS = option(
    "--tool-mass",
    type=positive_float,
    default=None,
    metavar="KG",
    help="mass of the simulated tool [kg] (default: the paper's 0.3217 kg; robot sim: 1.2 kg)",
)
ESTIMATE_MOUNT = declared_option(CalibrationOptions, "estimate_mount")
SENSOR_SIGN = declared_option(CalibrationOptions, "sensor_sign")
IMU_POSITION = option(
    "--imu-position",
    type=number_list,
    default=None,
    metavar="X Y Z",
    help="the IMU's position in the sensor frame [m] (a datasheet value): its accelerometer "
    "reads the lever-arm terms of a turning tool (default: calibrate --dynamic estimates it, a "
    "static IMU calibration records none)",
)
DURATION = option(
    "--duration",
    type=positive_float,
    default=None,
    metavar="S",
    help="length [s] (default: plan --excitation 30; simulate placement and log 5, recording 10; "
    "robot guide, compensate --live and record --raw: until Ctrl-C)",
)
NO_CONVENTION_CHECK = option(
    "--no-convention-check",
    action="store_true",
    help="do not refit under the common convention mistakes (see 'ftkin doctor'; compensate: "
    "do not read the log under them against the calibration)",
)
SENSOR = option(
    "--sensor",
    metavar="NAME|MODULE:FACTORY",
    help="a built-in sensor (ati: ATI Net F/T, bota: Bota Systems; see docs/ati-netft.md and "
    "docs/bota.md), or an importable factory returning an object with read() -> (t, wrench) "
    "(robot sim prints its simulated sensor's; compensate --live: instead of the UR's own)",
)
SENSOR_OPTION = option(
    "--sensor-option",
    action="append",
    default=[],
    metavar="KEY=VALUE",
    help="an option of the built-in sensor (e.g. host=192.168.1.1, config=bota.json; an unknown "
    "one is refused naming the known ones), or a keyword argument (a string) for the factory; "
    "repeatable",
)


def open_named_sensor(args):
    """The sensor ``--sensor`` and ``--sensor-option`` name (:func:`ftkin.sensors.open_sensor`)."""
    from ..exceptions import InvalidInput
    from ..sensors.registry import open_sensor

    options = {}
    for item in args.sensor_option:
        key, equals, value = item.partition("=")
        if not equals or not key.isidentifier():
            raise InvalidInput(f"--sensor-option takes KEY=VALUE, got {item!r}")
        options[key] = value
    return open_sensor(args.sensor, options)


SPEED = option(
    "--speed",
    type=positive_float,
    default=None,
    help="fraction of the joint velocity and acceleration limits for moves (default: 0.3; "
    "robot demo: 0.8)",
)


DEFAULT_STATE_TIMEOUT = 0.1
"""The robot's clock not advancing this long is a lost connection [s] (a real FR3 at 1 kHz)."""
FRANKA = option(
    "--franka",
    metavar="HOST",
    help="the robot's FCI address (ftkin robot sim prints its own)",
)
NO_REALTIME = option(
    "--no-realtime",
    action="store_true",
    help="do not require a real-time kernel (franky RealtimeConfig.Ignore: simulators)",
)
STATE_TIMEOUT = option(
    "--state-timeout",
    type=positive_float,
    default=DEFAULT_STATE_TIMEOUT,
    metavar="S",
    help="the robot's clock not advancing this long is a lost connection [s] (default: "
    "%(default)s; 2 for a simulator on a loaded machine)",
)
WRENCH_FRAME = option(
    "--wrench-frame",
    choices=("sensor", "base"),
    default=None,
    help="frame the bag's (or the UR's) wrenches are expressed in; base: rotate them into "
    "the sensor frame (a UR TCP force) (default: sensor; with --ur: base, UR's convention for "
    "ft_raw_wrench, checked against the arm's motion)",
)
UR = option(
    "--ur",
    metavar="HOST",
    help="the UR controller's address (RTDE, port 30004): its joints and, unless --sensor, its "
    "built-in sensor (compensate --live, record; record asks its dashboard, port 29999, for the "
    "arm's model when --robot is not given)",
)
RESUME = option(
    "--resume",
    action="store_true",
    help="continue the samples file of a stopped session or recording (robot calibrate: the "
    "same plan; record: its poses count towards --n)",
)


def as_required(definition: tuple, is_required: bool = True) -> tuple:
    """A shared option made required (or not) by a command: the same flag, help and default."""
    flags, keywords = definition
    return flags, {**keywords, "required": is_required}


def payload_body_option(spec) -> tuple:
    """``--end-effector`` or ``--sensor-body`` as the payload export declares it
    (:data:`~ftkin.io.payload_export.END_EFFECTOR`, :data:`~ftkin.io.payload_export.SENSOR_BODY`):
    ``ftkin export`` and ``ftkin robot payload`` take the same option."""
    return option(spec.flag, dest=spec.name, default=None, help=spec.help, **spec.argparse)


END_EFFECTOR_OPTION = payload_body_option(END_EFFECTOR)
SENSOR_BODY_OPTION = payload_body_option(SENSOR_BODY)


def resolved(value, default):
    """``value``, or the command's ``default`` when the option was not given (None)."""
    return default if value is None else value
