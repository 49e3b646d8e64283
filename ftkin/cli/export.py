"""``ftkin export CALIB.json --format FORMAT -o OUT.yaml``: parameters for ROS controllers and robot
payloads; the formats and their options come from the registry (:mod:`ftkin.io.export`).
"""

from .. import load_calibration
from ..io.atomic import atomic_write_text
from ..io.export import EXPORT_FORMATS, export_request
from .arg_types import add_command, add_options, option
from .common import ALLOW_OTHER_ARM, add_arm_arguments, arm_from_args, arm_of_calibration


def register(subparsers) -> None:
    formats = "; ".join(f"'{name}': {fmt.summary}" for name, fmt in EXPORT_FORMATS.items())
    parser = add_command(
        subparsers,
        "export",
        help="write a calibration as ROS controller parameters or as the robot's payload (Franka, "
        "UR)",
        description=f"Export a calibration file to: {formats}. What a format cannot hold is "
        "printed and written as comments; names written (nodes, frames) are checked against "
        "ROS's rules. Payloads: the centre of mass in the flange frame, through the mount and the "
        "URDF.",
        options=(
            option("calibration", metavar="CALIB.json"),
            option(
                "--format",
                required=True,
                choices=tuple(EXPORT_FORMATS),
                dest="fmt",
                help="target format",
            ),
            option("-o", "--output", required=True, metavar="OUT.yaml"),
        ),
        run=run,
    )
    takers: dict[str, list] = {}
    for fmt in EXPORT_FORMATS.values():
        for spec in fmt.options:
            takers.setdefault(spec.name, [spec]).append(fmt.name)
    takes = "; ".join(f"{spec.flag}: {', '.join(names)}" for spec, *names in takers.values())
    add_options(
        parser.add_argument_group(f"format options (each format takes its own: {takes})"),
        *(
            option(spec.flag, dest=spec.name, default=None, help=spec.help, **spec.argparse)
            for spec, *names in takers.values()
        ),
    )
    add_options(parser, ALLOW_OTHER_ARM)
    add_arm_arguments(parser)
    parser.set_defaults(export_options=tuple(takers))


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    arm = (  # the options' arm, else (for a format that needs one) the calibration's
        arm_of_calibration(args, calibration)
        if EXPORT_FORMATS[args.fmt].needs_arm
        else arm_from_args(args)
    )
    chosen, request = export_request(
        calibration,
        args.fmt,
        arm,
        path=args.output,
        allow_other_arm=args.allow_other_arm,
        **{name: getattr(args, name) for name in args.export_options},
    )
    atomic_write_text(request.path, chosen.text(request))
    print(f"wrote {args.fmt} to {args.output}{chosen.summary_line(request)}")
    for note in chosen.notes(request):
        print(f"  note: {note}")
    return 0
