"""``ftkin calibrate SAMPLES.csv [-o CALIB.json]`` (``--dynamic`` for a moving recording)."""

import argparse
from dataclasses import replace
from pathlib import Path

from .. import (
    METHODS,
    MOUNT_MODES,
    STANDARD_GRAVITY,
    Arm,
    CalibrationOptions,
    InvalidInput,
    SensorNoise,
    bundled_urdf_path,
    calibrate,
    save_calibration,
)
from ..calibration.conventions import BASE_MOUNTS
from ..calibration.drift import drift_candidates, drift_choices
from ..calibration.ml import LOSSES
from ..kinematics.record import KinematicsRecord
from .arg_types import (
    add_command,
    add_options,
    bounded_int,
    finite_float,
    gravity,
    option,
    positive_float,
    refuse,
)
from .common import (
    SG_WINDOW,
    add_samples_arguments,
    arm_from_args,
    load_samples_from_args,
)
from .doctor import refuse_convention_mistakes


def drift_spec(text: str) -> str:
    """argparse type: a drift spec the registry knows (``auto``, ``none``, ``poly:2``, ...)."""
    try:
        drift_candidates(text)
    except InvalidInput as error:
        raise argparse.ArgumentTypeError(str(error)) from None
    return text


# The ml estimator's options.
_ML_OPTIONS = (
    option(
        "--noise-force",
        type=positive_float,
        metavar="N",
        help="noise std of one force reading [N] (with --noise-torque; default: estimated from "
        "the spread of repeated readings per pose, else from the residuals)",
    ),
    option(
        "--noise-torque",
        type=positive_float,
        metavar="N·m",
        help="noise std of one torque reading",
    ),
    option(
        "--resolution",
        type=positive_float,
        nargs=2,
        metavar=("N", "N·m"),
        help="resolution (quantization step) of one force and one torque reading: an estimated "
        "noise is at least resolution/√12, so a drift model cannot take all of it",
    ),
    option(
        "--loss",
        choices=LOSSES,
        default="linear",
        help="loss function; soft_l1/huber resist outlier poses (default: %(default)s)",
    ),
    option(
        "--drop-outliers",
        action="store_true",
        help="refit without the poses flagged as outliers",
    ),
    option(
        "--drift",
        type=drift_spec,
        default="auto",
        metavar="MODEL",
        help=f"bias drift over time, with a 't' column: {'|'.join(drift_choices())} (poly:N a "
        "polynomial of degree N; random-walk estimates the rate; auto picks by BIC and says "
        "which; default: %(default)s)",
    ),
    option(
        "--cross-validate",
        type=bounded_int(2, 50, "folds"),
        metavar="K",
        default=None,
        help="also print the K-fold cross-validated compensation error at held-out poses, with "
        "drift none beside the --drift model (does modelling a drift pay on this sensor?)",
    ),
    option(
        "--estimate-mount",
        choices=MOUNT_MODES[1:],
        metavar="yaw|full",
        help="also estimate how the sensor is turned on the flange: yaw (about its z axis) or "
        "full (any rotation); needs joint-angle samples (default: the URDF's sensor frame is "
        "right)",
    ),
)

# Sensor and robot conventions, stored in the calibration file.
_CONVENTION_OPTIONS = (
    option(
        "--sensor-sign",
        type=int,
        choices=(1, -1),
        default=1,
        help="-1: the sensor reports the reaction, negate every reading (default: %(default)s, "
        "the load on the sensor)",
    ),
    option(
        "--flip-axis",
        choices=("x", "y", "z"),
        help="negate this axis's force and torque channels in every reading (a mirrored, "
        "left-handed sensor axis)",
    ),
    option(
        "--base-mount",
        choices=BASE_MOUNTS,
        default="floor",
        help="how the robot base is mounted: floor (gravity along base -z), ceiling (+z), wall "
        "(no check); a fitted weight more than 90° off the expected direction is refused as a "
        "suspect sign (default: %(default)s)",
    ),
    option(
        "--expected-gravity",
        type=finite_float,
        nargs=3,
        metavar=("GX", "GY", "GZ"),
        help="expected gravity direction in the base frame (overrides --base-mount)",
    ),
)


def register(subparsers) -> None:
    parser = add_command(
        subparsers,
        "calibrate",
        help="estimate sensor bias, tool weight, centre of mass and base tilt",
        description="Calibrate from a samples CSV: wrench columns fx,fy,fz,mx,my,mz [N, N·m] and "
        "the orientation as joint columns (URDF names or q1..qn, rad), alpha,beta,gamma (deg, "
        "R = Rz Ry Rx) or qw,qx,qy,qz; optional integer 'pose' column groups repeated readings "
        "(their spread then gives the noise levels of the ml fit); optional 't' column [s] (bags: "
        "the stamps) lets the bias drift with time (--drift).",
        options=(
            option("samples", metavar="SAMPLES.csv"),
            option("-o", "--output", metavar="CALIB.json", help="write the calibration file here"),
            option(
                "--method",
                choices=METHODS,
                default=METHODS[0],
                help="ml: joint maximum-likelihood fit with standard errors; linear: the paper's "
                "two-step least squares (default: %(default)s)",
            ),
            option(
                "--g",
                type=gravity,
                default=STANDARD_GRAVITY,
                help="gravity for the mass, 1 to 30 [m/s²] (default: %(default)s)",
            ),
        ),
        run=run,
    )
    add_options(
        parser.add_argument_group("ml estimator"),
        *_ML_OPTIONS,
    )
    add_options(
        parser.add_argument_group("sensor and robot conventions (stored in the calibration file)"),
        *_CONVENTION_OPTIONS,
    )
    add_options(
        parser.add_argument_group(
            "dynamic calibration (a moving recording: columns t, joints, fx..mz, or a bag)"
        ),
        option(
            "--dynamic",
            action="store_true",
            help="identify mass, centre of mass, inertia, bias and tilt from a moving recording",
        ),
        option(
            "--no-inertia",
            action="store_true",
            help="with --dynamic: fit the static parameters only",
        ),
        SG_WINDOW,
    )
    parser.add_argument(
        "--no-convention-check",
        action="store_true",
        help="do not refit under the common convention mistakes (see 'ftkin doctor')",
    )
    add_samples_arguments(parser)


