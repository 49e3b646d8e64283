"""What ``ftkin view`` shows, computed by the library (ftkin.viz.view_frames): the frames with
the bias each reading had, and the table of the drawn vectors, against hand computations."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest

from ftkin import Compensator, InvalidInput
from ftkin.calibration.drift import BiasDrift
from ftkin.calibration.model import SensorModel
from ftkin.calibration.result import CalibrationResult
from ftkin.calibration.samples import Samples
from ftkin.viz.view_frames import pose_frames, replay_frames, vector_rows, vector_table
from ftkin.viz.viewer import pose_vectors

END_BIAS = np.array([0.5, -0.4, 0.3, 0.01, -0.02, 0.03])  # [N, N·m]
WEIGHT = np.array([0.0, 0.0, -10.0])  # the tool's weight in base [N]
COM = np.array([0.0, 0.0, 0.05])  # [m]


def _calibration(bias=END_BIAS) -> CalibrationResult:
    """A tool of 10 N with a poly:1 bias trajectory over 95–205 s (−0.1 N·m per 100 s before
    the end), its current bias ``bias`` (END_BIAS unless re-zeroed)."""
    drift = BiasDrift(
        model="poly:1",
        selected_by="given",
        times=np.array([100.0, 200.0]),
        bias=np.array([END_BIAS - 0.1, END_BIAS]),
        bias_std=np.zeros((2, 6)),
        coefficients=np.full((1, 6), 0.1),
        time_scale=100.0,
        recorded_span=np.array([95.0, 205.0]),
    )
    model = SensorModel(bias[:3], bias[3:], WEIGHT, COM)
    return dataclasses.replace(CalibrationResult.from_model(model), drift=drift)


def _readings(bias_rows: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """Raw readings at R_BS = I: bias + [a, P × a] + contact (by hand)."""
    gravity = np.concatenate([WEIGHT, np.cross(COM, WEIGHT)])
    return bias_rows + gravity + contact


def test_the_frames_carry_the_bias_of_compensate_inside_and_after_a_re_zeroed_recording():
    """Inside the recording a reading had the trajectory's bias, after it the re-zeroed one: the
    frame's reading minus the calibration's bias and the tool gravity is the contact (what
    ``ftkin compensate`` writes), not the contact plus the re-zero's change."""
    rezeroed = END_BIAS + [0.4, 0.0, 0.0, 0.0, 0.0, 0.0]
    calibration = _calibration(rezeroed)
    times = np.array([150.0, 300.0])
    had = np.array([END_BIAS - 0.05, rezeroed])  # linear, half way at 150 s; the re-zero after
    contact = np.array([[1.0, 0, 0, 0, 0, 0], [0, 2.0, 0, 0, 0, 0]])
    samples = Samples(
        _readings(had, contact), np.repeat(np.eye(3)[None], 2, axis=0), np.arange(2), times=times
    )
    gravity = np.concatenate([WEIGHT, np.cross(COM, WEIGHT)])
    for frames in (pose_frames(samples, calibration), replay_frames(samples, calibration, 10)):
        np.testing.assert_allclose(frames.raw_wrenches - rezeroed - gravity, contact, atol=1e-12)
    np.testing.assert_allclose(
        Compensator(calibration).compensate_samples(samples), contact, atol=1e-12
    )
    assert pose_frames(samples, calibration).labels == ("pose 0", "pose 1")


def test_replayed_frames_at_their_times_or_thirty_a_second_and_time_must_not_decrease(caplog):
    calibration = _calibration()
    rotations = np.repeat(np.eye(3)[None], 5, axis=0)
    raw = _readings(np.tile(END_BIAS, (5, 1)), np.zeros(6))
    no_clock = replay_frames(Samples(raw, rotations), calibration, 3)
    assert no_clock.labels == ("row 0", "row 2", "row 4")
    np.testing.assert_allclose(no_clock.times, [0.0, 2 / 30, 4 / 30])
    backwards = Samples(raw, rotations, times=np.array([300.0, 301, 302, 301, 304]))
    with pytest.raises(InvalidInput, match="log.csv: the time column must not decrease"):
        replay_frames(backwards, calibration, 10, "log.csv")
    # a log long before the recording (another clock) is said, as by compensate
    early = Samples(raw, rotations, times=np.arange(5.0) - 5000.0)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        replay_frames(early, calibration, 10)
    assert "are long before the calibration's recording" in caplog.text
    with pytest.raises(InvalidInput, match="no row 1; available: row 0, row 2, row 4"):
        no_clock.index(1, replay=True)


def test_the_table_has_the_norms_and_the_angle_of_the_drawn_vectors():
    model = SensorModel(END_BIAS[:3], END_BIAS[3:], WEIGHT, COM)
    contact = np.array([10.0, 0.0, 0.0, 0.0, 0.3, 0.4])
    raw = _readings(END_BIAS, contact)
    vectors = pose_vectors(model, np.eye(3), np.zeros(3), raw)
    (row,) = vector_rows(["pose 3"], [vectors])
    # measured force F − F0 = a + [10, 0, 0] = [10, 0, −10]: 45° from a = [0, 0, −10]
    assert row.measured_force == pytest.approx(10.0 * np.sqrt(2.0), rel=1e-12)
    assert row.gravity_force == pytest.approx(10.0, rel=1e-12)
    assert row.angle_deg == pytest.approx(45.0, rel=1e-12)
    assert row.contact_force == pytest.approx(10.0, rel=1e-12)
    assert row.contact_torque == pytest.approx(0.5, rel=1e-12)  # |(0.3, 0.4)|
    line = vector_table(["pose 3"], [vectors]).splitlines()[1]
    assert line.split() == ["pose", "3", "14.1421", "10.0000", "45.000", "10.0000", "0.5000"]
    table = vector_table([f"row {i}" for i in range(42)], [vectors] * 42)
    assert len(table.splitlines()) == 1 + 40 + 1 and table.endswith("... 2 more")


def test_the_report_predicts_with_the_bias_of_compensate_after_a_re_zero():
    """The report's prediction at a pose's time takes the bias by the same rule: a pose after
    the recording of a re-zeroed calibration has the re-zeroed bias (its residual is its
    contact, zero here), not the trajectory's end."""
    from ftkin.viz.report import report_data

    rezeroed = END_BIAS + [0.4, 0.0, 0.0, 0.0, 0.0, 0.0]
    calibration = _calibration(rezeroed)
    had = np.array([END_BIAS - 0.05, rezeroed])  # at 150 s (inside) and 300 s (after)
    samples = Samples(
        _readings(had, np.zeros((2, 6))),
        np.repeat(np.eye(3)[None], 2, axis=0),
        np.arange(2),
        times=np.array([150.0, 300.0]),
    )
    np.testing.assert_allclose(report_data(calibration, samples)["residuals"], 0.0, atol=1e-12)


def test_the_outlined_cells_are_the_calibration_s_outlier_poses():
    from types import SimpleNamespace

    from ftkin.viz.view_frames import outlier_indices

    flagged = SimpleNamespace(diagnostics=SimpleNamespace(outlier_pose_ids=np.array([3, 7])))
    labels = ["pose 1", "pose 3", "pose 5", "pose 7", "row 3"]
    assert outlier_indices(labels, flagged) == [1, 3]  # a replay's "row 3" is not pose 3
    assert outlier_indices(labels, SimpleNamespace(diagnostics=None)) == []
