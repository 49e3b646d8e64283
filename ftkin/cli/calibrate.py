"""``ftkin calibrate SAMPLES.csv [-o CALIB.json]``."""

from __future__ import annotations

from ..calibration import METHODS, calibrate
from ..calibration_file import save_calibration
from ..model import STANDARD_GRAVITY
from .common import add_samples_arguments, load_samples_from_args, positive_float


def register(subparsers) -> None:
    parser = subparsers.add_parser(
        "calibrate",
        help="estimate sensor bias, tool weight, centre of mass and base tilt",
        description="Calibrate from a samples CSV: wrench columns fx,fy,fz,mx,my,mz [N, N·m] and the "
        "orientation as joint columns (URDF names or q1..qn, rad), alpha,beta,gamma (deg, "
        "R = Rz Ry Rx) or qw,qx,qy,qz; optional integer 'pose' column groups repeated readings.",
    )
    parser.add_argument("samples", metavar="SAMPLES.csv")
    parser.add_argument("-o", "--output", metavar="CALIB.json", help="write the calibration file here")
    parser.add_argument("--method", choices=METHODS, default=METHODS[0], help="estimator (default: %(default)s)")
    parser.add_argument("--g", type=positive_float, default=STANDARD_GRAVITY, help="gravity for the mass [m/s²] (default: %(default)s)")
    add_samples_arguments(parser)
    parser.set_defaults(func=run)


def run(args) -> int:
    loaded = load_samples_from_args(args.samples, args)
    result = calibrate(loaded.samples, method=args.method, g=args.g)
    print(result.summary())
    if args.output:
        save_calibration(result, args.output)
        print(f"wrote {args.output}")
    return 0
