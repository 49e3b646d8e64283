"""Pose constraints and readings per pose: one definition for ``plan``, ``evaluate-poses``,
``simulate samples`` and ``robot calibrate``.

Every command that plans or visits calibration poses takes these flags with the same spelling,
default and help (``tests/cli/test_flags.py`` walks the parsers): ``--margin``,
``--floor-height`` / ``--no-floor``, ``--max-tilt-deg``, ``--joint-range NAME:LO:HI``,
``--no-self-collision``, ``--clearance`` (:class:`~ftkin.planning.constraints.PoseConstraints`) and
``--readings-per-pose``.
"""

import argparse
import logging

from ..planning.constraints import PoseConstraints
from .arg_types import add_options, bounded_int, option
from .declared import declared_option, declared_values

logger = logging.getLogger("ftkin.cli")

DEFAULT_READINGS_PER_POSE = 50
"""Readings per pose: what ``robot calibrate`` records at each pose and what ``plan`` predicts
the standard errors for (one value, so that a plan's prediction is the session's)."""


CONSTRAINT_OPTIONS = (
    declared_option(PoseConstraints, "margin"),
    declared_option(PoseConstraints, "floor_height"),
    option(
        "--no-floor",
        action="store_true",
        help="no floor constraint (an arm mounted on a wall or ceiling)",
    ),
    declared_option(PoseConstraints, "max_tilt"),
    declared_option(PoseConstraints, "joint_ranges"),
    declared_option(PoseConstraints, "self_collision"),
    declared_option(PoseConstraints, "clearance"),
)
"""The pose constraints (:func:`constraints_from_args`), declared on
:class:`~ftkin.planning.constraints.PoseConstraints`; ``--no-floor`` is the command line's way
to say ``floor_height=None``."""

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
    values = declared_values(PoseConstraints, args)
    if args.no_floor:
        values["floor_height"] = None
    return PoseConstraints(**values)
