"""The calibration records its arm; Compensator refuses another arm unless told it is deliberate."""

from __future__ import annotations

import dataclasses
import json

import numpy as np
import pytest

import ftkin
from ftkin import Compensator, calibrate, load_calibration, save_calibration
from ftkin.calibration.information import SensorNoise
from ftkin.kinematics.record import KinematicsRecord
from ftkin.kinematics.robots import load_robot
from ftkin.sim.sensor import SimulatedSensor


@pytest.fixture(scope="module")
def ur5():
    return load_robot("ur5", [0.0, 0.01, 0.05, 0.0, 0.0, 0.3])


@pytest.fixture(scope="module")
def calibration(ur5, truth):
    rng = np.random.default_rng(31)
    q = ur5.random_configurations(8, rng, margin=0.3)
    samples = SimulatedSensor(truth, SensorNoise.paper()).samples_at_configurations(ur5, q, rng, 2)
    return dataclasses.replace(
        calibrate(samples, method="linear"), kinematics=KinematicsRecord.from_arm(ur5)
    )


def test_record_says_how_the_sensor_frame_was_obtained(ur5, calibration, tmp_path):
    record = calibration.kinematics
    assert record.robot == "ur5" and record.sensor_parent == "tool0"
    np.testing.assert_allclose(record.sensor_offset, [0.0, 0.01, 0.05, 0.0, 0.0, 0.3])
    assert record.describe() == "--robot ur5 --sensor-offset 0 0.01 0.05 0 0 0.3"
    path = save_calibration(calibration, tmp_path / "c.json")
    assert load_calibration(path).kinematics == record
    rebuilt = record.build_arm()
    q = ur5.random_configurations(3, np.random.default_rng(0))
    np.testing.assert_allclose(
        rebuilt.rotation_sensor_to_base(q), ur5.rotation_sensor_to_base(q), atol=1e-12
    )


def test_compensator_checks_the_arm_against_the_record(ur5, calibration, arm, tmp_path):
    Compensator(calibration, ur5)  # the same arm: fine
    Compensator(
        calibration, load_robot("ur5", [0.0, 0.01, 0.05, 0.0, 0.0, 0.3])
    )  # rebuilt identically: fine
    cases = {
        "other robot": (arm, r"joint 2 \(joint2\): its axis is turned 180°"),
        "other mount": (
            load_robot("ur5", [0.0, 0.01, 0.06, 0.0, 0.0, 0.3]),
            "sensor frame 'ft_sensor' is moved 10 mm",  # 0.06 − 0.05 m
        ),
        "other angle": (
            load_robot("ur5", [0.0, 0.01, 0.05, 0.0, 0.0, 0.0]),
            "sensor frame 'ft_sensor' is turned 17.2°",  # 0.3 rad
        ),
    }
    for other, pattern in cases.values():
        with pytest.raises(ftkin.InvalidInput, match=pattern):
            Compensator(calibration, other)
        Compensator(calibration, other, allow_other_arm=True)  # deliberate
    # another file with the same kinematics (a copy with a comment): the same arm
    urdf = tmp_path / "copy.urdf"
    urdf.write_text(ur5.urdf_path.read_text() + "\n<!-- edited -->\n")
    Compensator(calibration, ftkin.Arm.from_urdf(urdf, "ft_sensor", sensor_mount=ur5.sensor_mount))
    # a model without a record (SensorModel, older files) is not checked
    Compensator(calibration.model, arm)


def test_malformed_record_is_refused(calibration, tmp_path):
    path = save_calibration(calibration, tmp_path / "c.json")
    document = json.loads(path.read_text())
    document["kinematics"]["sensor_offset"] = [0, 0, True, 0, 0, 0]
    path.write_text(json.dumps(document))
    with pytest.raises(ftkin.CalibrationFileError, match="kinematics"):
        load_calibration(path)


def test_cli_compensate_needs_no_options_repeated(ur5, truth, tmp_path, capsys):
    from ftkin.cli import main
    from ftkin.io.csv_table import read_table, write_csv

    rng = np.random.default_rng(5)
    wrench = ["fx", "fy", "fz", "mx", "my", "mz"]
    q = ur5.random_configurations(8, rng, margin=0.3)
    rows = np.hstack([q, truth.predict(ur5.rotation_sensor_to_base(q))])
    samples = write_csv(tmp_path / "s.csv", [f"q{i + 1}" for i in range(6)] + wrench, rows.tolist())
    calib = tmp_path / "c.json"
    assert (
        main(
            [
                "calibrate",
                str(samples),
                "--robot",
                "ur5",
                "--sensor-offset",
                "0",
                "0.01",
                "0.05",
                "0",
                "0",
                "0.3",
                "--method",
                "linear",
                "-o",
                str(calib),
            ]
        )
        == 0
    )
    out = tmp_path / "o.csv"
    assert main(["compensate", str(calib), str(samples), "-o", str(out)]) == 0  # no robot options
    np.testing.assert_allclose(read_table(out).floats(wrench), 0.0, atol=1e-9)
    assert main(["compensate", str(calib), str(samples), "-o", str(out), "--robot", "ur5"]) == 2
    assert (
        "not the one the calibration was made with (--robot ur5 --sensor-offset"
        in capsys.readouterr().err
    )
