"""``ftkin extract RECORDING -o SAMPLES.csv``: the samples a bag yields, as a CSV to inspect."""

import numpy as np

from ..io.csv_table import write_csv
from .arg_types import add_command, option
from .common import add_samples_arguments, load_samples_from_args


def register(subparsers) -> None:
    add_command(
        subparsers,
        "extract",
        help="write the samples extracted from a ROS 2 bag (or a samples CSV) as a CSV",
        description="Read a ROS 2 bag (rosbag2 folder, .mcap or .db3), align joint states to the "
        "wrench stamps, find the static segments and write one row per reading: t [s], pose "
        "(static segment number), the arm's joint angles [rad] and fx..mz [N, N·m]. A continuous "
        "recording in a CSV (a time column, no pose column) gets the same search; its still rows "
        "are written with a pose column. The CSV is a valid input of 'ftkin calibrate'. With "
        "--all-rows, every reading (no pose column) is written.",
        options=(
            option("recording", metavar="RECORDING"),
            option("-o", "--output", metavar="SAMPLES.csv", required=True),
        ),
        groups=(add_samples_arguments,),
        run=run,
    )


def run(args) -> int:
    loaded = load_samples_from_args(args.recording, args)
    write_csv(args.output, loaded.table.header, loaded.table.rows)
    print(
        f"wrote {len(loaded.table.rows)} readings"
        + (
            f" in {len(np.unique(loaded.samples.pose_ids))} static poses"
            if loaded.search is not None
            else ""
        )
        + f" to {args.output}"
    )
    recording = loaded.recording
    if recording is not None:
        print(
            f"  topics: {recording.joint_topic} (joints), {recording.wrench_topic} (wrench, frame "
            f"{recording.wrench_frame_id or '?'})"
        )
        if recording.dropped:
            print(
                f"  {recording.dropped} wrench readings outside the joint-state time range were "
                "dropped"
            )
    return 0
