"""Pose constraints and readings per pose: one definition for ``plan``, ``evaluate-poses``,
``simulate samples`` and ``robot calibrate``.

Every command that plans or visits calibration poses takes these flags with the same spelling,
default and help (``tests/cli/test_flags.py`` walks the parsers): ``--margin``,
``--floor-height`` / ``--no-floor``, ``--max-tilt-deg``, ``--joint-range NAME:LO:HI``,
``--no-self-collision``, ``--clearance`` (:class:`~ftkin.planning.constraints.PoseConstraints`) and
``--readings-per-pose``.
"""

from ..planning.constraints import PoseConstraints
from .arg_types import add_options, bounded_int, option
from .declared import declared_option, declared_values

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


def add_constraint_arguments(parser) -> None:
    """The pose constraint flags (:data:`CONSTRAINT_OPTIONS`) as a group of ``parser``."""
    add_options(parser.add_argument_group("pose constraints"), *CONSTRAINT_OPTIONS)


def add_readings_argument(parser) -> None:
    """``--readings-per-pose`` (:data:`READINGS_PER_POSE`)."""
    add_options(parser, READINGS_PER_POSE)


def constraints_from_args(args) -> PoseConstraints:
    """The pose constraints named on the command line."""
    values = declared_values(PoseConstraints, args)
    if args.no_floor:
        values["floor_height"] = None
    return PoseConstraints(**values)
