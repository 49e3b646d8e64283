"""Moving recordings from CSV and ROS 2 bags: read, differentiate, identify (MuJoCo truth)."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import InvalidSamples, calibrate_dynamic, plan_excitation
from ftkin.io import load_motion_bag, load_motion_csv
from ftkin.io.csv_table import write_csv

mujoco_recording = pytest.importorskip("ftkin.sim.mujoco.recording")
pytest.importorskip("mujoco")
pytest.importorskip("rosbags")
from rosbags.rosbag2 import StoragePlugin, Writer  # noqa: E402
from rosbags.typesys import Stores, get_typestore  # noqa: E402

TYPESTORE = get_typestore(Stores.ROS2_HUMBLE)
TOOL = mujoco_recording.ToolInertia(1.5, [0.006, -0.012, 0.072], np.diag([0.006, 0.005, 0.002]))
BIAS = np.array([2.0, -1.5, 3.0, 0.1, -0.05, 0.02])
RATE = 500.0
T0 = 1_700_000_000.0


def _stamp(seconds):
    nanoseconds = int(round(seconds * 1e9))
    stamp = TYPESTORE.types["builtin_interfaces/msg/Time"](
        sec=nanoseconds // 10**9, nanosec=nanoseconds % 10**9
    )
    return TYPESTORE.types["std_msgs/msg/Header"](stamp=stamp, frame_id="ft_sensor")


@pytest.fixture(scope="module")
def excitation(arm):
    plan = plan_excitation(
        arm, 6.0, rate=RATE, period=3.0, harmonics=3, candidates=2, optimize=False, seed=3
    )
    recorder = mujoco_recording.MujocoRecorder(joint_names=arm.joint_names, tool=TOOL)
    wrenches = (
        recorder.wrenches(plan.joint_positions, plan.joint_velocities, plan.joint_accelerations)
        + BIAS
    )
    return plan, wrenches, recorder


def _check(result):
    assert abs(result.tool_mass - TOOL.mass) < 2e-3 * TOOL.mass
    np.testing.assert_allclose(result.center_of_mass, TOOL.center_of_mass, atol=5e-4)
    assert np.abs(result.inertia_about_com_in_sensor - TOOL.inertia_about_com).max() < 0.03 * 0.006


def test_bag_recording_identifies_the_tool(tmp_path, arm, excitation):
    plan, _, recorder = excitation
    types = TYPESTORE.types
    path = tmp_path / "motion"
    jitter = np.random.default_rng(0).uniform(-2e-4, 2e-4, len(plan.times))  # 10 % of the period
    wrench_times = plan.times + jitter
    wrenches = (
        recorder.wrenches(*plan.trajectory.evaluate(wrench_times)) + BIAS
    )  # measured at their stamps
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        joints = writer.add_connection(
            "/joint_states", "sensor_msgs/msg/JointState", typestore=TYPESTORE
        )
        wrench = writer.add_connection(
            "/wrench", "geometry_msgs/msg/WrenchStamped", typestore=TYPESTORE
        )
        for t, q in zip(plan.times, plan.joint_positions):
            message = types["sensor_msgs/msg/JointState"](
                header=_stamp(T0 + t),
                name=list(arm.joint_names),
                position=q,
                velocity=np.zeros(0),
                effort=np.zeros(0),
            )
            writer.write(
                joints,
                int((T0 + t) * 1e9),
                TYPESTORE.serialize_cdr(message, "sensor_msgs/msg/JointState"),
            )
        for t, w in zip(wrench_times, wrenches):
            vector = types["geometry_msgs/msg/Vector3"]
            message = types["geometry_msgs/msg/WrenchStamped"](
                header=_stamp(T0 + t),
                wrench=types["geometry_msgs/msg/Wrench"](
                    force=vector(*w[:3]), torque=vector(*w[3:])
                ),
            )
            writer.write(
                wrench,
                int((T0 + t) * 1e9),
                TYPESTORE.serialize_cdr(message, "geometry_msgs/msg/WrenchStamped"),
            )
    recording = load_motion_bag(path, arm)
    assert recording.times[1] - recording.times[0] == pytest.approx(1 / RATE, rel=0.05)
    _check(calibrate_dynamic(recording.motion_samples(arm)))
    # the same bag read as base-frame wrenches (a UR TCP force): rotated into the sensor frame,
    # R_BSᵀ w
    as_base = load_motion_bag(path, arm, wrench_frame="base")
    rotations = arm.rotation_sensor_to_base(as_base.joint_positions)
    expected = np.concatenate(
        [
            np.einsum("nji,nj->ni", rotations, recording.wrenches[:, :3]),
            np.einsum("nji,nj->ni", rotations, recording.wrenches[:, 3:]),
        ],
        axis=1,
    )
    np.testing.assert_allclose(as_base.wrenches, expected, atol=2e-3)


def test_csv_recording_and_its_errors(tmp_path, arm, excitation):
    plan, wrenches, _ = excitation
    header = ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"]
    rows = np.column_stack([plan.times, plan.joint_positions, wrenches])
    write_csv(tmp_path / "log.csv", header, rows.tolist())
    _check(calibrate_dynamic(load_motion_csv(tmp_path / "log.csv", arm).motion_samples(arm)))
    write_csv(tmp_path / "no_t.csv", header[1:], rows[:, 1:].tolist())
    with pytest.raises(InvalidSamples, match="time"):
        load_motion_csv(tmp_path / "no_t.csv", arm)
    backwards = rows.copy()
    backwards[5, 0] = backwards[3, 0]
    write_csv(tmp_path / "backwards.csv", header, backwards.tolist())
    with pytest.raises(InvalidSamples, match="line 7"):
        load_motion_csv(tmp_path / "backwards.csv", arm)
    gap = np.delete(rows, [100, 101, 102], axis=0)
    write_csv(tmp_path / "gap.csv", header, gap.tolist())
    with pytest.raises(InvalidSamples, match="uniformly"):
        load_motion_csv(tmp_path / "gap.csv", arm).motion_samples(arm)
