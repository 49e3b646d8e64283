"""CLI: calibrate --drift, compensate with a 't' column, rezero in place or to -o."""

from __future__ import annotations

import json

import numpy as np
import pytest

from ftkin import Arm, SensorNoise, SimulatedSensor, load_calibration
from ftkin.cli import main
from ftkin.io.csv_table import write_csv
from ftkin.sim import SensorDrift
from ftkin.sim.sensor import paper_like_truth, recording_times


@pytest.fixture(scope="module")
def samples_csv(tmp_path_factory):
    arm = Arm.default()
    rng = np.random.default_rng(21)
    configurations = arm.random_configurations(24, rng, margin=0.3)
    times = recording_times(24, 4, 1200.0, 0.01)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise.paper(), SensorDrift.typical())
    samples = sensor.samples_at_configurations(arm, configurations, rng, 4, times=times)
    header = ["t", "pose", *[f"q{i + 1}" for i in range(6)], "fx", "fy", "fz", "mx", "my", "mz"]
    rows = [
        [t, int(p), *q, *w]
        for t, p, q, w in zip(
            samples.times, samples.pose_ids, samples.joint_positions, samples.wrenches
        )
    ]
    path = tmp_path_factory.mktemp("drift") / "samples.csv"
    write_csv(path, header, rows)
    return path


def test_calibrate_with_drift_then_compensate_at_the_reading_times(samples_csv, tmp_path, capsys):
    assert (
        main(["calibrate", str(samples_csv), "--drift", "poly:3", "-o", str(tmp_path / "c.json")])
        == 0
    )
    out = capsys.readouterr().out
    assert "bias drift: poly:3 (given)" in out and "end of the recording" in out
    assert json.loads((tmp_path / "c.json").read_text())["drift"]["model"] == "poly:3"
    assert (
        main(
            [
                "compensate",
                str(tmp_path / "c.json"),
                str(samples_csv),
                "-o",
                str(tmp_path / "out.csv"),
            ]
        )
        == 0
    )
    assert "used the bias at their time" in capsys.readouterr().out
    assert main(["calibrate", str(samples_csv), "--drift", "poly:7"]) == 2
    assert "degree must be 1..5" in capsys.readouterr().err


def test_rezero_updates_the_file_in_place_or_writes_elsewhere(samples_csv, tmp_path, capsys):
    calibration_path = tmp_path / "c.json"
    assert (
        main(["calibrate", str(samples_csv), "--drift", "none", "-o", str(calibration_path)]) == 0
    )
    before = calibration_path.read_text()
    original = load_calibration(calibration_path)
    q = [0.2, -1.1, 1.3, 0.4, 1.2, -0.3]
    arm = Arm.default()
    rotation = arm.rotation_sensor_to_base(np.array([q]))[0]
    wrench = original.tool_gravity_wrench(rotation) + [0.1, -0.2, 0.3, 0.01, 0.0, -0.01]
    args = ["rezero", str(calibration_path), "--q", *map(str, q), "--wrench", *map(str, wrench)]
    assert main([*args, "-o", str(tmp_path / "other.json")]) == 0
    assert calibration_path.read_text() == before  # -o leaves the input alone
    other = load_calibration(tmp_path / "other.json")
    np.testing.assert_allclose(other.bias, [0.1, -0.2, 0.3, 0.01, 0.0, -0.01], atol=1e-12)
    np.testing.assert_array_equal(other.gravity_in_base, original.gravity_in_base)
    assert main(args) == 0
    assert "updated in place" in capsys.readouterr().out
    document = json.loads(calibration_path.read_text())
    assert document["rezero"]["previous_bias"] == original.bias.tolist()
    np.testing.assert_allclose(load_calibration(calibration_path).bias, other.bias)
    assert main(["rezero", str(calibration_path), "--q", "0", "1", "--wrench", *["0"] * 6]) == 2
    assert "takes the arm's 6 joint angles q [rad]" in capsys.readouterr().err
    # a pose the arm cannot be in: degrees, or past a joint limit (joint2's upper limit is 1.134
    # rad)
    unchanged = calibration_path.read_text()
    assert (
        main(
            [
                "rezero",
                str(calibration_path),
                "--q",
                "0",
                "0",
                "0",
                "0",
                "0",
                "90",
                "--wrench",
                *["0"] * 6,
            ]
        )
        == 2
    )
    assert "joint6 = 90 is outside its limits" in capsys.readouterr().err
    assert (
        main(
            [
                "rezero",
                str(calibration_path),
                "--q",
                "0",
                "1.5",
                "0",
                "0",
                "0",
                "0",
                "--wrench",
                *["0"] * 6,
            ]
        )
        == 2
    )
    assert "joint2 = 1.5 is outside its limits" in capsys.readouterr().err
    assert calibration_path.read_text() == unchanged
    # a JSON file where a CSV is expected
    assert (
        main(
            [
                "compensate",
                str(calibration_path),
                str(calibration_path),
                "-o",
                str(tmp_path / "x.csv"),
            ]
        )
        == 2
    )
    assert "is a JSON file" in capsys.readouterr().err


def test_view_subtracts_the_bias_at_each_pose_time(samples_csv, tmp_path, capsys):
    calibration = tmp_path / "c.json"
    for drift, largest in (("poly:3", 0.05), ("none", 0.1)):
        assert main(["calibrate", str(samples_csv), "--drift", drift, "-o", str(calibration)]) == 0
        capsys.readouterr()
        assert (
            main(["view", str(calibration), str(samples_csv), "--html", str(tmp_path / "v.html")])
            == 0
        )
        rows = [
            line.split()
            for line in capsys.readouterr().out.splitlines()
            if line.strip().startswith("pose ")
        ]
        contact = np.array([float(row[5]) for row in rows])  # |F'| [N] at the 24 calibration poses
        assert len(contact) == 24
        if drift == "none":
            assert (
                contact.max() > largest
            )  # a constant bias leaves the warm-up in the contact force
        else:
            assert contact.max() < largest  # the bias at each pose's time: only the noise is left


