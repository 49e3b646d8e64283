"""Samples read with another arm than the calibration's are warned of by the library
(ftkin.calibration.samples_arm), so compensate_samples, the report and the view's frames say it
as ``ftkin compensate`` does."""

from __future__ import annotations

import json
import logging
from dataclasses import replace
from types import SimpleNamespace

import numpy as np

from ftkin import (
    Arm,
    Compensator,
    SensorNoise,
    SimulatedSensor,
    calibrate,
    load_calibration,
    load_samples,
    save_calibration,
)
from ftkin.calibration.samples_arm import samples_arm_mismatch
from ftkin.cli import main
from ftkin.io.csv_table import write_csv
from ftkin.sim.sensor import paper_like_truth
from ftkin.viz.report import report_data
from ftkin.viz.view_frames import pose_frames

LOGGER = "ftkin.calibration.samples_arm"


def test_the_urdf_file_name_and_the_sensor_frame_decide():
    rng = np.random.default_rng(3)
    made = calibrate(
        SimulatedSensor(paper_like_truth(), SensorNoise.paper()).samples(
            Arm.default().rotation_sensor_to_base(
                Arm.default().random_configurations(8, rng, margin=0.3)
            ),
            rng,
            3,
        )
    )
    calibration = replace(made, urdf="/a/arm.urdf", sensor_frame="ft_sensor")

    def read_with(urdf, frame="ft_sensor"):
        return SimpleNamespace(urdf=urdf, sensor_frame=frame)

    assert samples_arm_mismatch(read_with("/elsewhere/arm.urdf"), calibration) is None  # a copy
    assert samples_arm_mismatch(read_with(None), calibration) is None  # orientations: not known
    assert samples_arm_mismatch(read_with("/a/arm.urdf"), made) is None  # records no arm
    assert samples_arm_mismatch(read_with("/a/arm.urdf"), paper_like_truth()) is None  # a model
    assert samples_arm_mismatch(read_with("/a/other.urdf"), calibration) == (
        "the calibration was made with /a/arm.urdf (sensor frame ft_sensor) but these samples "
        "were read with /a/other.urdf (sensor frame ft_sensor)"
    )
    assert "(sensor frame tool)" in samples_arm_mismatch(
        read_with("/a/arm.urdf", "tool"), calibration
    )


def test_the_api_doors_and_the_cli_say_the_same(tmp_path, caplog):
    arm, rng = Arm.default(), np.random.default_rng(5)
    configurations = arm.random_configurations(8, rng, margin=0.3)
    samples = SimulatedSensor(paper_like_truth(), SensorNoise.paper()).samples_at_configurations(
        arm, configurations, rng, 3
    )
    log = tmp_path / "log.csv"
    header = ["pose", *[f"q{i + 1}" for i in range(6)], "fx", "fy", "fz", "mx", "my", "mz"]
    write_csv(
        log,
        header,
        [
            [int(p), *q, *w]
            for p, q, w in zip(samples.pose_ids, samples.joint_positions, samples.wrenches)
        ],
    )
    path = tmp_path / "c.json"
    save_calibration(calibrate(samples), path)
    document = json.loads(path.read_text())
    document["urdf"] = "/elsewhere/another_arm.urdf"  # as if made on another arm's file
    path.write_text(json.dumps(document))
    calibration = load_calibration(path)

    def said(call) -> list[str]:
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger="ftkin"):
            call()
        return [r.getMessage() for r in caplog.records if r.name == LOGGER]

    expected = [
        "the calibration was made with /elsewhere/another_arm.urdf (sensor frame ft_sensor) but "
        f"these samples were read with {samples.urdf} (sensor frame ft_sensor)"
    ]
    read = load_samples(log, arm).samples
    assert said(lambda: Compensator(calibration, arm).compensate_samples(read)) == expected
    assert said(lambda: report_data(calibration, read)) == expected
    assert said(lambda: pose_frames(read, calibration)) == expected
    assert (
        said(lambda: main(["compensate", str(path), str(log), "-o", str(tmp_path / "p.csv")]))
        == expected
    )
