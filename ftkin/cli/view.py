"""``ftkin view CALIB.json SAMPLES.csv`` / ``ftkin view CALIB.json --replay LOG.csv``: see the
calibration in 3D.
"""

import argparse
import time

from .. import Arm, InvalidInput, load_calibration
from ..kinematics import mounted_arm
from ..viz.view_frames import (
    SHEET_CELLS,
    ViewFrames,
    pose_frames,
    replay_frames,
    save_frames_sheet,
    vector_table,
)
from .arg_types import add_command, bounded_int, option, positive_float
from .common import (
    add_samples_arguments,
    arm_for_calibration,
    load_samples_from_args,
)

# The calibration, what to show and how, and where to write it.
_OPTIONS = (
    option("calibration", metavar="CALIB.json"),
    option(
        "samples",
        metavar="SAMPLES.csv",
        nargs="?",
        help="the calibration samples (poses to step through)",
    ),
    option(
        "--replay",
        metavar="LOG.csv",
        help="play a recorded run instead: joint columns, fx..mz, optional t [s]",
    ),
    option(
        "--html",
        metavar="OUT.html",
        help="write a self-contained page (animated unless --pose is given)",
    ),
    option(
        "--png",
        metavar="OUT.png",
        help="write a screenshot with headless Chromium: the --pose (1024×768), else a "
        f"contact sheet of every pose (at most {SHEET_CELLS} evenly spaced rows of a "
        "replay; outlier poses outlined in red)",
    ),
    option(
        "--pose",
        type=int,
        metavar="K",
        help="only this pose: pose id of SAMPLES.csv, or row index of the replay log",
    ),
    option(
        "--no-wait",
        action="store_true",
        help="do not keep the live viewer running (scripts, tests)",
    ),
    option(
        "--scale",
        type=positive_float,
        metavar="M_PER_N",
        help="arrow length per newton [m/N] (default: tool weight drawn 25 cm long)",
    ),
    option(
        "--tilt-exaggeration",
        type=positive_float,
        default=1.0,
        metavar="K",
        help="draw the base tilt K times larger",
    ),
    option(
        "--hold",
        type=positive_float,
        default=1.0,
        metavar="S",
        help="seconds per calibration pose in the animation",
    ),
    option(
        "--max-frames",
        type=bounded_int(1, 1_000_000, "frames"),
        default=1500,
        metavar="N",
        help="replay: keep at most N rows (evenly spaced)",
    ),
)


def register(subparsers) -> None:
    add_command(
        subparsers,
        "view",
        help="3D view (meshcat) of the arm, sensor frame and "
        "force vectors at the calibration poses",
        description="Show the arm at each calibration pose with arrows from the sensor origin: "
        "measured force minus "
        "bias (magenta), predicted tool gravity (cyan), compensated contact force (yellow); the "
        "tool's centre of mass "
        "(green) and the estimated gravity direction of the base (purple). At a good calibration "
        "magenta lies on cyan. "
        "Starts a meshcat server and prints its URL (Ctrl-C stops it), or writes --html / --png.",
        options=_OPTIONS,
        groups=(add_samples_arguments,),
        run=run,
    )


def _load_frames(args, calibration, source: str):
    """The frames to show and the arm to draw them on (None: orientations only)."""
    arm = arm_for_calibration(args, calibration) or Arm.default()
    loaded = load_samples_from_args(source, args, static_only=not args.replay, arm=arm)
    frames = (
        replay_frames(loaded.samples, calibration, args.max_frames, loaded.table.source)
        if args.replay
        else pose_frames(loaded.samples, calibration)
    )
    if frames.configurations is None:
        return frames, None  # orientations without joint angles: no arm to draw
    return frames, mounted_arm(arm, calibration.mount_rotation)


def _write_outputs(
    viewer, frames: ViewFrames, chosen: int | None, shown, args, source: str
) -> None:
    """The screenshot or contact sheet, the animation (or the one pose ``shown``) and the page."""
    if args.png and chosen is not None:
        from ..viz.browser import screenshot_html

        label = frames.labels[chosen]
        screenshot_html(viewer.static_html(caption=f"{source}: {label}"), args.png)
        print(f"wrote {args.png} ({label})")
    elif args.png:
        cells, outliers = save_frames_sheet(
            viewer, frames, viewer.calibration, args.png, title=str(source)
        )
        print(
            f"wrote {args.png} (contact sheet of {cells} poses, {outliers} outliers outlined in "
            "red)"
        )
    if chosen is None:
        vectors = viewer.animate(
            frames.raw_wrenches, times=frames.times, hold=args.hold, **frames.placement()
        )
        print(vector_table(frames.labels, vectors))
    else:
        print(vector_table([frames.labels[chosen]], [shown]))
    if args.html:
        caption = f"{source}: " + (
            frames.labels[chosen] if chosen is not None else f"{len(frames.labels)} poses, animated"
        )
        viewer.save_html(args.html, caption=caption)
        print(f"wrote {args.html}")


def run(args: argparse.Namespace) -> int:
    from ..viz import CalibrationViewer  # meshcat is optional: imported only here

    if (args.samples is None) == (args.replay is None):
        raise InvalidInput("give SAMPLES.csv (calibration poses) or --replay LOG.csv, exactly one")
    calibration = load_calibration(args.calibration)
    source = args.replay or args.samples
    frames, arm = _load_frames(args, calibration, source)
    chosen = frames.index(args.pose, bool(args.replay)) if args.pose is not None else None
    with CalibrationViewer(
        calibration, arm, scale=args.scale, tilt_exaggeration=args.tilt_exaggeration
    ) as viewer:
        k = chosen if chosen is not None else 0
        shown = (
            viewer.show_rotation(frames.rotations[k], frames.raw_wrenches[k])
            if frames.configurations is None
            else viewer.show_pose(frames.configurations[k], frames.raw_wrenches[k])
        )
        print(
            f"scale: 1 N = {100 * viewer.scale:.3g} cm; magenta = measured force − bias, cyan = "
            "predicted tool gravity, yellow = contact force, green = tool COM, purple = base "
            "gravity direction"
        )
        _write_outputs(viewer, frames, chosen, shown, args, source)
        if args.no_wait or args.html or args.png:
            return 0
        print(
            f"meshcat viewer: {viewer.url}  (animation controls: Open Controls > Animations; "
            "Ctrl-C to stop)"
        )
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            print("stopped the viewer")
    return 0
