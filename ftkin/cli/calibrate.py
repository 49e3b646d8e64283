"""``ftkin calibrate SAMPLES.csv [-o CALIB.json]``."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from ..calibration.estimate import METHODS, calibrate
from ..calibration.information import SensorNoise
from ..calibration.ml import LOSSES
from ..calibration.model import STANDARD_GRAVITY
from ..exceptions import InvalidInput
from ..io.calibration_file import save_calibration
from ..kinematics.record import KinematicsRecord
from .common import add_samples_arguments, arm_from_args, gravity, load_samples_from_args, positive_float
from .doctor import check_conventions


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "calibrate",
        help="estimate sensor bias, tool weight, centre of mass and base tilt",
        description="Calibrate from a samples CSV: wrench columns fx,fy,fz,mx,my,mz [N, N·m] and the "
        "orientation as joint columns (URDF names or q1..qn, rad), alpha,beta,gamma (deg, "
        "R = Rz Ry Rx) or qw,qx,qy,qz; optional integer 'pose' column groups repeated readings "
        "(their spread then gives the noise levels of the ml fit).",
    )
    parser.add_argument("samples", metavar="SAMPLES.csv")
    parser.add_argument("-o", "--output", metavar="CALIB.json", help="write the calibration file here")
    parser.add_argument(
        "--method", choices=METHODS, default=METHODS[0],
        help="ml: joint maximum-likelihood fit with standard errors; linear: the paper's two-step "
        "least squares (default: %(default)s)",
    )
    parser.add_argument("--g", type=gravity, default=STANDARD_GRAVITY, help="gravity for the mass, 1 to 30 [m/s²] (default: %(default)s)")
    ml = parser.add_argument_group("ml estimator")
    ml.add_argument(
        "--noise-force", type=positive_float, metavar="N",
        help="noise std of one force reading [N] (with --noise-torque; default: estimated from the spread "
        "of repeated readings per pose, else from the residuals)",
    )
    ml.add_argument("--noise-torque", type=positive_float, metavar="N·m", help="noise std of one torque reading [N·m]")
    ml.add_argument(
        "--loss", choices=LOSSES, default="linear",
        help="loss function; soft_l1/huber resist outlier poses (default: %(default)s)",
    )
    ml.add_argument("--drop-outliers", action="store_true", help="refit without the poses flagged as outliers")
    parser.add_argument(
        "--no-convention-check", action="store_true",
        help="do not refit under the common convention mistakes (see 'ftkin doctor')",
    )
    add_samples_arguments(parser)
    parser.set_defaults(func=run)


def _noise(args) -> SensorNoise | None:
    if (args.noise_force is None) != (args.noise_torque is None):
        raise InvalidInput("give both --noise-force [N] and --noise-torque [N·m], or neither (then estimated)")
    if args.noise_force is None:
        return None
    return SensorNoise(args.noise_force, args.noise_torque)


def _bundled_if_used(loaded):
    """The bundled arm when the samples' joint columns were read with it (no arm option given)."""
    from ..kinematics.arm import Arm, bundled_urdf_path

    if loaded.samples.urdf and Path(loaded.samples.urdf).resolve() == bundled_urdf_path().resolve():
        return Arm.default()
    return None


def run(args) -> int:
    noise = _noise(args)
    if args.method == "linear" and (noise is not None or args.loss != "linear" or args.drop_outliers):
        raise InvalidInput("--noise-force/--noise-torque, --loss and --drop-outliers apply to --method ml only")
    arm = arm_from_args(args)
    loaded = load_samples_from_args(args.samples, args, arm=arm)
    if not args.no_convention_check:
        check_conventions(loaded, arm)
    result = calibrate(
        loaded.samples, method=args.method, g=args.g, noise=noise, loss=args.loss, drop_outliers=args.drop_outliers
    )
    samples_arm = getattr(loaded.samples, "urdf", None) and (arm or _bundled_if_used(loaded))
    if samples_arm is not None:
        result = replace(result, kinematics=KinematicsRecord.from_arm(samples_arm))
    print(result.summary())
    if args.output:
        save_calibration(result, args.output)
        print(f"wrote {args.output}")
    return 0
