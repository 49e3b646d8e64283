"""``plan --excitation`` → MuJoCo recording → ``calibrate --dynamic`` → ``compensate``, and the
file's inertia.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftkin import CalibrationResult, DynamicCalibrationResult, load_calibration, save_calibration
from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv

mujoco_recording = pytest.importorskip("ftkin.sim.mujoco.recording")
pytest.importorskip("mujoco")

TOOL = mujoco_recording.ToolInertia(1.5, [0.006, -0.012, 0.072], np.diag([0.006, 0.005, 0.002]))
BIAS = np.array([2.0, -1.5, 3.0, 0.1, -0.05, 0.02])


@pytest.fixture(scope="module")
def recorded(tmp_path_factory, arm):
    folder = tmp_path_factory.mktemp("dynamic")
    plan_path = folder / "excitation.csv"
    code = main(
        [
            "plan",
            "--excitation",
            "--duration",
            "8",
            "--rate",
            "250",
            "--period",
            "4",
            "--harmonics",
            "3",
            "--iterations",
            "5",
            "--floor-height",
            "0.15",
            "-o",
            str(plan_path),
        ]
    )
    assert code == 0
    table = read_table(plan_path)
    times = table.floats(["t"])[:, 0]
    q = table.floats(arm.joint_names)
    dq = table.floats([f"{name}_vel" for name in arm.joint_names])
    ddq = table.floats([f"{name}_acc" for name in arm.joint_names])
    recorder = mujoco_recording.MujocoRecorder(joint_names=arm.joint_names, tool=TOOL)
    wrenches = recorder.wrenches(q, dq, ddq) + BIAS
    log = folder / "log.csv"
    write_csv(
        log,
        ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"],
        np.column_stack([times, q, wrenches]).tolist(),
    )
    return folder, log


def test_calibrate_dynamic_then_compensate(recorded, capsys):
    folder, log = recorded
    calibration = folder / "calib.json"
    assert main(["calibrate", "--dynamic", str(log), "-o", str(calibration)]) == 0
    assert "inertia_about_com_in_sensor" in capsys.readouterr().out
    result = load_calibration(calibration)
    assert isinstance(result, DynamicCalibrationResult) and result.has_inertia
    largest = 0.006
    assert (
        np.abs(result.inertia_about_com_in_sensor - TOOL.inertia_about_com).max() < 0.02 * largest
    )
    assert abs(result.tool_mass - TOOL.mass) < 1e-3 * TOOL.mass
    assert json.loads(calibration.read_text())["std_errors"]["inertia"] is not None
    out = folder / "contact.csv"
    assert main(["compensate", str(calibration), str(log), "-o", str(out)]) == 0
    assert "inertial term" in capsys.readouterr().out
    contact = read_table(out).floats(["fx", "fy", "fz"])
    static_calibration = folder / "static.json"
    save_calibration(
        CalibrationResult(
            result.force_offset, result.torque_offset, result.gravity_in_base, result.center_of_mass
        ),
        static_calibration,
    )
    static_out = folder / "static_contact.csv"
    assert main(["compensate", str(static_calibration), str(log), "-o", str(static_out)]) == 0
    static_contact = read_table(static_out).floats(["fx", "fy", "fz"])
    inner = slice(30, -30)
    assert np.sqrt(np.mean(contact[inner] ** 2)) < 0.1 * np.sqrt(
        np.mean(static_contact[inner] ** 2)
    )


def test_file_round_trip_and_old_files(recorded, tmp_path):
    folder, log = recorded
    path = tmp_path / "c.json"
    assert main(["calibrate", "--dynamic", str(log), "-o", str(path)]) == 0
    first = load_calibration(path)
    save_calibration(first, tmp_path / "again.json")
    again = load_calibration(tmp_path / "again.json")
    np.testing.assert_allclose(
        again.inertia_about_com_in_sensor, first.inertia_about_com_in_sensor, rtol=1e-12, atol=0
    )
    np.testing.assert_allclose(
        again.inertia_std_errors, first.inertia_std_errors, rtol=1e-12, atol=0
    )
    document = json.loads(path.read_text())
    del document["inertia"], document["std_errors"]["inertia"]
    (tmp_path / "old.json").write_text(json.dumps(document))
    old = load_calibration(tmp_path / "old.json")
    assert type(old) is CalibrationResult
    document["inertia"] = [
        [1.0, 0, 0],
        [0, 1.0, 0],
        [0, 0, 5.0],
    ]  # violates the triangle inequality
    (tmp_path / "bad.json").write_text(json.dumps(document))
    assert (
        main(["compensate", str(tmp_path / "bad.json"), str(log), "-o", str(tmp_path / "x.csv")])
        == 2
    )


def test_a_still_recording_at_one_orientation_is_refused(tmp_path, arm, capsys):
    recorder = mujoco_recording.MujocoRecorder(joint_names=arm.joint_names, tool=TOOL)
    q = np.tile([0.1, -0.2, 0.3, 0.2, -0.5, 0.4], (200, 1))
    log = tmp_path / "still.csv"
    times = np.arange(200) * 1e-3
    write_csv(
        log,
        ["t", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz"],
        np.column_stack([times, q, recorder.wrenches(q) + BIAS]).tolist(),
    )
    assert main(["calibrate", "--dynamic", str(log)]) == 2
    err = capsys.readouterr().err
    # one orientation determines neither the inertia nor the offsets: the refusal says so, and
    # does not advise --no-inertia, which would fail the same way
    assert "too few distinct orientations" in err
    assert "--no-inertia" not in err


def test_a_dynamic_calibration_records_its_arm_and_refuses_another(recorded, tmp_path):
    """Like a static one, the dynamic calibration file says which arm it was made with; another arm
    is refused.
    """
    from ftkin import InvalidInput, load_robot
    from ftkin.control.dynamic_compensation import DynamicCompensator
    from ftkin.kinematics.arm import bundled_urdf_path
    from ftkin.kinematics.record import file_sha256

    _, log = recorded
    calibration = tmp_path / "calib.json"
    assert main(["calibrate", "--dynamic", str(log), "-o", str(calibration)]) == 0
    result = load_calibration(calibration)
    assert result.kinematics is not None and result.kinematics.urdf_sha256 == file_sha256(
        bundled_urdf_path()
    )
    with pytest.raises(InvalidInput, match="not the one the calibration was made with"):
        DynamicCompensator(result, load_robot("ur5"))
    DynamicCompensator(result, load_robot("ur5"), allow_other_arm=True)
