"""`ftkin compensate` reads joint angles with the URDF the calibration recorded, unless told
otherwise.
"""

from __future__ import annotations

import numpy as np

from ftkin import Arm, SensorNoise, SimulatedSensor
from ftkin.calibration.model import WRENCH_CHANNELS
from ftkin.cli import main
from ftkin.io.csv_table import read_table, write_csv
from ftkin.kinematics import bundled_urdf_path
from ftkin.sim.sensor import paper_like_truth


def _rotated_sensor_urdf(tmp_path):
    """The bundled arm with the sensor turned a further 90° about its z axis: other kinematics."""
    text = (
        bundled_urdf_path()
        .read_text()
        .replace('xyz="0 0 0.02" rpy="0 0 1.570796327"', 'xyz="0 0 0.02" rpy="0 0 3.141592654"')
    )
    path = tmp_path / "turned.urdf"
    path.write_text(text)
    return path


def _write_samples(path, arm, q, wrenches, pose_ids=None):
    header = (
        list(arm.joint_names) + list(WRENCH_CHANNELS) + (["pose"] if pose_ids is not None else [])
    )
    rows = []
    for i, (joints, wrench) in enumerate(zip(q, wrenches)):
        rows.append(
            [float(v) for v in joints]
            + [float(v) for v in wrench]
            + ([int(pose_ids[i])] if pose_ids is not None else [])
        )
    write_csv(path, header, rows)


def test_compensate_uses_the_recorded_urdf(tmp_path, rng, caplog):
    urdf = _rotated_sensor_urdf(tmp_path)
    arm = Arm.from_urdf(urdf)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise(1e-6, 1e-7))
    q_poses = arm.random_configurations(10, rng, margin=0.3)
    samples = sensor.samples_at_configurations(arm, q_poses, rng)
    _write_samples(tmp_path / "samples.csv", arm, samples.joint_positions, samples.wrenches)
    assert (
        main(
            [
                "calibrate",
                str(tmp_path / "samples.csv"),
                "--urdf",
                str(urdf),
                "-o",
                str(tmp_path / "calib.json"),
            ]
        )
        == 0
    )

    contact = np.array([1.0, -2.0, 3.0, 0.1, -0.05, 0.02])
    q_log = arm.random_configurations(5, rng, margin=0.3)
    raws = sensor.read(arm.rotation_sensor_to_base(q_log), rng, contact)
    _write_samples(tmp_path / "log.csv", arm, q_log, raws)
    # no --urdf: the recorded URDF must be used, not the bundled arm
    assert (
        main(
            [
                "compensate",
                str(tmp_path / "calib.json"),
                str(tmp_path / "log.csv"),
                "-o",
                str(tmp_path / "out.csv"),
            ]
        )
        == 0
    )
    out = read_table(tmp_path / "out.csv").floats(WRENCH_CHANNELS)
    np.testing.assert_allclose(out, np.tile(contact, (5, 1)), atol=1e-4)

    # with the bundled arm named explicitly the kinematics differ: refused (the record says which
    # arm) ...
    assert (
        main(
            [
                "compensate",
                str(tmp_path / "calib.json"),
                str(tmp_path / "log.csv"),
                "-o",
                str(tmp_path / "wrong.csv"),
                "--robot",
                "ftkin_c4",
            ]
        )
        == 2
    )
    assert not (tmp_path / "wrong.csv").exists()
    # ... unless deliberate: then the result is wrong, and a warning says why
    assert (
        main(
            [
                "compensate",
                str(tmp_path / "calib.json"),
                str(tmp_path / "log.csv"),
                "-o",
                str(tmp_path / "wrong.csv"),
                "--robot",
                "ftkin_c4",
                "--allow-other-arm",
            ]
        )
        == 0
    )
    wrong = read_table(tmp_path / "wrong.csv").floats(WRENCH_CHANNELS)
    assert np.abs(wrong - contact).max() > 0.1
    assert "the calibration was made with" in caplog.text and "turned.urdf" in caplog.text


def test_frame_options_are_checked_for_every_way_of_naming_the_arm(tmp_path, capsys):
    samples = tmp_path / "s.csv"
    samples.write_text("alpha,beta,gamma,fx,fy,fz,mx,my,mz\n0,0,0,0,0,3,0,0,0\n")
    # bundled arm: a frame it lacks is an error listing its frames, not silently ignored
    assert main(["calibrate", str(samples), "--tool-frame", "nope"]) == 2
    assert "frame 'nope' not found" in capsys.readouterr().err
    assert main(["calibrate", str(samples), "--sensor-frame", "ft_sensr"]) == 2
    assert "available frames: universe, base_link" in capsys.readouterr().err
    # --robot names its sensor frame itself
    assert main(["calibrate", str(samples), "--robot", "ftkin_c4", "--sensor-frame", "flange"]) == 2
    assert "--sensor-frame is for --urdf" in capsys.readouterr().err


def test_bundled_arm_with_other_frames(tmp_path):
    import argparse

    from ftkin.cli.common import add_arm_arguments, arm_from_args

    parser = argparse.ArgumentParser()
    add_arm_arguments(parser)
    assert arm_from_args(parser.parse_args([])) is None  # bundled arm, loaded on demand
    arm = arm_from_args(parser.parse_args(["--sensor-frame", "flange", "--tool-frame", "gripper"]))
    assert (arm.sensor_frame, arm.tool_frame) == ("flange", "gripper")
    assert arm.urdf_path == bundled_urdf_path().resolve()