def _noise(args) -> SensorNoise | None:
    if (args.noise_force is None) != (args.noise_torque is None):
        raise InvalidInput(
            "give both --noise-force [N] and --noise-torque [N·m], or neither (then estimated)"
        )
    return None if args.noise_force is None else SensorNoise(args.noise_force, args.noise_torque)


def _run_dynamic(args, noise) -> int:
    static_only = {
        "--method": args.method != METHODS[0],
        "--loss": args.loss != "linear",
        "--drop-outliers": args.drop_outliers,
        "--estimate-mount": args.estimate_mount,
        "--sensor-sign": args.sensor_sign != 1,
        "--flip-axis": args.flip_axis,
        "--drift": args.drift != "auto",
        "--resolution": args.resolution,
        "--cross-validate": args.cross_validate,
    }
    if given := [flag for flag, used in static_only.items() if used]:
        raise InvalidInput(
            f"{', '.join(given)} apply to static calibration, not (yet) to --dynamic; calibrate "
            "the mount and sign from static poses first"
        )
    from .. import calibrate_dynamic, load_motion_bag, load_motion_csv
    from ..io.bags import is_bag_path

    arm = arm_from_args(args) or Arm.default()
    if is_bag_path(args.samples):
        recording = load_motion_bag(
            args.samples, arm, args.joint_topic, args.wrench_topic, args.wrench_frame or "sensor"
        )
    else:
        recording = load_motion_csv(args.samples, arm)
    result = calibrate_dynamic(
        recording.motion_samples(arm, args.sg_window),
        estimate_inertia=not args.no_inertia,
        g=args.g,
        noise=noise,
    )  # the file records its arm, as a static one does
    return _report(replace(result, kinematics=KinematicsRecord.from_arm(arm)), args)


def _options(args, noise) -> CalibrationOptions:
    """The calibration options of the command line (their combinations checked there)."""
    ml_only = noise is not None or args.loss != "linear" or args.drop_outliers or args.resolution
    refuse(
        InvalidInput,
        (
            args.no_inertia or args.sg_window is not None,
            "--no-inertia and --sg-window apply to --dynamic only",
        ),
        (
            args.method == "linear" and (ml_only or args.estimate_mount),
            "--noise-force/--noise-torque, --resolution, --loss, --drop-outliers and "
            "--estimate-mount apply to --method ml only",
        ),
    )
    return CalibrationOptions(
        method=args.method,
        g=args.g,
        noise=noise,
        loss=args.loss,
        drop_outliers=args.drop_outliers,
        estimate_mount=args.estimate_mount or "none",
        sensor_sign=args.sensor_sign,
        flip_axis=args.flip_axis,
        base_mount=args.base_mount,
        expected_gravity=args.expected_gravity,
        drift=args.drift,
        resolution=args.resolution,
    )


def run(args) -> int:
    noise = _noise(args)
    if args.dynamic:
        return _run_dynamic(args, noise)
    options = _options(args, noise)
    arm = arm_from_args(args)
    loaded = load_samples_from_args(args.samples, args, arm=arm)
    # The doctor refits the readings as given, on a floor-mounted base with the URDF's sensor
    # frame; with a stated sign, axis, base mount or an estimated mount calibrate() checks the
    # conventions itself.
    if not (
        args.no_convention_check
        or args.sensor_sign != 1
        or args.flip_axis
        or args.base_mount != "floor"
        or args.expected_gravity
        or args.estimate_mount
    ):
        refuse_convention_mistakes(loaded, arm)
    result = calibrate(loaded.samples, options)
    urdf = loaded.samples.urdf
    # a model built without a URDF (the UR e-Series) records itself by its robot name
    built = arm is not None and arm.urdf_path is None and loaded.samples.joint_positions is not None
    if built or (urdf and (arm or Path(urdf).resolve() == bundled_urdf_path().resolve())):
        # the arm the joint columns were read with (the bundled one when no option named one)
        result = replace(result, kinematics=KinematicsRecord.from_arm(arm or Arm.default()))
    validation = None
    if args.cross_validate:  # before anything is written: a failure leaves no file behind
        from ..calibration.cross_validation import cross_validate

        timed = loaded.samples.times is not None and args.drift != "none"
        validation = cross_validate(
            loaded.samples,
            ("none", args.drift) if timed else ("none",),
            folds=args.cross_validate,
            options=options,
        )
    _report(result, args)
    if validation is not None:
        print(validation.report())
    return 0


def _report(result, args) -> int:
    print(result.summary())
    if args.output:
        save_calibration(result, args.output)
        print(f"wrote {args.output}")
    return 0
