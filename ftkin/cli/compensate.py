"""``ftkin compensate CALIB.json LOG.csv -o OUT.csv``, with the inertial term for a moving log
(``--ur HOST --live``: a UR arm's readings as they come, :mod:`ftkin.cli.compensate_live`).
"""

import numpy as np

from .. import Arm, Compensator, InvalidInput, load_calibration
from ..calibration.fused_result import FusedCalibrationResult
from ..calibration.imu_result import ImuCalibrationResult
from ..calibration.model import WRENCH_CHANNELS
from ..control.bias_checks import check_log_times, drifting
from ..io.bags import is_bag_path
from ..io.column_spelling import spelled_header, spelled_table
from ..io.csv_table import read_table, write_csv
from .arg_types import add_command, option
from .common import (
    ALLOW_OTHER_ARM,
    SG_WINDOW,
    add_samples_arguments,
    arm_for_calibration,
    column_spelling_from_args,
    input_paths,
    load_samples_from_args,
    logger,
    stream_reading_from_args,
)
from .compensate_live import add_live_arguments, check_live_arguments, run_live
from .shared_options import (
    IMU_POSITION,
    NO_CONVENTION_CHECK,
    NOISE_FORCE,
    NOISE_TORQUE,
    TRACK_LOAD,
    noise_from_args,
)


def register(subparsers) -> None:
    parser = add_command(
        subparsers,
        "compensate",
        help="remove bias and tool gravity from a log of raw readings",
        description="Write the contact wrench (fx..mz, sensor frame, N and N·m) of every row of "
        "LOG.csv, "
        "keeping its other columns. LOG.csv has the same columns as a calibration samples file. "
        "With a 't' "
        "column [s] and a drifting calibration, rows inside the calibration's recording use the "
        "bias at their "
        "time, later rows the calibration's last bias. When the calibration has an inertia "
        "(calibrate --dynamic) "
        "and the log has a time column t and joint columns, the tool's inertial wrench is removed "
        "too (joint "
        "derivatives from the log, zero-phase). With --ur HOST --live: a Universal Robots arm's "
        "readings as they come (its built-in sensor, or --sensor), printed a few times a second "
        "and with --log written at full rate, until --duration or Ctrl-C.",
        options=(
            option("calibration", metavar="CALIB.json"),
            option(
                "log",
                nargs="*",
                metavar="LOG.csv",
                help="a log (or a bag); or several CSVs on their own clocks (wrench, IMU, joints "
                "or orientation, any order), joined on their time column (none with --live)",
            ),
            IMU_POSITION,
            option("-o", "--output", metavar="OUT.csv"),
            SG_WINDOW,
            ALLOW_OTHER_ARM,
            NO_CONVENTION_CHECK,
            TRACK_LOAD,
            NOISE_FORCE,
            NOISE_TORQUE,
        ),
        groups=(add_samples_arguments, add_live_arguments),
        run=run,
    )
    _parse_intermixed(parser)


def _parse_intermixed(parser) -> None:
    """Let LOG.csv (optional since ``--live``) follow options, as when it was required.

    argparse fills an optional positional with nothing when an option comes between it and the
    one before (``compensate CALIB --robot ur5 LOG -o OUT`` would leave LOG unrecognized);
    ``parse_known_intermixed_args`` reads the positionals after the options. It calls
    ``parse_known_args`` itself: the plain one is put back for the time of the call.
    """
    plain = parser.parse_known_args

    def intermixed(args=None, namespace=None):
        parser.parse_known_args = plain
        try:
            return parser.parse_known_intermixed_args(args, namespace)
        finally:
            parser.parse_known_args = intermixed

    parser.parse_known_args = intermixed