def test_a_rezero_of_a_drifting_calibration_and_a_log_on_another_clock_are_said(
    samples_csv, tmp_path, capsys, caplog
):
    """A re-zero with a contact (the bias moves by 40 N, more than the 3.15 N tool) is warned;
    a log inside the recording after that re-zero keeps the recording's bias, which is said;
    a log far before the recording (another clock) is said too."""
    import logging

    calibration = tmp_path / "c.json"
    assert main(["calibrate", str(samples_csv), "--drift", "poly:1", "-o", str(calibration)]) == 0
    original = load_calibration(calibration)
    q = [0.2, -1.1, 1.3, 0.4, 1.2, -0.3]
    rotation = Arm.default().rotation_sensor_to_base(np.array([q]))[0]
    pushed = original.tool_gravity_wrench(rotation) + original.bias + [40.0, 0, 0, 0, 0, 0]
    zeroed = tmp_path / "zeroed.json"
    argv = ["rezero", str(calibration), "--q", *map(str, q), "--wrench", *map(str, pushed)]
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        assert main([*argv, "-o", str(zeroed)]) == 0
    assert "more than the tool's weight" in caplog.text
    assert "keep the bias the recording saw" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        assert (
            main(["compensate", str(zeroed), str(samples_csv), "-o", str(tmp_path / "a.csv")]) == 0
        )
    assert "not the bias re-zeroed since (it moved by up to 40" in caplog.text
    # the same log 1e6 s earlier: another clock
    rows = [line.split(",") for line in samples_csv.read_text().splitlines()]
    shifted = [rows[0]] + [[str(float(row[0]) - 1e6), *row[1:]] for row in rows[1:]]
    early = tmp_path / "early.csv"
    early.write_text("\n".join(",".join(row) for row in shifted) + "\n")
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        assert (
            main(["compensate", str(calibration), str(early), "-o", str(tmp_path / "b.csv")]) == 0
        )
    assert "are long before the calibration's recording" in caplog.text


def test_the_api_and_the_cli_say_the_same_of_a_rezero_and_of_a_log_on_another_clock(
    samples_csv, tmp_path, caplog
):
    """The checks live in the library: ``ftkin rezero``/``ftkin compensate`` and
    Compensator.rezero/compensate_batch given the same numbers log the same texts."""
    import functools
    import logging

    from ftkin import Compensator

    calibration_path = tmp_path / "c.json"
    assert (
        main(["calibrate", str(samples_csv), "--drift", "poly:1", "-o", str(calibration_path)]) == 0
    )
    calibration = load_calibration(calibration_path)
    q = [0.2, -1.1, 1.3, 0.4, 1.2, -0.3]
    rotation = Arm.default().rotation_sensor_to_base(np.array([q]))[0]
    pushed = calibration.tool_gravity_wrench(rotation) + calibration.bias + [0, 25.0, 0, 0, 0, 0]

    def said(call) -> list[str]:
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="ftkin"):
            call()
        return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING]

    zeroed = tmp_path / "zeroed.json"
    argv = [
        "rezero",
        str(calibration_path),
        "--q",
        *map(repr, q),
        "--wrench",
        *map(repr, pushed.tolist()),
    ]
    by_cli = said(lambda: main([*argv, "-o", str(zeroed)]))
    by_api = said(lambda: Compensator(calibration).rezero(np.array(q), pushed))
    assert len(by_api) == 2 and "the bias moved by 25 N" in by_api[0]
    assert by_cli == by_api
    # the re-zeroed file, and the samples 1e6 s earlier: rows inside, then another clock
    table = np.loadtxt(samples_csv, delimiter=",", skiprows=1)
    times, joints, wrenches = table[:, 0], table[:, 2:8], table[:, 8:14]
    for shift in (0.0, -1e6):
        log = tmp_path / f"log{shift:g}.csv"
        rows = np.column_stack([times + shift, table[:, 1:]])
        write_csv(log, samples_csv.read_text().splitlines()[0].split(","), rows.tolist())
        command = ["compensate", str(zeroed), str(log), "-o", f"{log}.out.csv"]
        by_cli = said(functools.partial(main, command))
        compensator = Compensator(load_calibration(zeroed), Arm.default())
        by_api = said(
            functools.partial(compensator.compensate_batch, joints, wrenches, times=times + shift)
        )
        assert len(by_api) == 1 and by_cli == by_api
    assert "are long before the calibration's recording" in by_api[0]


def test_rezero_on_another_arm_is_refused_and_the_advice_works(samples_csv, tmp_path, capsys):
    """A re-zero with robot options that differ from the calibration's arm is refused naming
    --allow-other-arm, which rezero takes (it was compensate's alone)."""
    calibration = tmp_path / "c.json"
    assert main(["calibrate", str(samples_csv), "--drift", "none", "-o", str(calibration)]) == 0
    capsys.readouterr()
    argv = ["rezero", str(calibration), "--robot", "ur5", "--sensor-offset", "0", "0", "0.05"]
    argv += ["--q", "0", "-1", "1", "0", "1", "0", "--wrench", *["0"] * 6]
    assert main([*argv, "-o", str(tmp_path / "a.json")]) == 2
    assert "--allow-other-arm" in capsys.readouterr().err
    assert not (tmp_path / "a.json").exists()
    assert main([*argv, "-o", str(tmp_path / "b.json"), "--allow-other-arm"]) == 0
    assert (tmp_path / "b.json").exists()
