"""``ftkin compensate CALIB.json --ur HOST --live [--log OUT.csv] [--duration S]``: a UR arm's
contact wrench as it comes.

The library loop is :func:`~ftkin.robot.live_compensation.compensated_stream` over a
:class:`~ftkin.robot.ur.UrArm` (its built-in sensor, or ``--sensor MODULE:FACTORY``). The
contact wrench is printed a few times a second; ``--log`` writes every sample (``t`` [s, the
sensor's stamp], the joints [rad], ``fx..mz`` [N, N·m], sensor frame) as it comes. With the
built-in sensor the log is every RTDE package, read on a connection of its own
(:class:`~ftkin.robot.live_compensation.PackageLog`: ur_rtde's getters skip packages when this
process is late); with ``--sensor`` it is every new sample the loop sees, flushed every
:data:`~ftkin.robot.live_log.FLUSH_EVERY` rows (:class:`~ftkin.robot.live_log.SampleLog`).
The summary counts the samples logged and the packages missed (gaps in the controller's
timestamps, :func:`~ftkin.robot.live_log.missed_packages`). Ctrl-C ends it with the summary and
exit code 130.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, install_command
from ..robot.live_log import SampleLog, missed_packages, settle
from ..robot.stillness import Stillness
from .arg_types import add_options, option, positive_float
from .declared import declared_option
from .shared_options import (
    DURATION,
    SENSOR,
    SENSOR_OPTION,
    UR,
    noise_from_args,
    open_named_sensor,
)


def add_live_arguments(parser) -> None:
    """The options of the live mode (a group of ``ftkin compensate``)."""
    add_options(
        parser.add_argument_group(
            f"live, on a Universal Robots arm through ur_rtde ({install_command('ur')}); "
            "--wrench-frame says the axes of its ft_raw_wrench (default: base)"
        ),
        UR,
        option(
            "--live",
            action="store_true",
            help="compensate the arm's readings as they come (instead of LOG.csv), until "
            "--duration or Ctrl-C",
        ),
        option(
            "--log",
            dest="live_log",
            metavar="OUT.csv",
            help="write every compensated sample (t, joints, fx..mz) as it comes",
        ),
        DURATION,
        option(
            "--print-rate",
            type=positive_float,
            default=5.0,
            metavar="HZ",
            help="lines printed per second (default: %(default)s)",
        ),
        declared_option(Stillness, "stale_after"),
        SENSOR,
        SENSOR_OPTION,
    )


def check_live_arguments(args) -> None:
    """Refuse option combinations of the live mode before anything connects."""
    from .arg_types import refuse

    live_only = {"--log": args.live_log, "--duration": args.duration, "--sensor": args.sensor}
    refuse(
        InvalidInput,
        (args.ur is not None and not args.live, "--ur HOST compensates live: add --live"),
        (args.live and args.ur is None, "--live needs --ur HOST (the UR controller)"),
        (
            args.live and (bool(args.log) or args.output is not None),
            "--live compensates the arm's readings: give no LOG.csv and no -o (write the "
            "samples with --log OUT.csv)",
        ),
        (
            not args.live and any(v is not None for v in live_only.values()),
            f"{', '.join(k for k, v in live_only.items() if v is not None)} go with --ur HOST "
            "--live",
        ),
        (
            not args.live and (not args.log or args.output is None),
            "give LOG.csv and -o OUT.csv (or --ur HOST --live for a UR arm)",
        ),
        (
            args.sensor_option and args.sensor is None,
            "--sensor-option goes with --sensor MODULE:FACTORY",
        ),
    )
    if args.live_log is not None:  # (checked against the inputs with every output option)
        if Path(args.live_log).exists():
            raise InvalidInput(
                f"--log {args.live_log} exists: ftkin never overwrites a file; choose another"
            )


def _sensor(args, ur):
    """The UR's built-in sensor, or the one ``--sensor`` names (closed with the command)."""
    if args.sensor is None:
        return ur.sensor
    return open_named_sensor(args)


