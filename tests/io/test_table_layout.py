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
from ftkin.io.table_layout import (
    GROUPED,
    MAX_RECORDER_STEP,
    ONE_PER_POSE,
    POSE_COLUMN_LAYOUT,
    RECORDING,
    table_layout,
)
from ftkin.sim.sensor import SimulatedSensor
from tests.io.test_continuous_recording import recording, write_recording
from tests.io.test_static_segments import trajectory

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
    assert "read as a pose table: 12 rows, one pose each (one reading per pose), because" in line
    assert "300 s apart" in line


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
    assert "read as a pose table: 60 rows, 12 pose(s) by its pose column" in line


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


# The rule (ftkin.io.table_layout): a recorder's rows come at steady steps of at most
# MAX_RECORDER_STEP (0.25 s); a pose table's rows are a move and a settling apart. Rows that
# never repeat an orientation are a pose table unless they are a recorder's smooth motion.

SWEEP_ROWS = 40
SWEEP_STEPS = (0.5, 1.0, 2.0, 4.5, 10.0)  # [deg] turn from one row to the next
RECORDER_SPACINGS = (0.01, 0.1, 0.2)  # [s] at most MAX_RECORDER_STEP: a sampled motion
TABLE_SPACINGS = (0.3, 1.0, 10.0, 60.0)  # [s] beyond it: one settled pose per row


