"""K-fold cross-validation against folds fitted by hand, and on a drifting sensor (auto beats
none).
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin import SensorNoise, SimulatedSensor, calibrate
from ftkin.calibration import cross_validate
from ftkin.cli import main
from ftkin.exceptions import InvalidInput
from ftkin.io.csv_table import write_csv
from ftkin.sim import SensorDrift
from ftkin.sim.sensor import paper_like_truth, recording_times


@pytest.fixture(scope="module")
def drifting(arm):
    rng = np.random.default_rng(4)
    q = arm.random_configurations(24, rng, margin=0.3)
    sensor = SimulatedSensor(paper_like_truth(), SensorNoise(0.02, 0.001), SensorDrift.typical())
    return sensor.samples_at_configurations(
        arm, q, rng, 4, times=recording_times(24, 4, 720.0, 0.01)
    )


def test_each_fold_is_compensated_by_a_fit_without_it(drifting):
    result = cross_validate(drifting, drifts=("none",), folds=3, seed=7)
    poses = np.unique(drifting.pose_ids)
    fold = dict(
        zip(poses.tolist(), (np.random.default_rng(7).permutation(len(poses)) % 3).tolist())
    )
    squares = []
    for k in range(
        3
    ):  # by hand: fit on the readings of the other folds, compensate this fold's pose means
        train = np.array([fold[int(i)] != k for i in drifting.pose_ids])
        fit = calibrate(
            type(drifting)(
                drifting.wrenches[train], drifting.rotations[train], drifting.pose_ids[train]
            ),
            drift="none",
        )
        for pose in poses[[fold[int(p)] == k for p in poses]]:
            rows = drifting.pose_ids == pose
            rotation = drifting.rotations[rows][0]
            residual = (
                drifting.wrenches[rows].mean(axis=0) - fit.tool_gravity_wrench(rotation) - fit.bias
            )
            squares.append([residual[:3] @ residual[:3], residual[3:] @ residual[3:]])
    expected = np.sqrt(np.mean(squares, axis=0))
    assert result.force_rms["none"] == pytest.approx(expected[0], rel=1e-9)
    assert result.torque_rms["none"] == pytest.approx(expected[1], rel=1e-9)
    assert result.pose_count == 24 and result.models["none"] == ("none",) * 3


def test_auto_drift_pays_on_a_drifting_sensor(drifting, caplog):
    with caplog.at_level(logging.ERROR, logger="ftkin"):
        result = cross_validate(drifting, folds=4)
    assert result.force_rms["none"] > 2.0 * result.force_rms["auto"]
    assert "÷ none" in result.report() and len(result.models["auto"]) == 4


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"folds": 1}, "folds must be an integer"),
        ({"folds": 30}, "cannot be split"),
        ({"drifts": ()}, "distinct drift settings"),
        ({"drifts": ("none", "none")}, "distinct"),
        ({"drift": "none"}, "drifts="),
    ],
)
def test_bad_arguments(drifting, kwargs, match):
    with pytest.raises(InvalidInput, match=match):
        cross_validate(drifting, **kwargs)


def test_cli_prints_the_table_and_refuses_it_with_dynamic(drifting, tmp_path, capsys):
    path = tmp_path / "s.csv"
    rows = [
        [float(t), int(p), *map(float, q), *map(float, w)]
        for t, p, q, w in zip(
            drifting.times, drifting.pose_ids, drifting.joint_positions, drifting.wrenches
        )
    ]
    write_csv(
        path,
        ["t", "pose", *[f"q{i + 1}" for i in range(6)], "fx", "fy", "fz", "mx", "my", "mz"],
        rows,
    )
    assert main(["calibrate", str(path), "--cross-validate", "3", "--drift", "poly:2"]) == 0
    out = capsys.readouterr().out
    assert "3-fold cross-validation over 24 poses" in out and "poly:2 ×3" in out
    assert main(["calibrate", str(path), "--dynamic", "--cross-validate", "3"]) == 2
    assert "--cross-validate apply to static calibration" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("positional", "keywords", "match"),
    [
        ((None,), {"drift": "none"}, "drifts="),
        ((None, None), {"drift": "none"}, "drifts="),
        ((None, [["none"]]), {"drift": "none"}, "drifts="),
        ((None, ("none", "none")), {}, "distinct"),
        ((None, ("none",), 1), {}, "folds must be an integer"),
    ],
)
def test_bad_arguments_are_refused_before_the_samples_are_read(positional, keywords, match):
    """Regression: the refusals ran as one table evaluated up front, so the samples' pose ids and
    the drift settings were read first: a wrong call crashed (AttributeError, TypeError) instead
    of naming the argument that e83cc10 refused first.
    """
    with pytest.raises(InvalidInput, match=match):
        cross_validate(*positional, **keywords)
