"""``ftkin rezero CALIB.json --q Q1 .. Qn --wrench FX .. MZ [-o OUT.json]``: a safe re-zero.

The new bias is the reading minus the tool gravity the calibration predicts at
that pose (:meth:`~ftkin.control.compensation.Compensator.rezero`), so the tool's
weight stays compensated at every other pose. Without ``-o`` the calibration
file itself is updated, atomically: re-zeroing it is this command's purpose
(the one place where ftkin writes over an input). ``-o`` writes elsewhere and
leaves CALIB.json untouched.
"""

import datetime
import logging

import numpy as np

from .. import Compensator, InvalidInput, load_calibration, save_calibration
from .arg_types import add_command, finite_float, option, refuse
from .common import add_arm_arguments, arm_of_calibration

logger = logging.getLogger("ftkin.cli")

REZERO_WARNING_FORCE = 2.0
"""A re-zero that moves the force bias by more than the tool's weight and this [N] is warned of
(a contact at the pose, or a sensor tared in its driver: a thermal drift is smaller)."""


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
        ),
        groups=(add_arm_arguments,),
        run=run,
    )


def run(args) -> int:
    calibration = load_calibration(args.calibration)
    arm = arm_of_calibration(args, calibration, "rezero --q")
    # angles beyond 2π (degrees) and a pose outside the joint limits are refused: the bias would
    # be set at a pose the arm was not in
    refuse(
        InvalidInput,
        (
            len(args.q) != arm.nq,
            f"--q takes the arm's {arm.nq} joint angles [rad] ({', '.join(arm.joint_names)}), "
            f"got {len(args.q)}",
        ),
        (not np.all(np.isfinite(args.q)), f"--q must be finite numbers [rad], got {list(args.q)}"),
    )
    for name, value, low, high in zip(arm.joint_names, args.q, arm.lower_limits, arm.upper_limits):
        refuse(
            InvalidInput,
            (
                abs(value) > 2.0 * np.pi + 0.01,
                f"--q: {name} = {value:g} is beyond ±2π: joint angles are in radians (this looks "
                "like degrees)",
            ),
            (
                not low - 1e-6 <= value <= high + 1e-6,
                f"--q: {name} = {value:g} rad is outside its limits [{low:g}, {high:g}] rad",
            ),
        )
    previous = calibration.bias
    bias = Compensator(calibration, arm).rezero(np.array(args.q), np.array(args.wrench))
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
    weight = float(calibration.tool_weight)
    if np.linalg.norm(change[:3]) > max(weight, REZERO_WARNING_FORCE):
        logger.warning(
            "the bias moved by %.4g N, more than the tool's weight (%.4g N): was the tool touching "
            "something, or the sensor tared in its driver since the calibration? Re-zero at a "
            "contact-free pose",
            float(np.linalg.norm(change[:3])),
            weight,
        )
    drift = calibration.drift
    if drift is not None and drift.model != "none":
        logger.warning(
            "this calibration has a drift trajectory (%s) over %.6g–%.6g s: rows of a log timed "
            "inside it keep the bias the recording saw; the re-zeroed bias applies after it",
            drift.model,
            float(drift.times[0]),
            float(drift.times[-1]),
        )
    return 0