def run(args) -> int:
    check_live_arguments(args)
    calibration = load_calibration(args.calibration)
    if isinstance(calibration, ImuCalibrationResult) and (
        not isinstance(calibration, FusedCalibrationResult) or _logs_an_accelerometer(args)
    ):  # made from the IMU: its columns compensate (a fused one: with FK when the log has none)
        if args.track_load:
            raise InvalidInput(
                "--track-load needs the sensor's orientation from poses (joint or R_BS columns); "
                "a calibration made from the IMU compensates without them"
            )
        return _compensate_imu(args, calibration)
    if args.imu_position is not None:
        raise InvalidInput("--imu-position applies to a calibration made from the IMU")
    arm = arm_for_calibration(args, calibration)
    if args.live:
        return run_live(args, calibration, arm)
    compensator = Compensator(
        calibration, arm, allow_other_arm=args.allow_other_arm
    )  # checks arm against the record
    if calibration.has_inertia:
        if (done := _compensate_motion(args, calibration, arm or Arm.default())) is not None:
            return done
    elif args.sg_window is not None:
        raise InvalidInput(
            "--sg-window applies to a calibration with an inertia (ftkin calibrate --dynamic)"
        )
    loaded = load_samples_from_args(args.log, args, static_only=False, arm=arm, g=calibration.g)
    if not is_bag_path(input_paths(args.log)[0]):
        _check_log_conventions(args, loaded.table, arm, calibration)
    contact = compensator.compensate_samples(loaded.samples)
    header, table_rows = loaded.table.header, loaded.table.rows
    if args.track_load:
        header, table_rows, contact = _track_load(
            calibration,
            noise_from_args(args),
            compensator.sensor_rotations(loaded.samples),
            contact,
            loaded.samples.times,
            header,
            table_rows,
            loaded.table,
        )
    rows = _write_contact(args.output, header, table_rows, contact)
    print(
        f"wrote {rows} compensated rows to {args.output} (median contact force |F'| "
        f"{np.median(Compensator.payload_weight(contact)):.4f} N)"
    )
    if loaded.samples.times is not None and drifting(calibration.drift):
        # the clock warnings came from the library (Compensator.bias_at); this is the count
        check = check_log_times(calibration.drift, loaded.samples.times, calibration.bias)
        print(
            f"bias drift {calibration.drift.model}: {check.inside} rows inside the calibration "
            f"recording used the bias at their time, {check.outside} the last bias"
        )
    return 0


def _check_log_conventions(args, table, arm, calibration) -> None:
    """:func:`~ftkin.io.log_conventions.check_log_conventions`, unless --no-convention-check."""
    from ..io.log_conventions import check_log_conventions

    if not args.no_convention_check:
        check_log_conventions(
            table,
            arm,
            calibration,
            advice=" (--no-convention-check compensates the log as given)",
        )


def _logs_an_accelerometer(args) -> bool:
    """Whether a file of the log (CSVs; not live) has the accelerometer's ``ax,ay,az``."""
    from ..io.stream_join import ACCEL_COLUMNS

    if args.live or args.log is None:
        return False
    spelling = column_spelling_from_args(args)
    for path in input_paths(args.log):
        if is_bag_path(path):
            return False
        header = spelled_header(path, spelling)
        if all(name in header for name in ACCEL_COLUMNS):
            return True
    return False


def _compensate_imu(args, calibration) -> int:
    """A calibration from the IMU: the wrench and IMU columns of the files (joined on time),
    compensated with :class:`~ftkin.control.imu_compensation.ImuCompensator` (with a gyro and
    times, the rotational terms too, zero-phase)."""
    from ..control.imu_compensation import ImuCompensator
    from ..io.imu_columns import load_imu_samples

    paths = input_paths(args.log)
    reading = stream_reading_from_args(args)
    samples, joined = load_imu_samples(
        *paths,
        accel_unit=reading.accel_unit,
        g=calibration.g,
        max_gap=reading.max_gap,
        gaps=reading.gaps,
        spelling=column_spelling_from_args(args),
    )
    compensator = ImuCompensator(calibration, imu_position=args.imu_position)
    contact = compensator.compensate_recording(samples, window=args.sg_window)
    header = ["t", *joined.columns] if samples.times is not None else list(joined.columns)
    columns = [joined.times] if samples.times is not None else []
    columns += [np.asarray(joined.columns[name], dtype=float) for name in joined.columns]
    rows = [list(row) for row in zip(*columns)]
    count = _write_contact(args.output, header, rows, contact)
    moving = samples.angular_velocity is not None and samples.times is not None
    terms = "gravity, linear and rotational terms" if moving else "gravity, linear acceleration"
    median = np.median(np.linalg.norm(contact[:, :3], axis=1))
    print(
        f"wrote {count} compensated rows to {args.output} from the IMU ({terms}); median "
        f"contact force |F'| {median:.4f} N"
    )
    return 0


