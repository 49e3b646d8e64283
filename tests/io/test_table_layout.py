"""A timed samples table is read as the shape it has: poses (one or a few rows each, any time
apart) or a continuous recording (a steady stream with still phases), told apart from the data.

The regression: a script that records one row per pose, minutes apart, was cut as if it were a
stream ("1 static segment(s) from 8 still stretch(es)" then "only 1 distinct pose(s)"), because
the speed between rows minutes apart is tiny. Each shape is simulated with a known truth and a
known drift, and calibrated through the CLI, the printed line saying how it was read.
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InvalidSamples
from ftkin.io.csv_table import write_csv
from ftkin.io.samples_csv import load_samples
from ftkin.io.static_segments import SegmentParameters
from ftkin.io.table_layout import GROUPED, ONE_PER_POSE, POSE_COLUMN_LAYOUT, RECORDING
from ftkin.sim.sensor import SimulatedSensor
from tests.io.test_continuous_recording import recording, write_recording

NOISE = SensorNoise.paper()
STILL = SegmentParameters()
DRIFT_RATE = np.array([2e-4, -1e-4, 3e-4, 0.0, 0.0, 0.0])  # [N/s, N·m/s]: linear bias drift


def planned_poses(arm, count, rng):
    """Poses a planner might give: spread over the workspace, consecutive ones close enough
    that the implied speed between rows minutes apart is far under the stillness threshold."""
    centre = 0.5 * (arm.lower_limits + arm.upper_limits)
    span = np.minimum(arm.upper_limits - arm.lower_limits, 2.0)
    walk = np.cumsum(rng.uniform(-0.5, 0.5, (count, arm.nq)), axis=0)
    return np.clip(centre + walk, centre - span / 2, centre + span / 2)


def timed_table(path, arm, truth, q, times, rng, pose_column=None):
    """One reading per row of ``q`` at ``times`` [s], with the linear drift added."""
    wrenches = SimulatedSensor(truth, NOISE).read(arm.rotation_sensor_to_base(q), rng)
    wrenches += np.outer(times, DRIFT_RATE)
    header = ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    columns = [times, q, wrenches]
    if pose_column is not None:
        header.insert(1, "pose")
        columns.insert(1, pose_column)
    write_csv(path, header, np.column_stack(columns).tolist())
    return path


def read_line(out: str) -> str:
    return next(line for line in out.splitlines() if "read as" in line)


def test_one_row_per_pose_minutes_apart_is_a_table_of_poses(arm, truth, tmp_path, capsys):
    rng = np.random.default_rng(40)
    q = planned_poses(arm, 12, rng)
    times = 300.0 * np.arange(12)  # five minutes between poses: speed ~1e-3 rad/s
    implied_speed = np.abs(np.diff(q, axis=0)).max(axis=1) / np.diff(times)
    assert np.all(implied_speed < STILL.speed_threshold)  # the old reading called this still
    path = timed_table(tmp_path / "poses.csv", arm, truth, q, times, rng)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == ONE_PER_POSE and loaded.layout.poses == 12
    assert len(np.unique(loaded.samples.pose_ids)) == 12
    np.testing.assert_allclose(loaded.samples.times, times, rtol=0, atol=1e-9)
    assert main(["calibrate", str(path), "--drift", "poly:1", "-o", str(tmp_path / "c.json")]) == 0
    line = read_line(capsys.readouterr().out)
    assert "12 rows read as one reading per pose" in line and "12 pose(s)" in line


def test_the_drift_fit_on_one_row_per_pose(arm, truth, tmp_path):
    """The shape a drift calibration needs: the linear drift is recovered within noise."""
    rng = np.random.default_rng(41)
    q = np.concatenate([planned_poses(arm, 12, rng)] * 2)  # every pose visited twice
    times = 60.0 * np.arange(len(q))
    path = timed_table(tmp_path / "poses.csv", arm, truth, q, times, rng)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == ONE_PER_POSE and loaded.layout.poses == 24
    result = calibrate(loaded.samples, drift="poly:1")
    first, last = result.bias_at(np.array([times[0], times[-1]]))
    measured_rate = (last - first) / (times[-1] - times[0])
    # the rate's error: the noise over the span, a few standard deviations
    tolerance = 4 * NOISE.channel_std / (times[-1] - times[0]) * np.sqrt(12 / len(q)) * 2
    np.testing.assert_allclose(measured_rate, DRIFT_RATE, rtol=0, atol=tolerance.max())
    np.testing.assert_allclose(first[:3], truth.force_offset, atol=0.05)


def test_a_10_hz_stream_with_still_phases_is_a_recording(arm, truth, tmp_path, capsys):
    rng = np.random.default_rng(42)
    times, q, wrenches, moving = recording(arm, truth, rng)
    assert 0.3 < moving < 0.6
    path = write_recording(tmp_path / "stream.csv", arm, times, q, wrenches)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == RECORDING and loaded.layout.poses == 12
    assert len(np.unique(loaded.samples.pose_ids)) == 12
    assert main(["calibrate", str(path), "--drift", "none"]) == 0
    line = read_line(capsys.readouterr().out)
    assert "read as a continuous recording" in line and "12 pose(s)" in line
    assert re.search(r"rows every 0\.1 s", line)


def test_a_table_with_a_pose_column_and_times(arm, truth, tmp_path, capsys):
    rng = np.random.default_rng(43)
    poses = planned_poses(arm, 12, rng)
    q = np.repeat(poses, 5, axis=0)
    pose = np.repeat(np.arange(12), 5)
    times = np.arange(len(q)) * 0.5 + pose * 30.0
    path = timed_table(tmp_path / "posed.csv", arm, truth, q, times, rng, pose)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == POSE_COLUMN_LAYOUT and loaded.layout.poses == 12
    np.testing.assert_array_equal(loaded.samples.pose_ids, pose)
    assert main(["calibrate", str(path), "--drift", "poly:1"]) == 0
    line = read_line(capsys.readouterr().out)
    assert "60 rows read as pose column (its pose column): 12 pose(s)" in line


def test_a_few_readings_per_pose_without_a_pose_column_are_grouped(arm, truth, tmp_path):
    """Five readings per pose 0.2 s apart, poses a minute apart: grouped by orientation, every
    row kept (a recording's settling and minimum duration would drop them all)."""
    rng = np.random.default_rng(44)
    q = np.repeat(planned_poses(arm, 12, rng), 5, axis=0)
    times = np.arange(len(q)) * 0.2 + np.repeat(np.arange(12), 5) * 60.0
    path = timed_table(tmp_path / "grouped.csv", arm, truth, q, times, rng)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == GROUPED and loaded.layout.poses == 12
    np.testing.assert_array_equal(loaded.samples.pose_ids, np.repeat(np.arange(12), 5))
    result = calibrate(loaded.samples, drift="none")
    assert abs(result.tool_weight - truth.tool_weight) < 0.05


def test_a_steady_motion_that_never_holds_still_is_refused(arm, truth, tmp_path):
    rng = np.random.default_rng(45)
    times, q, wrenches, moving = recording(arm, truth, rng, poses=4, hold=0.0)
    assert moving > 0.9
    path = write_recording(tmp_path / "moving.csv", arm, times, q, wrenches)
    with pytest.raises(InvalidSamples, match="no usable still segment: .* in motion.*rad/s"):
        load_samples(path, arm, STILL)


def test_a_stream_with_a_gap_is_still_a_recording(arm, truth, tmp_path):
    """Rows dropped for a gap of one joined stream (here 8 s in the middle, during a motion)
    made the times 'not a recorder's steady steps', and every row in motion became a pose."""
    rng = np.random.default_rng(42)
    times, q, wrenches, _ = recording(arm, truth, rng)
    middle = 0.5 * (times[0] + times[-1])
    keep = np.abs(times - middle) > 4.0
    path = write_recording(tmp_path / "gap.csv", arm, times[keep], q[keep], wrenches[keep])
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == RECORDING
    assert 10 <= loaded.layout.poses <= 12  # a still phase inside the gap is lost, no more


def test_milliseconds_read_as_seconds_are_named(arm, truth, tmp_path):
    """The same stream with its times in milliseconds: every motion is 1000 times slower, so a
    'still' segment turns by a radian; refused, naming the time unit."""
    rng = np.random.default_rng(42)
    times, q, wrenches, _ = recording(arm, truth, rng)
    path = write_recording(tmp_path / "ms.csv", arm, 1000.0 * times, q, wrenches)
    with pytest.raises(InvalidSamples, match=r"moves by .* within it: are the times in seconds"):
        load_samples(path, arm, STILL)
