"""``ftkin calibrate SAMPLES.csv [-o CALIB.json]`` (``--dynamic`` for a moving recording)."""

from dataclasses import replace
from pathlib import Path

from .. import Arm, CalibrationOptions, InvalidInput, SensorNoise, calibrate, save_calibration
from ..kinematics import bundled_urdf_path
from ..kinematics.record import KinematicsRecord
from .arg_types import (
    add_command,
    add_options,
    bounded_int,
    option,
    refuse,
)
from .common import (
    SG_WINDOW,
    add_samples_arguments,
    arm_from_args,
    column_spelling_from_args,
    input_paths,
    load_samples_from_args,
    segment_parameters_from_args,
    stream_reading_from_args,
)
from .declared import add_declared, declared_values
from .doctor import refuse_convention_mistakes
from .shared_options import (
    ESTIMATE_MOUNT,
    GRAVITY,
    IMU_POSITION,
    METHOD,
    NO_CONVENTION_CHECK,
    NOISE_FORCE,
    NOISE_TORQUE,
    SENSOR_SIGN,
    noise_from_args,
    resolved,
)

CROSS_VALIDATE = option(
    "--cross-validate",
    type=bounded_int(2, 50, "folds"),
    metavar="K",
    default=None,
    help="also print the K-fold cross-validated compensation error at held-out poses, with "
    "drift none beside the --drift model (does modelling a drift pay on this sensor?)",
)
ML_FIELDS = ("resolution", "loss", "drop_outliers", "drift")
"""The ml estimator's options, declared on :class:`~ftkin.calibration.CalibrationOptions`."""
CONVENTION_FIELDS = ("flip_axis", "base_mount", "expected_gravity", "allow_tilt")
"""The sensor and robot conventions stored in the file (with ``sensor_sign``), declared there."""


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
            option(
                "samples",
                nargs="+",
                metavar="SAMPLES.csv",
                help="a samples CSV or a ROS 2 bag; or several CSVs on their own clocks (a wrench "
                "log, an IMU log, a joint or orientation log, any order), joined on their time "
                "column",
            ),
            option("-o", "--output", metavar="CALIB.json", help="write the calibration file here"),
            METHOD,
            GRAVITY,
        ),
        run=run,
    )
    ml = parser.add_argument_group("ml estimator")
    add_options(ml, NOISE_FORCE, NOISE_TORQUE)
    add_declared(ml, CalibrationOptions, only=ML_FIELDS)
    add_options(ml, CROSS_VALIDATE, ESTIMATE_MOUNT)
    conventions = parser.add_argument_group(
        "sensor and robot conventions (stored in the calibration file)"
    )
    add_options(conventions, SENSOR_SIGN)
    add_declared(conventions, CalibrationOptions, only=CONVENTION_FIELDS)
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
        option(
            "--prior",
            metavar="CALIB.json",
            help="with --dynamic from the IMU: a static IMU calibration of the same IMU (its "
            "accelerometer bias and scale): a motion cannot split the bias from the sensor's "
            "offsets, so without it the offsets are reported combined with the bias",
        ),
        IMU_POSITION,
    )
    add_options(parser, NO_CONVENTION_CHECK)
    add_samples_arguments(parser)


def _noise(args) -> SensorNoise | None:
    return noise_from_args(args)