LOAD_COLUMNS = ("load_mass", "load_mass_std", "load_com_x", "load_com_y", "load_com_z")


def _track_load(calibration, noise, rotations, contact, times, header, rows, table=None):
    """``(header, rows, contact)`` with the load's columns and the contact after tool and load
    (:func:`~ftkin.control.load_track.track_load`); prints the events. ``table``: the log's
    :class:`~ftkin.io.csv_table.Table` (None for a bag), whose ``gripper`` column is read."""
    from ..control.load_events import LoadTracker
    from ..control.load_track import GRIPPER_COLUMN, GRIPPER_STATES, track_load

    gripper = None
    if table is not None and GRIPPER_COLUMN in table.header:
        gripper = table.booleans(GRIPPER_COLUMN, GRIPPER_STATES)
    tracker = LoadTracker.for_calibration(calibration, noise, readings=contact)
    track = track_load(tracker, rotations, contact, times, gripper)
    force, torque = tracker.noise.force_std, tracker.noise.torque_std
    print(
        f"load tracking: noise per reading {np.array2string(force, precision=4)} N, "
        f"{np.array2string(torque, precision=5)} N·m; bounds {tracker.thresholds.k_sigma:g}σ"
    )
    names = [*LOAD_COLUMNS, "load_event"]
    kept = [i for i, name in enumerate(header) if name not in names]  # a rerun's are replaced
    values = np.column_stack([track.mass, track.mass_std, track.com_in_sensor])
    out = [
        [row[i] for i in kept] + [*map(float, numbers), label]
        for row, numbers, label in zip(rows, values, track.labels)
    ]
    for event in track.events:
        print(f"t {event.time:.3f} s: {event.kind} (mass step {event.mass:.4g} kg; {event.reason})")
    return [header[i] for i in kept] + names, out, track.contact


def _write_contact(path: str, header: list[str], rows, contact: np.ndarray) -> int:
    """Write ``rows`` with their fx..mz cells replaced by ``contact`` [N, N·m]; returns how many."""
    columns = [header.index(name) for name in WRENCH_CHANNELS]
    out = [list(row) for row in rows]
    for row, wrench in zip(out, contact):
        for column, value in zip(columns, wrench):
            row[column] = float(value)
    write_csv(path, header, out)
    return len(out)


def _compensate_motion(args, calibration, arm: Arm) -> int | None:
    """Compensation with the inertial term, or None when the log is not a moving recording."""
    from ..control.dynamic_compensation import DynamicCompensator
    from ..io.motion_recording import is_motion_table, load_motion_bag, motion_from_table

    paths = input_paths(args.log)
    if len(paths) > 1:
        return None  # several files: joined, then compensated at rest (the static path)
    table = None  # a bag's: no gripper column
    if is_bag_path(paths[0]):
        recording = load_motion_bag(
            paths[0], arm, args.joint_topic, args.wrench_topic, args.wrench_frame or "sensor"
        )
        header = ["t", *arm.joint_names, *WRENCH_CHANNELS]
        rows = np.column_stack(
            [recording.times, recording.joint_positions, recording.wrenches]
        ).tolist()
    else:
        table = spelled_table(read_table(paths[0]), column_spelling_from_args(args))
        if not is_motion_table(table, arm):
            logger.warning(
                "%s has no 't' and joint columns: static compensation only (no inertial term)",
                paths[0],
            )
            return None
        _check_log_conventions(args, table, arm, calibration)
        recording = motion_from_table(table, arm)
        header, rows = table.header, table.rows
    contact = DynamicCompensator(
        calibration, arm, allow_other_arm=args.allow_other_arm
    ).compensate_motion(recording.motion_samples(arm, args.sg_window))
    if args.track_load:
        header, rows, contact = _track_load(
            calibration,
            noise_from_args(args),
            recording.motion_samples(arm, args.sg_window).rotations @ calibration.mount_rotation.T,
            contact,
            recording.times,
            header,
            rows,
            table,
        )
    count = _write_contact(args.output, header, rows, contact)
    print(
        f"wrote {count} compensated rows to {args.output} with the inertial term (zero-phase "
        "Savitzky–Golay "
        "derivatives); median contact force |F'| "
        f"{np.median(np.linalg.norm(contact[:, :3], axis=1)):.4f} N"
    )
    return 0
