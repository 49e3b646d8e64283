"""Make docs/images/contact_sheet.png: the bundled arm's 9-pose plan through ``ftkin view --png``.

Simulated readings (paper-like tool and noise, 5 readings per pose, seed 0);
pose 4 gets a 1.5 N sideways push so that the calibration flags it as an outlier.
Run: ``PYTHONPATH=. python scripts/contact_sheet_example.py [OUT.png]`` (needs Chromium).
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

import numpy as np

import ftkin
from ftkin.cli import main
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import SimulatedSensor, paper_like_truth


def write_example(folder: Path, push_pose: int = 4) -> tuple[Path, Path]:
    """Calibration file and samples CSV of the 9-pose plan of the bundled arm."""
    arm = ftkin.Arm.default()
    plan = ftkin.plan_poses(arm, 9)
    rng = np.random.default_rng(0)
    samples = SimulatedSensor(
        paper_like_truth(), ftkin.SensorNoise.paper()
    ).samples_at_configurations(arm, plan.joint_positions, rng, readings_per_pose=5)
    wrenches = samples.wrenches.copy()
    wrenches[samples.pose_ids == push_pose, 1] += (
        1.5  # N along the sensor's y: a contact during the pose
    )
    header = [f"q{i + 1}" for i in range(arm.nq)] + ["fx", "fy", "fz", "mx", "my", "mz", "pose"]
    rows = [
        [*map(float, q), *map(float, w), int(p)]
        for q, w, p in zip(samples.joint_positions, wrenches, samples.pose_ids)
    ]
    write_csv(folder / "samples.csv", header, rows)
    calibration = ftkin.calibrate(ftkin.load_samples(folder / "samples.csv", arm=arm).samples)
    ftkin.save_calibration(calibration, folder / "calib.json")
    return folder / "calib.json", folder / "samples.csv"


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "docs/images/contact_sheet.png").resolve()
    with tempfile.TemporaryDirectory() as scratch:
        write_example(Path(scratch))
        os.chdir(scratch)
        sys.exit(main(["view", "calib.json", "samples.csv", "--png", str(out), "--no-wait"]))