def _run_dynamic(args, noise) -> int:
    static_only = {
        "--method": args.method not in (None, "ml"),
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
    from .. import calibrate_dynamic
    from ..io import load_motion_bag, load_motion_csv
    from ..io.bags import is_bag_path

    arm = arm_from_args(args) or Arm.default()
    paths = input_paths(args.samples)
    if len(paths) > 1:
        raise InvalidInput(
            "--dynamic with joint angles reads one recording (t, joints, fx..mz); several files "
            "are joined for the static fit and the IMU's"
        )
    if is_bag_path(paths[0]):
        recording = load_motion_bag(
            paths[0], arm, args.joint_topic, args.wrench_topic, args.wrench_frame or "sensor"
        )
    else:
        recording = load_motion_csv(paths[0], arm, column_spelling_from_args(args))
        _warn_unused_imu(paths[0], args)
    result = calibrate_dynamic(
        recording.motion_samples(arm, args.sg_window),
        estimate_inertia=not args.no_inertia,
        g=args.g,
        noise=noise,
    )  # the file records its arm, as a static one does
    return _report(replace(result, kinematics=KinematicsRecord.from_arm(arm)), args)


def _warn_unused_imu(path: str, args) -> None:
    """Say that a moving recording's IMU columns are not used by the fit from joint angles (the
    joints' derivatives give the motion)."""
    import logging

    from ..io.column_spelling import spelled_header
    from ..io.stream_join import ACCEL_COLUMNS, GYRO_COLUMNS

    header = spelled_header(path, column_spelling_from_args(args))
    found = [name for name in (*ACCEL_COLUMNS, *GYRO_COLUMNS) if name in header]
    if found:
        logging.getLogger("ftkin.cli").warning(
            "%s: the IMU columns %s are not used: --dynamic with joint angles takes the motion "
            "from the joints; drop the joint columns to fit from the IMU",
            path,
            ",".join(found),
        )


def _options(args, noise) -> CalibrationOptions:
    """The calibration options of the command line (their combinations checked there)."""
    refuse(
        InvalidInput,
        (
            args.no_inertia or args.sg_window is not None,
            "--no-inertia and --sg-window apply to --dynamic only",
        ),
    )  # the combinations of the fit's options are CalibrationOptions' to check, once
    given = declared_values(CalibrationOptions, args, skip=("method", "estimate_mount"))
    return CalibrationOptions(
        **given,
        method=resolved(args.method, "ml"),
        estimate_mount=args.estimate_mount or "none",
        noise=noise,
        convention_check=not args.no_convention_check,
    )


def run(args) -> int:
    noise = _noise(args)
    paths = input_paths(args.samples)
    if _from_imu(args, paths):
        return _run_imu(args, noise, paths)
    if args.prior or args.imu_position is not None:
        raise InvalidInput(
            "--prior and --imu-position apply to a calibration from the IMU (accelerometer columns "
            "ax,ay,az and no orientation)"
        )
    if args.dynamic:
        return _run_dynamic(args, noise)
    options = _options(args, noise)
    arm = arm_from_args(args)
    loaded = load_samples_from_args(args.samples, args, arm=arm, g=args.g)
    # The doctor refits the readings as given, on a floor-mounted base with the URDF's sensor
    # frame; with a stated sign, axis, base mount or an estimated mount calibrate() checks the
    # conventions itself.
    if not (
        args.no_convention_check
        or args.sensor_sign != 1
        or args.flip_axis
        or args.base_mount is not None
        or args.expected_gravity
        or args.estimate_mount
    ):
        refuse_convention_mistakes(loaded, arm, _declared_units(paths, args))
    samples = _with_imu(loaded, args)
    result = calibrate(samples, options)
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


def _declared_units(paths, args) -> dict:
    """The wrench units the CSVs' headers declare (``mx [N·m]``), by channel."""
    from ..io.bags import is_bag_path
    from ..io.column_spelling import declared_wrench_units
    from ..io.csv_table import read_header

    spelling, units = column_spelling_from_args(args), {}
    for path in paths:
        if not is_bag_path(path):
            units.update(declared_wrench_units(read_header(path), spelling))
    return units


def _with_imu(loaded, args):
    """The samples, with the IMU's specific force when the table has ``ax,ay,az`` too: the
    orientation and the IMU fitted together, the mount checked
    (:func:`~ftkin.io.imu_columns.with_imu_columns`)."""
    from ..io.imu_columns import with_imu_columns

    unit = stream_reading_from_args(args).accel_unit
    samples = with_imu_columns(loaded, accel_unit=unit, g=args.g)
    if samples is not loaded.samples:
        print(f"{loaded.table.source}: the orientation and the IMU (ax,ay,az) fitted together")
    return samples


def _from_imu(args, paths) -> bool:
    """Whether the inputs are a calibration from the IMU (CSVs, an accelerometer, no
    orientation)."""
    from ..io.bags import is_bag_path
    from ..io.joined_files import imu_only

    if any(is_bag_path(path) for path in paths):
        return False
    arm = arm_from_args(args) or Arm.default()
    return imu_only(paths, column_spelling_from_args(args), arm.joint_names)


def _run_imu(args, noise, paths) -> int:
    """The calibration from the sensor's IMU: static poses, or (``--dynamic``) a motion."""
    from ..io.calibration_file import load_calibration
    from ..io.imu_columns import load_imu_samples

    reading = stream_reading_from_args(args)
    refuse(
        InvalidInput,
        (
            args.estimate_mount or args.method == "linear" or args.cross_validate,
            "--estimate-mount, --method linear and --cross-validate apply to a calibration from "
            "joint angles or orientations; the IMU's fit estimates the IMU's rotation itself",
        ),
        (
            args.prior is not None and not args.dynamic,
            "--prior (a static IMU calibration) applies to --dynamic",
        ),
        (
            args.sensor_sign != 1 or args.flip_axis is not None,
            "--sensor-sign and --flip-axis apply to a calibration with an orientation; the IMU's "
            "fit takes the wrench as the load on the sensor: for a sensor that reports the "
            "reaction, negate the wrench columns (fx..mz) of the file",
        ),
    )
    samples, joined = load_imu_samples(
        *paths,
        accel_unit=reading.accel_unit,
        g=args.g,
        max_gap=reading.max_gap,
        gaps=reading.gaps,
        spelling=column_spelling_from_args(args),
        segments=None if args.dynamic else segment_parameters_from_args(args),
    )
    print(
        f"{' + '.join(paths)}: {len(samples)} readings from the sensor's IMU (no orientation: the "
        "accelerometer gives gravity)"
    )
    if args.dynamic:
        from .. import calibrate_dynamic

        prior = None if args.prior is None else load_calibration(args.prior)
        result = calibrate_dynamic(
            samples,
            prior=prior,
            imu_position=args.imu_position,
            noise=noise,
            window=args.sg_window,
        )
    else:
        result = calibrate(samples, wrench_noise=noise, imu_position=args.imu_position)
    return _report(result, args)


def _report(result, args) -> int:
    print(result.summary())
    if args.output:
        save_calibration(result, args.output)
        print(f"wrote {args.output}")
    return 0
