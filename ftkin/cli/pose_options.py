"""Pose constraints and readings per pose: one definition for ``plan``, ``evaluate-poses``,
``simulate samples`` and ``robot calibrate``.

Every command that plans or visits calibration poses takes these flags with the same spelling,
default and help (``tests/cli/test_flags.py`` walks the parsers): ``--margin``,
``--floor-height`` / ``--no-floor``, ``--max-tilt-deg``, ``--joint-range NAME:LO:HI``,
``--no-self-collision`` (:class:`~ftkin.planning.constraints.PoseConstraints`) and
``--readings-per-pose``.
"""

import argparse
import logging

import numpy as np

from ..exceptions import InvalidInput
from ..planning.constraints import DEFAULT_FLOOR_HEIGHT, DEFAULT_MARGIN, PoseConstraints
from .arg_types import (
    add_options,
    bounded_int,
    floor_height,
    non_negative_float,
    option,
    refuse,
)

logger = logging.getLogger("ftkin.cli")

DEFAULT_READINGS_PER_POSE = 50
"""Readings per pose: what ``robot calibrate`` records at each pose and what ``plan`` predicts
the standard errors for (one value, so that a plan's prediction is the session's)."""


def joint_range(text: str) -> tuple[str, float, float]:
    """argparse type: ``NAME:LO:HI`` [rad]."""
    parts = text.rsplit(":", 2)
    try:
        if len(parts) != 3 or not parts[0]:
            raise ValueError
        low, high = float(parts[1]), float(parts[2])
    except ValueError:
        raise argparse.ArgumentTypeError(
            f"expected NAME:LO:HI with LO, HI in radians, got {text!r}"
        ) from None
    refuse(
        argparse.ArgumentTypeError,
        (
            not (np.isfinite(low) and np.isfinite(high)),
            f"expected finite LO and HI [rad], got {text!r}",
        ),
        (
            max(abs(low), abs(high)) > 2.0 * np.pi,
            f"{text!r}: LO and HI are beyond 2π: ranges are in radians (these look like degrees)",
        ),
        (low > high, f"{text!r}: LO must not exceed HI"),
    )
    return parts[0], low, high


CONSTRAINT_OPTIONS = (
    option(
        "--margin",
        type=non_negative_float,
        default=DEFAULT_MARGIN,
        metavar="RAD",
        help="distance kept from the joint limits [rad] (default: %(default)s)",
    ),
    option(
        "--floor-height",
        type=floor_height,
        default=DEFAULT_FLOOR_HEIGHT,
        metavar="M",
        help="sensor and tool origins stay above this height in the base frame [m] (default: "
        "%(default)s, a floor at base z = 0 with a 10 cm margin)",
    ),
    option(
        "--no-floor",
        action="store_true",
        help="no floor constraint (an arm mounted on a wall or ceiling)",
    ),
    option(
        "--max-tilt-deg",
        type=non_negative_float,
        default=None,
        metavar="DEG",
        help="largest angle of the tool axis from pointing straight down [deg]",
    ),
    option(
        "--joint-range",
        type=joint_range,
        action="append",
        default=[],
        metavar="NAME:LO:HI",
        help="extra range for one joint [rad]; repeat for several joints",
    ),
    option("--no-self-collision", action="store_true", help="do not check self-collision"),
)
"""The pose constraints (:func:`constraints_from_args`)."""

READINGS_PER_POSE = option(
    "--readings-per-pose",
    type=bounded_int(1, 10**6, "readings per pose"),
    default=DEFAULT_READINGS_PER_POSE,
    metavar="K",
    help="readings at each pose (recorded on a robot or simulated; a plan predicts its standard "
    "errors for them) (default: %(default)s)",
)


class DeprecatedFlag(argparse.Action):
    """An old spelling of a flag: works as the new one for one release, with a warning naming
    it."""

    def __init__(self, option_strings, dest, replacement: str, **keywords):
        self.replacement = replacement
        super().__init__(option_strings, dest, **keywords)

    def __call__(self, parser, namespace, values, option_string=None):
        logger.warning(
            "%s is deprecated and will be removed: use %s", option_string, self.replacement
        )
        setattr(namespace, self.dest, self.const if self.nargs == 0 else values)


def add_constraint_arguments(parser) -> None:
    """The pose constraint flags (:data:`CONSTRAINT_OPTIONS`) as a group of ``parser``."""
    add_options(parser.add_argument_group("pose constraints"), *CONSTRAINT_OPTIONS)


def deprecated_readings() -> tuple:
    """``--readings``, the old spelling of ``--readings-per-pose`` (one release)."""
    return option(
        "--readings",
        dest="readings_per_pose",
        type=READINGS_PER_POSE[1]["type"],
        action=DeprecatedFlag,
        replacement="--readings-per-pose",
        help=argparse.SUPPRESS,
    )


def add_readings_argument(parser) -> None:
    """``--readings-per-pose`` (and ``--readings``, its deprecated spelling)."""
    add_options(parser, READINGS_PER_POSE, deprecated_readings())


def constraints_from_args(args) -> PoseConstraints:
    """The pose constraints named on the command line."""
    if args.max_tilt_deg is not None and args.max_tilt_deg > 180.0:
        raise InvalidInput(
            f"--max-tilt-deg must be between 0 and 180 [deg], got {args.max_tilt_deg:g}"
        )
    return PoseConstraints(
        margin=args.margin,
        floor_height=None if args.no_floor else args.floor_height,
        max_tilt=None if args.max_tilt_deg is None else float(np.deg2rad(args.max_tilt_deg)),
        joint_ranges=args.joint_range,
        self_collision=not args.no_self_collision,
    )
