"""A samples CSV recorded continuously (10 Hz, the arm moving between still phases): only the still
segments are fitted.

The simulated recording holds each pose 1.9 s and moves 1.6 s to the next (45 % of the rows in
motion); while moving, the readings carry the tool's inertial load ``Y(v, a) θ`` (the regressor
of :mod:`ftkin.calibration.regressor`), so a fit of every row is biased.
"""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.calibration.regressor import body_regressor, sensor_motion
from ftkin.cli import main
from ftkin.exceptions import InvalidSamples
from ftkin.io.csv_table import read_table, write_csv
from ftkin.io.samples_csv import load_samples
from ftkin.io.static_segments import SegmentParameters
from ftkin.sim.sensor import SimulatedSensor, recording_times

RATE = 10.0  # [Hz]
HOLD, MOVE = 1.9, 1.6  # [s] still, then moving to the next pose: 45 % of the time in motion
NOISE = SensorNoise.paper()
STILL = SegmentParameters()  # what calibrate, report, extract and view pass (not --all-rows)


def recording(arm, truth, rng, poses=12, hold=HOLD):
    """``(times, q, wrenches)`` of a continuous recording, and the fraction of rows in motion."""
    targets = arm.random_configurations(poses, rng, margin=0.3)
    period = hold + MOVE
    times = np.arange(0.0, poses * period - MOVE, 1.0 / RATE)
    k = np.minimum((times // period).astype(int), poses - 1)
    phase = np.clip((times - k * period - hold) / MOVE, 0.0, 1.0)
    step = targets[np.minimum(k + 1, poses - 1)] - targets[k]
    s = 0.5 - 0.5 * np.cos(np.pi * phase)  # cosine blend [0, 1]
    ds = 0.5 * np.pi / MOVE * np.sin(np.pi * phase) * (phase < 1) * (phase > 0)
    dds = 0.5 * (np.pi / MOVE) ** 2 * np.cos(np.pi * phase) * (phase < 1) * (phase > 0)
    q, dq, ddq = targets[k] + s[:, None] * step, ds[:, None] * step, dds[:, None] * step
    rotations, velocities, accelerations = sensor_motion(arm, q, dq, ddq)
    wrenches = SimulatedSensor(truth, NOISE).read(rotations, rng)
    mass = truth.tool_mass  # a point-mass tool: θ = [m, m·c, 0...] [kg, kg·m, kg·m²]
    theta = np.concatenate([[mass], mass * np.asarray(truth.center_of_mass), np.zeros(6)])
    wrenches -= body_regressor(velocities, accelerations) @ theta
    return times, q, wrenches, float(np.mean((phase > 0) & (phase < 1)))


def write_recording(path, arm, times, q, wrenches):
    header = ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    write_csv(path, header, np.column_stack([times, q, wrenches]).tolist())
    return path


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, arm, truth):
    rng = np.random.default_rng(4)  # an all-rows fit 2.5 % low, as in the issue
    times, q, wrenches, moving = recording(arm, truth, rng)
    path = write_recording(
        tmp_path_factory.mktemp("continuous") / "log.csv", arm, times, q, wrenches
    )
    return path, moving


def test_still_segments_are_fitted_and_the_all_rows_fit_is_biased(recorded, arm, truth):
    path, moving = recorded
    assert 0.40 < moving < 0.50  # the recording: 45 % of the rows in motion
    loaded = load_samples(path, arm, STILL)
    assert len(loaded.search.segments) == 12  # one per hold
    assert len(np.unique(loaded.samples.pose_ids)) == 12
    result = calibrate(loaded.samples, drift="none")
    weight_se = result.std_errors["tool_weight"]
    assert abs(result.tool_weight - truth.tool_weight) < 4 * weight_se  # within noise
    every_row = calibrate(load_samples(path, arm).samples, drift="none")
    assert abs(every_row.tool_weight - truth.tool_weight) > 10 * weight_se  # biased by motion


def test_only_still_rows_are_kept_and_extract_writes_them(recorded, arm, tmp_path, capsys):
    path, _ = recorded
    out = tmp_path / "static.csv"
    assert main(["extract", str(path), "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "12 static segment(s)" in printed and "joint speed" in printed
    table = read_table(out)
    assert table.header[-1] == "pose"
    kept = load_samples(out, arm, STILL)
    direct = load_samples(path, arm, STILL)
    np.testing.assert_allclose(kept.samples.wrenches, direct.samples.wrenches, rtol=1e-12)
    np.testing.assert_array_equal(kept.samples.pose_ids, direct.samples.pose_ids)
    speed = np.abs(np.diff(table.floats(arm.joint_names), axis=0)).max(axis=1)
    same_pose = np.diff(table.floats(["pose"])[:, 0]) == 0
    assert np.all(speed[same_pose] < 1e-9)  # no moving row inside a pose


def test_calibrate_reports_the_segments_and_all_rows_keeps_every_row(recorded, capsys):
    path, _ = recorded
    assert main(["calibrate", str(path), "--drift", "none"]) == 0
    assert "static segment(s)" in capsys.readouterr().out
    assert main(["calibrate", str(path), "--drift", "none", "--all-rows"]) == 0
    assert "static segment(s)" not in capsys.readouterr().out


def test_quaternion_recording_uses_the_orientation_speed(recorded, arm, tmp_path):
    path, _ = recorded
    table = read_table(path)
    q = table.floats(arm.joint_names)
    from scipy.spatial.transform import Rotation

    xyzw = Rotation.from_matrix(arm.rotation_sensor_to_base(q)).as_quat()
    header = ["t", "qw", "qx", "qy", "qz", "fx", "fy", "fz", "mx", "my", "mz"]
    wrenches = table.floats(["fx", "fy", "fz", "mx", "my", "mz"])
    rows = np.column_stack([table.floats(["t"]), xyzw[:, [3, 0, 1, 2]], wrenches])
    quaternions = write_csv(tmp_path / "quaternions.csv", header, rows.tolist())
    loaded = load_samples(quaternions, segments=STILL)
    assert loaded.search.quantity == "orientation speed"
    assert len(loaded.search.segments) == 12


def test_motion_without_a_usable_still_segment_is_refused(arm, truth, tmp_path):
    times, q, wrenches, _ = recording(arm, truth, np.random.default_rng(5), poses=5, hold=0.8)
    path = write_recording(tmp_path / "short_holds.csv", arm, times, q, wrenches)
    with pytest.raises(InvalidSamples, match=r"no usable still segment: \d+ of \d+ samples"):
        load_samples(path, arm, STILL)
    assert len(load_samples(path, arm).samples) == len(times)  # --all-rows


def test_a_recording_in_motion_throughout_is_refused(arm, truth, tmp_path):
    times, q, wrenches, moving = recording(arm, truth, np.random.default_rng(6), poses=4, hold=0.0)
    assert moving > 0.9  # an excitation-like recording: never held still
    path = write_recording(tmp_path / "moving.csv", arm, times, q, wrenches)
    with pytest.raises(InvalidSamples, match="no usable still segment: .* in motion"):
        load_samples(path, arm, STILL)


def test_one_timed_reading_per_pose_is_not_a_recording(arm, truth, rng, tmp_path):
    q = arm.random_configurations(12, rng, margin=0.3)
    wrenches = SimulatedSensor(truth, NOISE).read(arm.rotation_sensor_to_base(q), rng)
    path = write_recording(tmp_path / "poses.csv", arm, 30.0 * np.arange(12), q, wrenches)
    loaded = load_samples(path, arm, STILL)
    assert loaded.search is None and len(loaded.samples) == 12


def test_a_stop_and_go_log_keeps_every_row_as_before(arm, truth, rng, tmp_path):
    """Readings logged only while still (3 at 1 kHz per pose, 10 s apart): not a recording."""
    q = np.repeat(arm.random_configurations(6, rng, margin=0.3), 3, axis=0)
    wrenches = SimulatedSensor(truth, NOISE).read(arm.rotation_sensor_to_base(q), rng)
    times = recording_times(6, 3, 60.0)  # [s]
    path = write_recording(tmp_path / "stop_and_go.csv", arm, times, q, wrenches)
    loaded = load_samples(path, arm, STILL)
    assert loaded.search is None and len(np.unique(loaded.samples.pose_ids)) == 18
