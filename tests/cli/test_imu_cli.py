"""``ftkin calibrate|compensate FILE [FILE ...]`` with the sensor's IMU: a wrench log and an IMU
log on their own clocks (700 Hz and 250 Hz, microseconds since the epoch, the accelerometer in
g), in any order, joined on time; the calibration from the IMU alone; the compensation with the
IMU columns. Readings are built from first principles (not ftkin's model)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv
from tests.calibration.test_imu_fit import BIAS, IMU_ROTATION, SCALE, WRENCH_BIAS

G = 9.80665
MASS, COM = 1.7, np.array([0.01, -0.02, 0.08])
EPOCH_US = 1.7644104e15
HOLD, MOVE = 3.0, 1.0  # [s] still at a pose, then turning to the next


def _orientation(t, poses):
    """``R_WS`` at time ``t`` [s]: still at each pose for HOLD s, then a slerp to the next."""
    period = HOLD + MOVE
    k = min(int(t // period), len(poses) - 1)
    phase = np.clip((t - k * period - HOLD) / MOVE, 0.0, 1.0) if k < len(poses) - 1 else 0.0
    a, b = poses[k], poses[min(k + 1, len(poses) - 1)]
    return (a * Rotation.from_rotvec(phase * (a.inv() * b).as_rotvec())).as_matrix()


def _write_streams(tmp_path, rng, count=9):
    poses = Rotation.random(count, random_state=11)
    span = count * (HOLD + MOVE) - MOVE
    t_wrench = np.arange(0.0, span, 1 / 700.0)
    t_imu = np.arange(0.0, span, 1 / 250.0) + 0.0013  # another clock, offset
    wrench = []
    for t in t_wrench:
        up = _orientation(t, poses).T @ [0.0, 0.0, G]
        weight = -MASS * up
        wrench.append(np.concatenate([weight, np.cross(COM, weight)]) + WRENCH_BIAS)
    wrench = np.array(wrench) + rng.normal(0.0, 1.0, (len(t_wrench), 6)) * ([0.05] * 3 + [3e-3] * 3)
    accel = []
    for t in t_imu:
        up = _orientation(t, poses).T @ [0.0, 0.0, G]
        accel.append((1.0 + SCALE) * (IMU_ROTATION.T @ up) + BIAS)
    accel = (np.array(accel) + rng.normal(0.0, 0.02, (len(t_imu), 3))) / G  # logged in g
    wrench_csv = tmp_path / "wrench.csv"
    write_csv(
        wrench_csv,
        ["t_us", "Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
        np.column_stack([EPOCH_US + 1e6 * t_wrench, wrench]).tolist(),
    )
    imu_csv = tmp_path / "imu.csv"
    write_csv(
        imu_csv,
        ["t", "ax", "ay", "az", "temperature"],
        np.column_stack([EPOCH_US + 1e6 * t_imu, accel, np.full(len(t_imu), 31.0)]).tolist(),
    )
    return wrench_csv, imu_csv


@pytest.fixture(scope="module")
def streams(tmp_path_factory):
    return _write_streams(tmp_path_factory.mktemp("imu"), np.random.default_rng(5))


def test_calibrate_and_compensate_from_the_imu(streams, tmp_path, capsys):
    renamed, imu_csv = streams  # t_us (a unit in its name) and t, both µs since the epoch
    calib = tmp_path / "calib.json"
    argv = ["calibrate", str(imu_csv), str(renamed), "--time-unit", "us", "--accel-unit", "g"]
    assert main([*argv, "-o", str(calib)]) == 0
    out = capsys.readouterr().out
    assert "readings from the sensor's IMU" in out
    assert main([*argv[:-2], "--time-unit", "ms", "-o", str(tmp_path / "x.json")]) == 2
    assert "contradicts the time column 't_us'" in capsys.readouterr().err
    saved = json.loads(calib.read_text())
    assert saved["tool_mass"] == pytest.approx(MASS, rel=0.005)
    np.testing.assert_allclose(saved["center_of_mass"], COM, atol=1e-3)
    np.testing.assert_allclose(saved["force_offset"], WRENCH_BIAS[:3], atol=0.05)
    # compensate: the same files, any order; the contact is the noise (no contact anywhere)
    contact_csv = tmp_path / "contact.csv"
    argv = ["compensate", str(calib), str(renamed), str(imu_csv), "--time-unit", "us"]
    assert main([*argv, "--accel-unit", "g", "-o", str(contact_csv)]) == 0
    contact = read_table(contact_csv)
    forces = contact.floats(["fx", "fy", "fz"])
    assert np.median(np.linalg.norm(forces, axis=1)) < 0.15  # noise 0.05 N per channel
    assert "temperature" in contact.header  # the IMU file's other columns carried along


def test_joints_and_an_imu_in_one_file_are_fused_and_the_mount_warned(tmp_path, capsys, caplog):
    """A samples CSV with joint angles and ax,ay,az: calibrate fits both and warns, naming the
    angle, when the URDF's sensor frame is off (MuJoCo's accelerometer; a URDF turned 3.09°)."""
    import logging

    from tests.calibration.test_imu_fused import MOUNT_ERROR_RPY_DEG, turned_arm

    pytest.importorskip("mujoco")
    from tests.calibration.test_imu_fused import mujoco_poses as fixture

    data = fixture.__wrapped__()
    arm, _ = turned_arm(tmp_path, MOUNT_ERROR_RPY_DEG)
    path = tmp_path / "fused.csv"
    header = ["pose", *arm.joint_names, "fx", "fy", "fz", "mx", "my", "mz", "ax", "ay", "az"]
    write_csv(
        path,
        header,
        np.column_stack([data["ids"], data["q"], data["wrench"], data["accel"]]).tolist(),
    )
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        code = main(
            ["calibrate", str(path), "--urdf", str(arm.urdf_path), "-o", str(tmp_path / "c.json")]
        )
    assert code == 0
    assert "fitted together" in capsys.readouterr().out
    angle = float(re_search(r"([\d.]+)° ", caplog.text))
    assert abs(angle - 3.093) < 0.05 and "not mounted as the URDF says" in caplog.text
    # with the right URDF (the bundled arm, MuJoCo's), the fused calibration compensates a log
    # of joints and wrench only, with FK: MuJoCo's own readings at rest, the contact the noise
    assert main(["calibrate", str(path), "-o", str(tmp_path / "right.json")]) == 0
    log = tmp_path / "joints_only.csv"
    write_csv(log, header[1:-3], np.column_stack([data["q"], data["wrench"]]).tolist())
    out = tmp_path / "contact.csv"
    assert main(["compensate", str(tmp_path / "right.json"), str(log), "-o", str(out)]) == 0
    assert "from the IMU" not in capsys.readouterr().out
    forces = read_table(out).floats(["fx", "fy", "fz"])
    assert np.median(np.linalg.norm(forces, axis=1)) < 0.1


def re_search(pattern, text):
    import re

    match = re.search(pattern, text)
    assert match, text
    return match.group(1)


def test_three_files_with_an_orientation_convert_the_accelerometer_once(streams, tmp_path, capsys):
    """Wrench, IMU (in g) and orientation logs at their own rates: the join converts g to m/s²,
    and the fused fit reads the joined table in m/s² (it had converted it a second time: "median
    norm 95.6 m/s²")."""
    wrench_csv, imu_csv = streams
    poses = Rotation.random(9, random_state=11)  # the fixture's poses (R_WS = R_BS)
    t = np.arange(0.0, 9 * (HOLD + MOVE) - MOVE, 1 / 100.0) + 0.0007
    quaternions = Rotation.from_matrix([_orientation(x, poses) for x in t]).as_quat()
    orientation_csv = tmp_path / "orientation.csv"
    write_csv(
        orientation_csv,
        ["t", "qw", "qx", "qy", "qz"],
        np.column_stack([EPOCH_US + 1e6 * t, quaternions[:, [3, 0, 1, 2]]]).tolist(),
    )
    calib = tmp_path / "calib.json"
    argv = ["calibrate", str(wrench_csv), str(imu_csv), str(orientation_csv)]
    assert main([*argv, "--time-unit", "us", "--accel-unit", "g", "-o", str(calib)]) == 0
    assert "fitted together" in capsys.readouterr().out
    saved = json.loads(calib.read_text())
    assert saved["tool_mass"] == pytest.approx(MASS, rel=0.005)
    np.testing.assert_allclose(saved["center_of_mass"], COM, atol=1e-3)


def test_a_slower_imu_joined_counts_what_it_measured(streams):
    """700 Hz wrench, 250 Hz IMU: the IMU's readings are spread over 2.8 rows each, and linear
    interpolation leaves 2/3 of their variance (the mean of w² + (1 − w)² over w in [0, 1])."""
    from ftkin.io import load_imu_samples

    wrench_csv, imu_csv = streams
    samples, _ = load_imu_samples(wrench_csv, imu_csv, time_unit="us", accel_unit="g")
    assert samples.accel_count_factor == pytest.approx(250.0 / 700.0 * 2.0 / 3.0, rel=1e-3)


@pytest.fixture(scope="module")
def moving_and_static(tmp_path_factory):
    """MuJoCo's tool and IMU (tests.calibration.test_imu_dynamic): a moving recording
    (t, fx..mz, ax..az, wx..wz at 250 Hz) and twelve static poses of the same tool and IMU
    (pose, fx..mz, ax..az; 50 readings each), as CSVs; and MuJoCo's body θ."""
    from tests.calibration import test_imu_dynamic as dynamic

    arm, recorder = dynamic.tool_recorder()
    folder = tmp_path_factory.mktemp("moving")
    times, wrench, accel, gyro = dynamic.motion(arm, recorder, 3)
    moving = folder / "moving.csv"
    header = ["t", "fx", "fy", "fz", "mx", "my", "mz", "ax", "ay", "az", "wx", "wy", "wz"]
    write_csv(moving, header, np.column_stack([times, wrench, accel, gyro]).tolist())
    rng = np.random.default_rng(21)
    q = arm.random_configurations(12, rng, margin=0.05)
    wrench, accel, _ = recorder.readings(q)
    ids = np.repeat(np.arange(12), 50)
    accel = (1.0 + dynamic.SCALE) * accel[ids] + dynamic.BIAS + rng.normal(0.0, 0.02, (600, 3))
    wrench = wrench[ids] + dynamic.WRENCH_BIAS + rng.normal(0.0, 1.0, (600, 6)) * dynamic.NOISE
    static = folder / "static.csv"
    write_csv(static, ["pose", *header[1:10]], np.column_stack([ids, wrench, accel]).tolist())
    return moving, static, recorder.true_parameters()


def test_a_moving_imu_recording_without_a_prior_and_the_advice_followed(
    moving_and_static, tmp_path, capsys
):
    """Issue 37, item 6: ``calibrate --dynamic`` of a moving IMU recording without --prior gives
    the mass and COM (MuJoCo's) and names the bias it cannot split, on screen and in the file;
    the advice it prints (``--dynamic --prior STATIC.json``) works when followed."""
    from ftkin.calibration.log_cholesky import body_from_parameters
    from tests.calibration.test_imu_dynamic import BIAS, WRENCH_BIAS

    moving, static, theta = moving_and_static
    mass, com, _ = body_from_parameters(theta)
    combined = tmp_path / "combined.json"
    assert main(["calibrate", str(moving), "--dynamic", "-o", str(combined)]) == 0
    out = capsys.readouterr().out
    assert "not separated   accel_bias, force_offset, torque_offset" in out
    assert "--dynamic --prior STATIC.json" in out
    saved = json.loads(combined.read_text())
    assert saved["imu"]["inseparable"] == ["accel_bias", "force_offset", "torque_offset"]
    assert saved["tool_mass"] == pytest.approx(mass, rel=0.01)
    np.testing.assert_allclose(saved["center_of_mass"], com, atol=2e-3)
    # the advice: a static calibration of the same IMU, then the motion with it as the prior
    prior = tmp_path / "static.json"
    assert main(["calibrate", str(static), "-o", str(prior)]) == 0
    np.testing.assert_allclose(json.loads(prior.read_text())["imu"]["accel_bias"], BIAS, atol=0.02)
    split = tmp_path / "split.json"
    argv = ["calibrate", str(moving), "--dynamic", "--prior", str(prior), "-o", str(split)]
    assert main(argv) == 0
    assert "not separated" not in capsys.readouterr().out
    saved = json.loads(split.read_text())
    assert saved["imu"]["inseparable"] == []
    np.testing.assert_allclose(saved["force_offset"], WRENCH_BIAS[:3], atol=0.05)
    np.testing.assert_allclose(saved["torque_offset"], WRENCH_BIAS[3:], atol=5e-3)
    # a moving calibration is no prior: said, no traceback
    argv[4] = str(combined)
    assert main([*argv[:-1], str(tmp_path / "again.json")]) == 2
    err = capsys.readouterr().err
    assert "did not separate the accelerometer's bias" in err and "Traceback" not in err
    assert not (tmp_path / "again.json").exists()
