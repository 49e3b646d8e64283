"""A moving recording's own joint velocities and accelerations: used when given, checked against the
positions.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin.calibration.regressor import MotionSamples
from ftkin.exceptions import InvalidSamples
from ftkin.io.csv_table import write_csv
from ftkin.io.motion_recording import load_motion_csv

RATE, DURATION = 200.0, 4.0  # [Hz], [s]


def _trajectory(nq: int):
    """q = a sin(ω t + φ) per joint, with its exact derivatives (hand-computed)."""
    t = np.arange(int(RATE * DURATION)) / RATE
    a, w, phase = 0.4 + 0.05 * np.arange(nq), 1.0 + 0.3 * np.arange(nq), 0.2 * np.arange(nq)
    angle = np.outer(t, w) + phase
    return t, a * np.sin(angle), a * w * np.cos(angle), -a * w**2 * np.sin(angle)


def _write(path, arm, columns: dict):
    t, q, _, _ = _trajectory(arm.nq)
    wrench = np.tile([1.0, -2.0, 3.0, 0.1, 0.2, -0.1], (len(t), 1))
    header = ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz", *columns]
    write_csv(path, header, np.column_stack([t, q, wrench, *columns.values()]).tolist())
    return path


def test_given_derivatives_are_used_as_they_are(arm, tmp_path):
    t, q, dq, ddq = _trajectory(arm.nq)
    columns = {
        **{f"dq{i + 1}": dq[:, i] for i in range(arm.nq)},
        **{f"ddq{i + 1}": ddq[:, i] for i in range(arm.nq)},
    }
    recording = load_motion_csv(_write(tmp_path / "m.csv", arm, columns), arm)
    np.testing.assert_allclose(recording.joint_accelerations, ddq, rtol=1e-12)
    motion = recording.motion_samples(arm)
    expected = MotionSamples.from_joint_trajectory(arm, q, dq, ddq, recording.wrenches, t)
    np.testing.assert_allclose(motion.accelerations, expected.accelerations, rtol=1e-9, atol=1e-12)
    # named by joint: the same
    named = {
        **{f"{n}_velocity": dq[:, i] for i, n in enumerate(arm.joint_names)},
        **{f"{n}_acceleration": ddq[:, i] for i, n in enumerate(arm.joint_names)},
    }
    again = load_motion_csv(_write(tmp_path / "n.csv", arm, named), arm)
    np.testing.assert_allclose(again.joint_velocities, dq, rtol=1e-12)


@pytest.mark.parametrize(
    ("edit", "match"),
    [
        (lambda dq, ddq: (np.rad2deg(dq), ddq), "dq1..dq6 disagree with the time derivative"),
        (lambda dq, ddq: (dq, -ddq), "ddq1..ddq6 disagree"),
        (lambda dq, ddq: (dq[:, ::-1], ddq), "another order"),
    ],
)
def test_inconsistent_derivatives_are_refused(arm, tmp_path, edit, match):
    _, _, dq, ddq = _trajectory(arm.nq)
    dq, ddq = edit(dq, ddq)
    columns = {
        **{f"dq{i + 1}": dq[:, i] for i in range(arm.nq)},
        **{f"ddq{i + 1}": ddq[:, i] for i in range(arm.nq)},
    }
    with pytest.raises(InvalidSamples, match=match):
        load_motion_csv(_write(tmp_path / "m.csv", arm, columns), arm)


def test_partial_or_lone_derivatives(arm, tmp_path, caplog):
    _, _, dq, _ = _trajectory(arm.nq)
    with pytest.raises(InvalidSamples, match=r"joint velocity columns \['dq6'\] are missing"):
        load_motion_csv(
            _write(tmp_path / "a.csv", arm, {f"dq{i + 1}": dq[:, i] for i in range(arm.nq - 1)}),
            arm,
        )
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        recording = load_motion_csv(
            _write(tmp_path / "b.csv", arm, {f"dq{i + 1}": dq[:, i] for i in range(arm.nq)}), arm
        )
    assert recording.joint_velocities is None and "given without the other" in caplog.text


def test_nanosecond_stamps_and_ros_wrench_names_in_a_moving_recording(arm, tmp_path, caplog):
    from ftkin.io.column_spelling import ColumnSpelling
    from ftkin.io.csv_table import read_table
    from ftkin.io.motion_recording import is_motion_table

    t, q, _, _ = _trajectory(arm.nq)
    wrench = np.tile([1.0, -2.0, 3.0, 0.1, 0.2, -0.1], (len(t), 1))
    ros = ["force.x", "force.y", "force.z", "torque.x", "torque.y", "torque.z"]
    path = tmp_path / "ns.csv"
    write_csv(
        path,
        ["stamp", *arm.joint_names, *ros],
        np.column_stack([1.7644e18 + t * 1e9, q, wrench]).tolist(),
    )
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        assert not is_motion_table(read_table(path), arm)  # a static log then, not a crash
        with pytest.raises(InvalidSamples, match="not seconds.*--time-unit ns"):
            load_motion_csv(path, arm)
    spelled = load_motion_csv(path, arm, ColumnSpelling(time_unit="ns"))
    np.testing.assert_allclose(spelled.times - spelled.times[0], t - t[0], rtol=0, atol=1e-6)
    path = tmp_path / "ros.csv"
    write_csv(path, ["t", *arm.joint_names, *ros], np.column_stack([t, q, wrench]).tolist())
    np.testing.assert_allclose(load_motion_csv(path, arm).wrenches, wrench)