def run_live(args, calibration, arm) -> int:
    """The live loop; returns the exit code (130 after Ctrl-C)."""
    from ..robot.live_compensation import compensated_stream
    from ..robot.ur import UrArm

    if arm is None or arm.nq != 6:
        raise InvalidInput(
            "--ur needs a six-joint arm: the calibration's recorded arm (--robot ur5e, ...) or "
            f"--robot; got {arm!r}"
        )
    wrench_frame = args.wrench_frame or "base"
    ur = UrArm(args.ur, wrench_frame=wrench_frame, stale_after=args.stale_after)
    packages = log = None
    if args.live_log and args.sensor is None:  # every package, on a connection of its own
        from ..robot.live_compensation import PackageLog

        packages = PackageLog(
            calibration,
            args.ur,
            args.live_log,
            arm=arm,
            wrench_frame=wrench_frame,
            timeout=max(args.stale_after, 0.5),
            allow_other_arm=args.allow_other_arm,
        )
    elif args.live_log:
        log = SampleLog(args.live_log, arm.joint_names)
    tracker = _load_tracker(args, calibration)
    stamps: list[float] = []
    start = time.monotonic()
    code, interval, next_print = 0, 1.0 / args.print_rate, 0.0
    print(
        f"compensating {ur} ({'built-in sensor' if args.sensor is None else args.sensor}); "
        "contact wrench in the sensor frame, F' [N], M' [N·m]"
        + (f"; logging to {args.live_log}" if args.live_log else "")
    )
    try:
        sensor = _sensor(args, ur)
        stream = compensated_stream(
            calibration,
            ur,
            sensor,
            arm=arm,
            stale_after=args.stale_after,
            allow_other_arm=args.allow_other_arm,
            load=tracker,
        )
        settle(stream)
        seen = 0 if tracker is None else len(tracker.events)
        start = time.monotonic()
        for stamp, q, contact in stream:
            stamps.append(stamp)
            if log is not None:
                log.add(stamp, q, contact)
            if packages is not None and packages.error is not None:
                raise packages.error
            if tracker is not None and len(tracker.events) > seen:
                for event in tracker.events[seen:]:  # as compensate --track-load on a log
                    print(
                        f"t {stamp:.3f} s: {event.kind} (mass step {event.mass:.4g} kg; "
                        f"{event.reason})",
                        flush=True,
                    )
                seen = len(tracker.events)
            now = time.monotonic()
            if now >= next_print:
                next_print = now + interval
                force, torque = contact[:3], contact[3:]
                print(
                    f"t {stamp:12.3f} s  F' {force[0]:+9.3f} {force[1]:+9.3f} {force[2]:+9.3f}  "
                    f"|F'| {np.linalg.norm(force):8.3f}  M' {torque[0]:+8.4f} {torque[1]:+8.4f} "
                    f"{torque[2]:+8.4f}",
                    flush=True,
                )
            if args.duration is not None and now - start >= args.duration:
                break
    except KeyboardInterrupt:
        code = 130
    finally:
        elapsed = time.monotonic() - start
        if log is not None:
            log.close()
        if packages is not None:
            packages.close()
            stamps = packages.timestamps()
        ur.close(wait=False)  # the command ends with the process: no 0.5 s destructor
        _summary(np.array(stamps), elapsed, args.live_log, code == 130)
    return code


def _load_tracker(args, calibration):
    """``--track-load``'s tracker (the noise: the flags', else the calibration's), else None.

    The built-in sensor of a UR sends a package every 2 ms: the tracker's clock is that.
    """
    if not args.track_load:
        return None
    from ..control.load_events import LoadTracker

    tracker = LoadTracker.for_calibration(calibration, noise_from_args(args), period=0.002)
    force, torque = tracker.noise.force_std, tracker.noise.torque_std
    print(
        f"load tracking: noise per reading {np.array2string(force, precision=4)} N, "
        f"{np.array2string(torque, precision=5)} N·m; bounds {tracker.thresholds.k_sigma:g}σ"
    )
    return tracker


def _summary(stamps: np.ndarray, elapsed: float, log_path, interrupted: bool) -> None:
    missed, period = missed_packages(stamps)
    rate = (len(stamps) - 1) / (stamps[-1] - stamps[0]) if len(stamps) > 1 else 0.0
    line = (
        f"{len(stamps)} samples in {elapsed:.2f} s ({rate:.1f} Hz by the sensor's stamps), "
        f"{missed} missed"
        + (f" (gaps in the stamps, period {period * 1e3:.2f} ms)" if len(stamps) > 1 else "")
        + (f"; written to {log_path}" if log_path else "")
        + ("; stopped by Ctrl-C" if interrupted else "")
    )
    print(line, file=sys.stdout, flush=True)
