"""``ftkin rezero CALIB.json --q Q1 .. Qn --wrench FX .. MZ [-o OUT.json]``: a safe re-zero.

The new bias is the reading minus the tool gravity the calibration predicts at
that pose (:meth:`~ftkin.control.compensation.Compensator.rezero`), so the tool's
weight stays compensated at every other pose. Without ``-o`` the calibration
file itself is updated, atomically: re-zeroing it is this command's purpose
(the one place where ftkin writes over an input). ``-o`` writes elsewhere and
leaves CALIB.json untouched.
"""

import datetime

import numpy as np

from .. import Compensator, load_calibration, save_calibration
from .arg_types import add_command, finite_float, option
from .common import ALLOW_OTHER_ARM, add_arm_arguments, arm_of_calibration


def register(subparsers) -> None:
    add_command(
        subparsers,
        "rezero",
        help="re-zero the sensor bias from one contact-free reading at a known pose (tool weight "
        "kept)",
        description="Set the bias so that the contact wrench of the given raw reading is zero at "
        "the given joint "
        "angles: bias = reading − predicted tool gravity (not the whole reading, which would "
        "subtract the tool's "
        "weight at this pose). The tool must be free of contact and the arm still. Updates "
        "CALIB.json in place "
        "(atomically) unless -o is given.",
        options=(
            option("calibration", metavar="CALIB.json"),
            option(
                "--q",
                type=finite_float,
                nargs="+",
                required=True,
                metavar="Q",
                help="joint angles of the pose [rad]",
            ),
            option(
                "--wrench",
                type=finite_float,
                nargs=6,
                required=True,
                metavar=("FX", "FY", "FZ", "MX", "MY", "MZ"),
                help="raw reading at that pose [N, N·m], sensor frame (average a few hundred "
                "readings)",
            ),
            option(
                "-o",
                "--output",
                metavar="OUT.json",
                help="write the re-zeroed calibration here instead of in place",
            ),
            ALLOW_OTHER_ARM,
        ),
        groups=(add_arm_arguments,),
        run=run,
    )


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    arm = arm_of_calibration(args, calibration)  # None: the library says what to name
    # the library checks the pose (its joint count, radians, the joint limits) and warns of a
    # bias moved beyond the tool's weight and of a drift trajectory left in place
    previous = calibration.bias
    compensator = Compensator(calibration, arm, allow_other_arm=args.allow_other_arm)
    bias = compensator.rezero(np.array(args.q), np.array(args.wrench))
    output = args.output or args.calibration
    save_calibration(
        calibration.with_bias(bias),
        output,
        rezero={
            "q": args.q,
            "wrench": args.wrench,
            "previous_bias": previous,
            "time": datetime.datetime.now(datetime.UTC).isoformat(timespec="seconds"),
        },
    )
    change = bias - previous
    print(
        f"bias F0 = [{', '.join(f'{v:+.4f}' for v in bias[:3])}] N, M0 = "
        f"[{', '.join(f'{v:+.5f}' for v in bias[3:])}] N·m "
        f"(changed by {np.linalg.norm(change[:3]):.4f} N, {np.linalg.norm(change[3:]):.5f} N·m)"
    )
    print(f"wrote {output}" + (" (updated in place)" if args.output is None else ""))
    return 0
