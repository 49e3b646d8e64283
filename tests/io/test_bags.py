"""ROS 2 bags: real bags written with rosbags from a simulated recording with known truth."""

from __future__ import annotations

import shutil
import sys
from dataclasses import dataclass

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
)
from ftkin.calibration.model import WRENCH_CHANNELS
from ftkin.cli import main
from ftkin.exceptions import InvalidSamples, MissingDependency
from ftkin.io.bags import bag_samples, is_bag_path, read_bag
from ftkin.io.calibration_file import load_calibration
from ftkin.io.samples_csv import load_samples, read_table
from ftkin.io.static_segments import SegmentParameters

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
JOINT_STATE = "sensor_msgs/msg/JointState"
WRENCH_STAMPED = "geometry_msgs/msg/WrenchStamped"
T0 = 1_700_000_000.0  # absolute stamps, as on a real robot [s]
HOLD, MOVE = 2.0, 1.0  # [s] still, then moving to the next pose
JOINT_RATE, WRENCH_RATE = 40.0, 100.0  # [Hz], deliberately different
OVERSHOOT = 1.0  # [N] transient on fz after each stop, decaying with 0.1 s
NOISE = SensorNoise.paper()


@dataclass
class Recording:
    """A simulated session: hold each pose, move smoothly to the next."""

    poses: np.ndarray  # (P, nq) [rad]

    @property
    def duration(self) -> float:
        return len(self.poses) * (HOLD + MOVE) - MOVE

    def q(self, t: np.ndarray) -> np.ndarray:
        """Joint positions at times since start [s] (cosine blend while moving)."""
        t = np.asarray(t, dtype=float)
        k = np.clip((t // (HOLD + MOVE)).astype(int), 0, len(self.poses) - 1)
        phase = t - k * (HOLD + MOVE) - HOLD
        s = np.where(phase > 0, 0.5 - 0.5 * np.cos(np.pi * np.clip(phase / MOVE, 0, 1)), 0.0)
        following = np.minimum(k + 1, len(self.poses) - 1)
        return self.poses[k] + s[:, None] * (self.poses[following] - self.poses[k])

    def since_stop(self, t: np.ndarray) -> np.ndarray:
        """Time since the arm last stopped [s] (large while moving)."""
        phase = np.asarray(t) % (HOLD + MOVE)
        return np.where(phase <= HOLD, phase + (np.asarray(t) >= HOLD + MOVE) * 0.0, np.inf)


def make_recording(arm, rng, poses: int = 7) -> Recording:
    return Recording(arm.random_configurations(poses, rng, margin=0.3))


def write_bag(
    path,
    arm,
    truth,
    recording: Recording,
    rng,
    *,
    storage=StoragePlugin.MCAP,
    joint_names=None,
    joint_topic="/joint_states",
    wrench_topics=("/ft_sensor/wrench",),
    with_joints=True,
):
    """Write a rosbag2 with shuffled joint-name order, an extra finger joint and two rates."""
    names = list(joint_names or arm.joint_names)
    msg = TYPESTORE.types
    with Writer(path, version=9, storage_plugin=storage) as writer:
        if with_joints:
            joint_connection = writer.add_connection(joint_topic, JOINT_STATE, typestore=TYPESTORE)
            for t in np.arange(0.0, recording.duration, 1.0 / JOINT_RATE):
                q = recording.q(np.array([t]))[0] + rng.normal(0, 1e-5, arm.nq)
                order = rng.permutation(len(names) + 1)
                all_names = names + ["finger_joint"]
                all_values = np.append(q, 0.02)
                message = msg["sensor_msgs/msg/JointState"](
                    header=_header(T0 + t, ""),
                    name=[all_names[i] for i in order],
                    position=all_values[order],
                    velocity=np.zeros(0),
                    effort=np.zeros(0),
                )
                # received 3 ms after the stamp
                writer.write(
                    joint_connection,
                    int((T0 + t + 0.003) * 1e9),
                    TYPESTORE.serialize_cdr(message, JOINT_STATE),
                )
        wrench_times = np.arange(0.0, recording.duration, 1.0 / WRENCH_RATE) + 0.0037
        rotations = arm.rotation_sensor_to_base(recording.q(wrench_times))
        raw = (
            truth.predict(rotations)
            + rng.standard_normal((len(wrench_times), 6)) * NOISE.channel_std
        )
        raw[:, 2] += OVERSHOOT * np.exp(-recording.since_stop(wrench_times) / 0.1)
        for topic in wrench_topics:
            connection = writer.add_connection(topic, WRENCH_STAMPED, typestore=TYPESTORE)
            for t, w in zip(wrench_times, raw):
                message = msg["geometry_msgs/msg/WrenchStamped"](
                    header=_header(T0 + t, "ft_sensor"),
                    wrench=msg["geometry_msgs/msg/Wrench"](
                        force=_vector(w[:3]), torque=_vector(w[3:])
                    ),
                )
                writer.write(
                    connection,
                    int((T0 + t + 0.001) * 1e9),
                    TYPESTORE.serialize_cdr(message, WRENCH_STAMPED),
                )
    return path


def _header(seconds: float, frame_id: str):
    nanoseconds = int(round(seconds * 1e9))
    stamp = TYPESTORE.types["builtin_interfaces/msg/Time"](
        sec=nanoseconds // 10**9, nanosec=nanoseconds % 10**9
    )
    return TYPESTORE.types["std_msgs/msg/Header"](stamp=stamp, frame_id=frame_id)


def _vector(values):
    return TYPESTORE.types["geometry_msgs/msg/Vector3"](
        x=float(values[0]), y=float(values[1]), z=float(values[2])
    )


@pytest.fixture(scope="module")
def session(tmp_path_factory, arm, truth):
    """One recording written as an MCAP bag, an sqlite3 bag and a bare .mcap."""
    rng = np.random.default_rng(2024)
    recording = make_recording(arm, rng)
    folder = tmp_path_factory.mktemp("bags")
    mcap = write_bag(folder / "rec_mcap", arm, truth, recording, np.random.default_rng(1))
    sqlite = write_bag(
        folder / "rec_sqlite",
        arm,
        truth,
        recording,
        np.random.default_rng(1),
        storage=StoragePlugin.SQLITE3,
    )
    bare = folder / "bare.mcap"
    shutil.copy(next(mcap.glob("*.mcap")), bare)
    return {
        "recording": recording,
        "mcap": mcap,
        "sqlite": sqlite,
        "bare": bare,
        "db3": next(sqlite.glob("*.db3")),
    }


def _within_noise(result, truth, samples):
    poses = samples.pose_averages()
    information = fisher_information(truth, poses.rotations, NOISE, poses.counts)
    sigma = np.sqrt(np.diag(covariance_from_information(information)))
    error = result.to_vector() - truth.to_vector()
    assert np.all(np.abs(error) < 5 * sigma), error / sigma


@pytest.mark.parametrize("kind", ["mcap", "sqlite", "bare", "db3"])
def test_calibrate_from_bag_recovers_truth(kind, session, arm, truth):
    loaded = bag_samples(session[kind], arm)
    assert len(np.unique(loaded.samples.pose_ids)) == len(session["recording"].poses)
    _within_noise(calibrate(loaded.samples), truth, loaded.samples)
    assert is_bag_path(session[kind])


def test_storages_give_identical_samples(session, arm):
    reference = bag_samples(session["mcap"], arm).samples
    for kind in ("sqlite", "bare", "db3"):
        other = bag_samples(session[kind], arm).samples
        np.testing.assert_allclose(other.wrenches, reference.wrenches, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(
            other.joint_positions, reference.joint_positions, rtol=1e-12, atol=1e-15
        )


def test_joints_matched_by_name_and_interpolated_to_wrench_stamps(session, arm):
    """Shuffled names, an extra joint, 40 Hz joints vs 100 Hz wrench: q(t) matches the
    trajectory.
    """
    recording = read_bag(session["mcap"], arm)
    assert recording.joint_names == arm.joint_names
    assert recording.wrench_frame_id == "ft_sensor"
    exact = session["recording"].q(recording.times - T0)
    # linear interpolation of a cosine blend at 40 Hz: error ≤ (Δt²/8)·max|q̈| + encoder noise
    max_acceleration = (
        np.max(np.abs(np.diff(session["recording"].poses, axis=0))) * (np.pi / MOVE) ** 2 / 2
    )
    bound = (1 / JOINT_RATE) ** 2 / 8 * max_acceleration + 5e-5
    assert np.max(np.abs(recording.joint_positions - exact)) < bound
    assert len(recording.times) > 0.95 * WRENCH_RATE * session["recording"].duration


def test_static_readings_skip_settling_and_motion(session, arm):
    parameters = SegmentParameters()
    loaded = bag_samples(session["mcap"], arm, parameters=parameters)
    t = loaded.table.floats(["t"])[:, 0] - T0
    phase = t % (HOLD + MOVE)
    assert np.all(phase <= HOLD + 1e-6)  # never while moving
    assert np.all(phase >= parameters.settle_time - 1.0 / JOINT_RATE)  # settling skipped
    # skipping nothing lets the post-stop overshoot bias fz: the fit gets visibly worse
    loose = bag_samples(session["mcap"], arm, parameters=SegmentParameters(settle_time=0.0))
    assert calibrate(loose.samples).residual_rms[2] > 3 * calibrate(loaded.samples).residual_rms[2]


def test_all_readings_for_compensation(session, arm):
    loaded = bag_samples(session["mcap"], arm, static_only=False)
    assert loaded.table.header == ["t", *arm.joint_names, *WRENCH_CHANNELS]
    assert len(loaded.samples) == len(loaded.recording.times)
    assert loaded.search is None


def test_progress_bar_when_asked(session, arm, capsys):
    read_bag(session["mcap"], arm, progress=True)
    assert "reading bag" in capsys.readouterr().err
    read_bag(session["mcap"], arm)
    assert capsys.readouterr().err == ""


# ------------------------------------------------------------------ errors
def test_missing_topic_lists_topics(session, arm):
    with pytest.raises(
        InvalidSamples,
        match=r"no topic '/wrench'.*/ft_sensor/wrench \(geometry_msgs/msg/WrenchStamped\)",
    ):
        read_bag(session["mcap"], arm, wrench_topic="/wrench")
    with pytest.raises(
        InvalidSamples, match="carries sensor_msgs/msg/JointState, expected geometry_msgs"
    ):
        read_bag(session["mcap"], arm, wrench_topic="/joint_states")


def test_bag_without_joint_states(tmp_path, arm, truth, rng):
    path = write_bag(
        tmp_path / "b", arm, truth, make_recording(arm, rng, 2), rng, with_joints=False
    )
    with pytest.raises(
        InvalidSamples,
        match=r"no sensor_msgs/msg/JointState topic in the bag; topics found: /ft_sensor/wrench",
    ):
        read_bag(path, arm)


def test_ambiguous_wrench_topics(tmp_path, arm, truth, rng):
    path = write_bag(
        tmp_path / "b",
        arm,
        truth,
        make_recording(arm, rng, 2),
        rng,
        wrench_topics=("/a/wrench", "/b/wrench"),
    )
    expected = (
        r"several .*WrenchStamped topics: \['/a/wrench', '/b/wrench'\]; choose one with "
        r"--wrench-topic"
    )
    with pytest.raises(InvalidSamples, match=expected):
        read_bag(path, arm)
    assert len(read_bag(path, arm, wrench_topic="/b/wrench").times) > 0


def test_joint_names_not_matching_urdf(tmp_path, arm, truth, rng):
    wrong = [f"ur_joint{i}" for i in range(1, 7)]
    path = write_bag(
        tmp_path / "b", arm, truth, make_recording(arm, rng, 2), rng, joint_names=wrong
    )
    with pytest.raises(
        InvalidSamples,
        match=r"missing \['joint1'.*the bag has \['finger_joint', 'ur_joint1'.*expects \['joint1'",
    ):
        read_bag(path, arm)


def test_no_static_segment(session, arm):
    expected = (
        r"no static segments.*0 static segment\(s\) from 7 still "
        r"stretch\(es\).*--min-static-duration"
    )
    with pytest.raises(InvalidSamples, match=expected):
        bag_samples(session["mcap"], arm, parameters=SegmentParameters(min_duration=5.0))


def test_not_a_bag(tmp_path, arm):
    broken = tmp_path / "broken.mcap"
    broken.write_bytes(b"not an mcap file")
    with pytest.raises(InvalidSamples, match="cannot read the bag"):
        read_bag(broken, arm)
    with pytest.raises(InvalidSamples, match="file not found"):
        read_bag(tmp_path / "missing.mcap", arm)


def test_missing_rosbags(monkeypatch, session, arm):
    monkeypatch.setitem(sys.modules, "rosbags.highlevel", None)
    with pytest.raises(MissingDependency, match=r"ftkin\[bags\]"):
        read_bag(session["mcap"], arm)


# --------------------------------------------------------------------- CLI
def test_cli_calibrate_compensate_extract(session, tmp_path, truth, capsys):
    bag = str(session["bare"])
    calib = tmp_path / "calib.json"
    topics = ["--joint-topic", "/joint_states", "--wrench-topic", "/ft_sensor/wrench"]
    assert main(["calibrate", bag, *topics, "-o", str(calib)]) == 0
    result = load_calibration(calib)
    np.testing.assert_allclose(result.tool_weight, truth.tool_weight, atol=0.01)

    out = tmp_path / "out.csv"
    assert main(["compensate", str(calib), bag, "-o", str(out)]) == 0
    table = read_table(out)
    assert table.header[0] == "t" and table.header[-6:] == list(WRENCH_CHANNELS)
    contact = table.floats(WRENCH_CHANNELS)
    t = table.floats(["t"])[:, 0] - T0
    settled = (t % (HOLD + MOVE)) > 0.5
    assert np.median(np.abs(contact[settled, :3])) < 3 * NOISE.force_std.max()

    samples_csv = tmp_path / "samples.csv"
    assert main(["extract", bag, "-o", str(samples_csv)]) == 0
    assert "7 static poses" in capsys.readouterr().out
    from_csv = calibrate(load_samples(samples_csv).samples)
    np.testing.assert_allclose(from_csv.to_vector(), result.to_vector(), rtol=1e-9, atol=1e-12)


def test_cli_error_is_one_line(session, capsys):
    assert main(["calibrate", str(session["mcap"]), "--wrench-topic", "/nope"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftkin: error:") and "no topic '/nope'" in err and err.count("\n") == 1


def test_corrupt_bags_end_in_an_ftkin_error(session, arm, tmp_path):
    """Byte-level corruption of a valid .mcap (a mini fuzz run): a result or an ftkin error, nothing
    else.
    """
    import random

    from ftkin.exceptions import FtkinError

    sys.path.insert(
        0, str(__import__("pathlib").Path(__file__).resolve().parents[2] / "benchmarks")
    )
    from fuzz_readers import mutate_bytes

    original = session["bare"].read_bytes()
    rng = random.Random(7)
    outcomes = {"ok": 0, "error": 0}
    for _ in range(150):
        corrupt = tmp_path / "corrupt.mcap"
        corrupt.write_bytes(mutate_bytes(original, rng))
        try:
            loaded = bag_samples(corrupt, arm, progress=False)
            assert np.all(np.isfinite(loaded.samples.wrenches))
            outcomes["ok"] += 1
        except FtkinError:
            outcomes["error"] += 1
    assert outcomes["error"] > 0
