"""Streams at different rates joined by time: interpolation against independent computations,
each malformed stream, and CSV files in any order and unit."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation, Slerp

from ftkin.exceptions import InvalidInput, InvalidSamples
from ftkin.io.imu_columns import load_imu_samples, read_stream
from ftkin.io.stream_join import Stream, join_streams, slerp

G = 9.80665
WRENCH = ("fx", "fy", "fz", "mx", "my", "mz")


def wrench_stream(times, name="wrench.csv"):
    columns = {c: np.sin(times + i) for i, c in enumerate(WRENCH)}
    return Stream(name, times, columns)


def imu_stream(times, name="imu.csv"):
    columns = {"ax": 0.1 * times, "ay": 1.0 + 0.0 * times, "az": G - 0.2 * times}
    columns.update({"wx": 2.0 * times, "wy": -times, "wz": 0.5 + 0.0 * times})
    return Stream(name, times, columns)


def test_output_at_the_wrench_rate_linear_exact():
    wrench_times = np.arange(0.0, 2.0, 1 / 700)
    imu_times = np.arange(0.0, 2.0, 1 / 250)
    joined = join_streams([imu_stream(imu_times), wrench_stream(wrench_times)])  # any order
    inside = wrench_times <= imu_times[-1]
    np.testing.assert_array_equal(joined.times, wrench_times[inside])
    np.testing.assert_allclose(joined.columns["ax"], 0.1 * joined.times, atol=1e-12)
    np.testing.assert_allclose(joined.columns["wx"], 2.0 * joined.times, atol=1e-12)
    np.testing.assert_array_equal(joined.columns["fx"], np.sin(wrench_times[inside]))
    assert joined.sources["ax"] == "imu.csv" and joined.sources["fx"] == "wrench.csv"
    assert joined.has("accelerometer") and joined.has("gyro") and not joined.has("orientation")


def test_orientation_by_slerp_matches_scipy(rng):
    times = np.arange(0.0, 1.0, 0.01)
    rotations = Rotation.from_rotvec(np.cumsum(rng.normal(0, 0.2, (len(times), 3)), axis=0))
    quaternions = rotations.as_quat()[:, [3, 0, 1, 2]]  # w, x, y, z
    quaternions[::3] *= -1.0  # q and −q: the same rotation, as logs have them
    at = np.sort(rng.uniform(times[0], times[-1], 200))
    got = slerp(times, quaternions, at)
    expected = Slerp(times, rotations)(at).as_quat()[:, [3, 0, 1, 2]]
    dots = np.abs(np.einsum("ij,ij->i", got, expected))
    np.testing.assert_allclose(dots, 1.0, atol=1e-12)
    orientation = Stream("pose.csv", times, dict(zip(("qw", "qx", "qy", "qz"), quaternions.T)))
    joined = join_streams([orientation, wrench_stream(np.arange(0.0, 1.0, 0.003))])
    assert np.allclose(np.linalg.norm(joined.array(("qw", "qx", "qy", "qz")), axis=1), 1.0)


def test_partial_overlap_is_said():
    joined = join_streams(
        [wrench_stream(np.arange(0.0, 10.0, 0.01)), imu_stream(np.arange(2.0, 8.0, 0.004))]
    )
    assert joined.times[0] >= 2.0 and joined.times[-1] <= 8.0
    assert joined.overlap == pytest.approx((2.0, 7.996))
    assert "covers the overlap 2–7.996 s" in joined.notes[0]
    assert "200 rows of wrench.csv before it" in joined.notes[0]


def test_no_overlap_is_refused():
    with pytest.raises(InvalidSamples, match="do not overlap"):
        join_streams(
            [wrench_stream(np.arange(0.0, 1.0, 0.01)), imu_stream(np.arange(5.0, 6.0, 0.01))]
        )


def test_stamps_not_increasing_name_the_line(tmp_path):
    path = tmp_path / "imu.csv"
    rows = ["t,ax,ay,az", "0.000,0,0,9.8", "0.004,0,0,9.8", "0.004,0,0,9.8", "0.012,0,0,9.8"]
    path.write_text("\n".join(rows) + "\n")
    with pytest.raises(InvalidSamples, match=r"imu.csv, line 4: time stamps do not increase"):
        read_stream(path)
    with pytest.raises(InvalidSamples, match="do not increase"):
        Stream("x", [0.0, 2.0, 1.0], {})


@pytest.mark.parametrize("policy", ["drop", "mark"])
def test_a_gap_is_dropped_or_marked_and_said(policy):
    imu_times = np.concatenate([np.arange(0.0, 1.0, 0.004), np.arange(1.5, 3.0, 0.004)])
    wrench_times = np.arange(0.0, 3.0, 1 / 700)
    joined = join_streams([wrench_stream(wrench_times), imu_stream(imu_times)], gaps=policy)
    inside = (wrench_times > 0.996) & (wrench_times < 1.5)
    assert "1 gap(s) longer than 0.02 s" in joined.notes[-1]
    assert f"0.996–1.5 s: {int(inside.sum())} rows" in joined.notes[-1]
    if policy == "drop":
        assert not np.any((joined.times > 0.996) & (joined.times < 1.5))
        assert not joined.in_gap.any()
    else:
        assert joined.in_gap.sum() == inside.sum()
    tight = join_streams([wrench_stream(wrench_times), imu_stream(imu_times)], max_gap=1.0)
    assert not any("gap" in note for note in tight.notes)


def test_malformed_streams():
    times = np.arange(0.0, 1.0, 0.01)
    with pytest.raises(InvalidSamples, match="exactly one stream must hold the wrench"):
        join_streams([imu_stream(times)])
    with pytest.raises(InvalidSamples, match="exactly one stream must hold the wrench"):
        join_streams([wrench_stream(times), wrench_stream(times, "other.csv")])
    with pytest.raises(InvalidSamples, match="in both"):
        join_streams([wrench_stream(times), imu_stream(times), imu_stream(times, "again.csv")])
    with pytest.raises(InvalidSamples, match="without"):
        Stream("half.csv", times, {"ax": times, "ay": times})
    with pytest.raises(InvalidSamples, match="not finite"):
        Stream("nan.csv", [0.0, np.nan, 1.0], {})
    with pytest.raises(InvalidInput, match="gaps"):
        join_streams([wrench_stream(times)], gaps="fill")
    with pytest.raises(InvalidInput, match="max_gap"):
        join_streams([wrench_stream(times)], max_gap=-1.0)


def _write(path, header, rows):
    path.write_text(
        ",".join(header) + "\n" + "\n".join(",".join(f"{v:.9g}" for v in r) for r in rows) + "\n"
    )
    return path


def test_files_in_any_order_units_and_roles(tmp_path):
    """A wrench log at 700 Hz and an IMU log at 250 Hz in g, both with µs stamps."""
    rotation = Rotation.random(random_state=1).as_matrix()
    wrench_t = np.arange(0.0, 2.0, 1 / 700)
    imu_t = np.arange(0.0, 2.0, 1 / 250)
    up = rotation.T @ np.array([0.0, 0.0, 1.0])  # [g]
    wrench = _write(
        tmp_path / "wrench.csv",
        ["t", *WRENCH],
        [[1e6 * t, 0, 0, -10, 0, 0, 0] for t in wrench_t],
    )
    imu = _write(
        tmp_path / "imu.csv",
        ["t", "ax", "ay", "az", "wx", "wy", "wz"],
        [[1e6 * t, *up, 0.1, 0, 0] for t in imu_t],
    )
    samples, joined = load_imu_samples(imu, wrench, time_unit="us", accel_unit="g")
    assert len(samples) == len(joined) == int(np.sum(wrench_t <= imu_t[-1]))
    np.testing.assert_allclose(
        samples.specific_force, np.tile(G * up, (len(samples), 1)), atol=1e-6
    )
    np.testing.assert_allclose(samples.angular_velocity[:, 0], 0.1)
    np.testing.assert_allclose(np.diff(samples.times), 1 / 700, rtol=1e-5)  # 9 digits of µs
    with pytest.raises(InvalidSamples, match="accel_unit='g'"):
        load_imu_samples(imu, wrench, time_unit="us")  # g read as m/s²
    seconds = _write(
        tmp_path / "imu_s.csv", ["t", "ax", "ay", "az"], [[t, *up] for t in imu_t + 1.0]
    )
    with pytest.raises(InvalidSamples, match="do not overlap"):  # one file in s, one in µs
        load_imu_samples(seconds, wrench, time_unit="us", accel_unit="g")
    with pytest.raises(InvalidInput, match="time_unit must be one of"):
        load_imu_samples(imu, wrench, time_unit="min")


def test_one_static_table_without_time(tmp_path):
    rows = [[0, 0, -10, 0, 0, 0, 0.0, 0.0, G, 0], [0, 0, -10, 0, 0, 0, 0.0, 0.0, G, 0]]
    path = _write(tmp_path / "static.csv", [*WRENCH, "ax", "ay", "az", "pose"], rows)
    samples, _ = load_imu_samples(path)
    assert samples.times is None and list(samples.pose_ids) == [0, 0]