def sweep(rows, step_deg, rng, jitter=1e-5):
    """``R_BS`` ``(rows, 3, 3)`` of a slow sweep turning ``step_deg`` [deg] from each row to the
    next, about the sensor's x axis for the first half and its y axis after (two axes: the
    tool's weight can be told from the bias), with ``jitter`` [rad] of encoder-level noise."""
    from scipy.spatial.transform import Rotation

    axes = np.where((np.arange(rows - 1) < rows // 2)[:, None], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0])
    turns = Rotation.from_rotvec(np.radians(step_deg) * axes)
    orientations = [Rotation.from_euler("xyz", [0.3, -0.2, 0.1])]
    for turn in turns:
        orientations.append(orientations[-1] * turn)
    noise = Rotation.from_rotvec(rng.normal(0.0, jitter, (rows, 3)))
    return (Rotation.concatenate(orientations) * noise).as_matrix()


def test_the_sweep_turns_by_its_step(rng):
    """The generator, checked on its own: consecutive rows differ by the step, within jitter."""
    from scipy.spatial.transform import Rotation

    rotations = sweep(SWEEP_ROWS, 4.5, rng)
    relative = Rotation.from_matrix(rotations[:-1]).inv() * Rotation.from_matrix(rotations[1:])
    np.testing.assert_allclose(np.degrees(relative.magnitude()), 4.5, atol=0.01)


@pytest.mark.parametrize("spacing", TABLE_SPACINGS)
@pytest.mark.parametrize("step_deg", SWEEP_STEPS)
def test_a_sweep_with_rows_a_settling_apart_is_a_pose_table(step_deg, spacing, rng):
    """The issue: 4.5° steps 10 s apart read as one still stretch of 390 s and refused. Every
    row is a pose the arm was moved to: 40 rows, 40 poses, whatever the implied speed."""
    rotations = sweep(SWEEP_ROWS, step_deg, rng)
    times = 100.0 + spacing * np.arange(SWEEP_ROWS)
    layout = table_layout(times, rotations.reshape(-1, 9), STILL, "orientation speed")
    assert layout.kind == ONE_PER_POSE and layout.pose_table
    assert layout.rows == layout.poses == SWEEP_ROWS
    np.testing.assert_array_equal(layout.pose_ids, np.arange(SWEEP_ROWS))
    assert layout.time_step == pytest.approx(spacing, rel=1e-9)
    note = layout.describe()
    assert note.startswith(f"read as a pose table: {SWEEP_ROWS} rows, one pose each")
    assert f"{spacing:g} s apart" in note


@pytest.mark.parametrize("spacing", RECORDER_SPACINGS)
@pytest.mark.parametrize("step_deg", SWEEP_STEPS)
def test_the_same_sweep_at_a_recorders_rate_is_a_motion_and_refused(step_deg, spacing, rng):
    """Rows at most 0.25 s apart, each turned from the last: a sampled motion never held still
    (an excitation), refused with advice that works (--all-rows, --dynamic)."""
    rotations = sweep(SWEEP_ROWS, step_deg, rng)
    times = spacing * np.arange(SWEEP_ROWS)
    with pytest.raises(InvalidSamples, match=r"no usable still segment.*never holds a pose"):
        table_layout(times, rotations.reshape(-1, 9), STILL, "orientation speed")


def test_the_recorder_step_threshold_is_where_the_docs_say():
    """MAX_RECORDER_STEP lies between a 10 Hz recorder and the fastest pose table (0.5 s)."""
    assert max(RECORDER_SPACINGS) <= MAX_RECORDER_STEP < min(TABLE_SPACINGS)
    assert 0.1 < MAX_RECORDER_STEP < 0.5


@pytest.mark.parametrize(("offset", "poses"), [(0.5, 20), (0.9, 20), (1.1, 40), (2.0, 40)])
def test_a_repeated_reading_within_the_pose_tolerance_is_one_pose(offset, poses, arm, rng):
    """Each of 20 poses read twice, the second reading off by ``offset`` × pose_tolerance on one
    joint, rows 10 s apart: within the tolerance the two are one pose, beyond it two."""
    q = np.repeat(planned_poses(arm, 20, rng), 2, axis=0)
    q[1::2, 4] += offset * STILL.pose_tolerance
    layout = table_layout(10.0 * np.arange(len(q)), q, STILL)
    assert layout.poses == poses and layout.pose_table
    assert layout.kind == (GROUPED if poses == 20 else ONE_PER_POSE)
    expected = np.repeat(np.arange(20), 2) if poses == 20 else np.arange(40)
    np.testing.assert_array_equal(layout.pose_ids, expected)


@pytest.mark.parametrize("spacing", [0.3, 0.5, 2.0])
def test_two_readings_per_pose_a_fraction_of_a_second_apart_are_grouped(spacing, arm, rng):
    """Two readings per pose, every row ``spacing`` apart: the speed at the second reading sees
    the move to the next pose, but rows a settling apart are one pose by their displacement
    alone (this read as 40 poses of one reading each)."""
    q = np.repeat(planned_poses(arm, 20, rng), 2, axis=0)
    layout = table_layout(spacing * np.arange(len(q)), q, STILL)
    assert layout.kind == GROUPED and layout.poses == 20
    np.testing.assert_array_equal(layout.pose_ids, np.repeat(np.arange(20), 2))


def stream_500_hz(rng, holds=5, drift=0.0):
    """A 500 Hz joint stream: ``holds`` still phases of 2 s with 1 s moves between them (the
    static-segment tests' trajectory), 1e-4 rad encoder jitter and a slow ``drift`` [rad/s]."""
    times, q, _ = trajectory([2.0] * holds, rng, jitter=1e-4)
    return times, q + drift * times[:, None]


@pytest.mark.parametrize("drift", [0.0, 2e-4])
def test_a_500_hz_stream_with_five_still_phases_is_a_recording(drift, rng):
    """Five holds, each 2 s: still by speed, 1.5 s usable after settling: 5 poses."""
    times, q = stream_500_hz(rng, drift=drift)
    layout = table_layout(times, q, STILL)
    assert layout.kind == RECORDING and not layout.pose_table
    assert layout.poses == len(layout.search.segments) == 5
    assert layout.time_step == pytest.approx(1 / 500, rel=1e-6)
    assert layout.describe().startswith("read as a continuous recording: rows every 0.002 s")


def test_a_500_hz_stream_with_a_gap_is_a_recording(rng):
    """0.6 s of rows dropped during the second move (one gap of 300 steps): still 5 poses."""
    times, q = stream_500_hz(rng)
    keep = (times < 5.2) | (times > 5.8)  # the second move runs from 5 s to 6 s
    layout = table_layout(times[keep], q[keep], STILL)
    assert layout.kind == RECORDING and layout.poses == 5


def test_timed_quaternion_sweep_calibrates_with_every_pose(truth, tmp_path, capsys):
    """The issue's table end to end: 40 quaternion rows 10 s apart, 4.5° apart. The CLI prints
    how it was read; the API returns it on ``LoadedSamples.layout``; the weight is recovered."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(46)
    rotations = sweep(SWEEP_ROWS, 4.5, rng, jitter=0.0)
    wrenches = SimulatedSensor(truth, NOISE).read(rotations, rng)
    wxyz = Rotation.from_matrix(rotations).as_quat()[:, [3, 0, 1, 2]]
    times = 10.0 * np.arange(SWEEP_ROWS)
    header = ["t", "qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz"]
    path = write_csv(tmp_path / "sweep.csv", header, np.column_stack([times, wxyz, wrenches]))
    loaded = load_samples(path, segments=STILL)
    assert loaded.layout.kind == ONE_PER_POSE and loaded.layout.poses == SWEEP_ROWS
    assert len(np.unique(loaded.samples.pose_ids)) == SWEEP_ROWS
    result = calibrate(loaded.samples, drift="none")
    assert abs(result.tool_weight - truth.tool_weight) < 5 * result.std_errors["tool_weight"]
    assert main(["calibrate", str(path), "--drift", "none", "-o", str(tmp_path / "c.json")]) == 0
    line = read_line(capsys.readouterr().out)
    assert f"read as a pose table: {SWEEP_ROWS} rows, one pose each" in line
    assert "10 s apart" in line
    untimed = write_csv(tmp_path / "untimed.csv", header[1:], np.column_stack([wxyz, wrenches]))
    assert len(np.unique(load_samples(untimed, segments=STILL).samples.pose_ids)) == SWEEP_ROWS


def test_timed_joint_sweep_calibrates_with_every_pose(arm, truth, tmp_path):
    """The same with joint columns: joint 5 turns 4.5° a row, then joint 4, 10 s apart."""
    rng = np.random.default_rng(47)
    q = np.tile(0.5 * (arm.lower_limits + arm.upper_limits), (SWEEP_ROWS, 1))
    half = SWEEP_ROWS // 2
    q[:half, 4] += np.radians(4.5) * (np.arange(half) - half / 2)
    q[half:, 4] = q[half - 1, 4]
    q[half:, 3] += np.radians(4.5) * np.arange(1, SWEEP_ROWS - half + 1)
    path = timed_table(tmp_path / "joints.csv", arm, truth, q, 10.0 * np.arange(SWEEP_ROWS), rng)
    loaded = load_samples(path, arm, STILL)
    assert loaded.layout.kind == ONE_PER_POSE and loaded.layout.poses == SWEEP_ROWS
    result = calibrate(loaded.samples, drift="poly:1")
    assert abs(result.tool_weight - truth.tool_weight) < 5 * result.std_errors["tool_weight"]
