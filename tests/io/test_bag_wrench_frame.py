"""A bag whose wrenches are published in the base frame (UR TCP-force style): named, then
converted.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin import calibrate
from ftkin.calibration.information import SensorNoise
from ftkin.io.bags import bag_samples

rosbags = pytest.importorskip("rosbags")
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
NOISE = SensorNoise(0.02, 0.002)
HOLD, MOVE, RATE = 2.0, 1.0, 50.0  # [s], [s], [Hz]


def _header(seconds, frame_id):
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
def base_frame_bag(tmp_path_factory, arm, truth):
    """Seven held poses; the wrench rotated into the base frame and stamped frame_id 'base_link'."""
    rng = np.random.default_rng(51)
    poses = arm.random_configurations(7, rng, margin=0.3)
    times = np.arange(0.0, len(poses) * (HOLD + MOVE) - MOVE, 1.0 / RATE)
    index = np.minimum((times // (HOLD + MOVE)).astype(int), len(poses) - 1)
    phase = np.clip((times - index * (HOLD + MOVE) - HOLD) / MOVE, 0.0, 1.0)
    following = np.minimum(index + 1, len(poses) - 1)
    q = poses[index] + (0.5 - 0.5 * np.cos(np.pi * phase))[:, None] * (
        poses[following] - poses[index]
    )
    rotations = arm.rotation_sensor_to_base(q)
    in_sensor = truth.predict(rotations) + rng.normal(size=(len(times), 6)) * NOISE.channel_std
    in_base = np.concatenate(
        [
            np.einsum("nij,nj->ni", rotations, in_sensor[:, :3]),
            np.einsum("nij,nj->ni", rotations, in_sensor[:, 3:]),
        ],
        axis=1,
    )
    path = tmp_path_factory.mktemp("bag") / "tcp_force"
    types = TYPESTORE.types
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        joints = writer.add_connection(
            "/joint_states", "sensor_msgs/msg/JointState", typestore=TYPESTORE
        )
        wrench = writer.add_connection(
            "/tcp_wrench", "geometry_msgs/msg/WrenchStamped", typestore=TYPESTORE
        )
        for t, qi, w in zip(times, q, in_base):
            stamp = int((1e9 + t) * 1e9)
            state = types["sensor_msgs/msg/JointState"](
                header=_header(1e9 + t, ""),
                name=list(arm.joint_names),
                position=qi,
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
            writer.write(
                joints, stamp, TYPESTORE.serialize_cdr(state, "sensor_msgs/msg/JointState")
            )
            message = types["geometry_msgs/msg/WrenchStamped"](
                header=_header(1e9 + t + 0.001, "base_link"),
                wrench=types["geometry_msgs/msg/Wrench"](
                    force=_vector(w[:3]), torque=_vector(w[3:])
                ),
            )
            writer.write(
                wrench,
                stamp + 1_000_000,
                TYPESTORE.serialize_cdr(message, "geometry_msgs/msg/WrenchStamped"),
            )
    return path


def test_base_frame_wrench_named_then_converted(base_frame_bag, arm, truth, caplog):
    with caplog.at_level(logging.WARNING):
        as_recorded = bag_samples(base_frame_bag, arm)
    assert (
        "published in the base frame 'base_link'" in caplog.text
        and "--wrench-frame base" in caplog.text
    )
    converted = bag_samples(base_frame_bag, arm, wrench_frame="base")
    assert not np.allclose(as_recorded.samples.wrenches, converted.samples.wrenches)
    result = calibrate(converted.samples, noise=NOISE)
    errors = result.std_errors
    assert np.all(
        np.abs(result.center_of_mass - truth.center_of_mass) < 4 * errors["center_of_mass"]
    )
    assert np.all(np.abs(result.force_offset - truth.force_offset) < 4 * errors["force_offset"])


def test_cli_wrench_frame_option(base_frame_bag, tmp_path, capsys):
    from ftkin import load_calibration
    from ftkin.cli import main

    calib = tmp_path / "calib.json"
    assert main(["calibrate", str(base_frame_bag), "--wrench-frame", "base", "-o", str(calib)]) == 0
    assert load_calibration(calib).pose_count == 7


def test_a_joint_named_like_another_column_is_kept_as_a_duplicate_header():
    """A URDF joint called ``t`` must not replace the time column of an extracted table."""
    import numpy as np

    from ftkin.io.bags import _table

    table = _table("bag", [("t", np.array([0.0, 0.5])), ("t", np.array([1.25, -2.0]))])
    assert table.header == ["t", "t"]
    np.testing.assert_allclose(np.array(table.rows, dtype=float), [[0.0, 1.25], [0.5, -2.0]])
