"""The bias checks of the library (ftkin.control.bias_checks): a re-zero that moved the bias by
more than the tool's weight, a drift trajectory a re-zero leaves in place, a log on another clock
than a drifting calibration's recording. Each threshold is tested on both of its sides, with the
expectation computed by hand from the numbers the test builds, and through the Compensator (the
API door) as well as the functions."""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
import pytest

from ftkin import Compensator
from ftkin.calibration.drift import BiasDrift
from ftkin.calibration.model import SensorModel
from ftkin.calibration.result import CalibrationResult
from ftkin.control.bias_checks import check_log_times, rezero_warnings

LOGGER = "ftkin.control"
END_BIAS = np.array([0.5, -0.4, 0.3, 0.01, -0.02, 0.03])  # [N, N·m]
SPAN = (95.0, 205.0)  # the recording's first and last reading [s]


def _drift(end_bias=END_BIAS) -> BiasDrift:
    """A poly:1 trajectory over pose times 100 and 200 s inside a recording of 95–205 s."""
    return BiasDrift(
        model="poly:1",
        selected_by="given",
        times=np.array([100.0, 200.0]),
        bias=np.array([end_bias - 0.1, end_bias]),
        bias_std=np.zeros((2, 6)),
        coefficients=np.full((1, 6), 0.1),
        time_scale=100.0,
        recorded_span=np.array(SPAN),
    )


def _calibration(weight: float, drift: BiasDrift | None = None) -> CalibrationResult:
    """A tool of ``weight`` [N] hanging along base −z, COM 5 cm along the sensor's z, the bias
    END_BIAS."""
    model = SensorModel(END_BIAS[:3], END_BIAS[3:], np.array([0.0, 0.0, -weight]), [0, 0, 0.05])
    return dataclasses.replace(CalibrationResult.from_model(model), drift=drift)


def _reading_at_identity(calibration, bias) -> np.ndarray:
    """The raw reading at R_BS = I with no contact: bias + [a, P × a] (by hand)."""
    a = calibration.gravity_in_base
    return np.asarray(bias) + np.concatenate([a, np.cross(calibration.center_of_mass, a)])


# ------------------------------------------------------------------ a log on another clock
def test_a_log_long_before_the_recording_is_said_on_either_side_of_ten_spans():
    first_allowed = SPAN[0] - 10.0 * (SPAN[1] - SPAN[0])  # 95 − 10 · 110 = −1005 s
    early = check_log_times(_drift(), [first_allowed - 0.5, 150.0, 300.0], END_BIAS)
    assert (early.rows, early.inside, early.outside) == (3, 1, 2)  # only 150 s is inside
    assert len(early.warnings) == 1
    assert "the log's times (-1005.5–300 s) are long before" in early.warnings[0]
    assert "(95–205 s)" in early.warnings[0]
    near = check_log_times(_drift(), [first_allowed + 0.5, 150.0], END_BIAS)
    assert near.warnings == () and near.inside == 1


def test_rows_inside_the_recording_are_said_once_the_bias_moved_from_the_trajectory_end():
    times = [96.0, 150.0, 204.0, 900.0]  # three inside 95–205 s, one after
    assert check_log_times(_drift(), times, END_BIAS).warnings == ()  # not re-zeroed
    below = END_BIAS + [0, 0, 0, 0, 0, 0.5e-9]  # within MOVED_BIAS = 1e-9: the same bias
    assert check_log_times(_drift(), times, below).warnings == ()
    above = END_BIAS + [0, 0, 0, 0, 0, 2e-9]
    (text,) = check_log_times(_drift(), times, above).warnings
    assert text.startswith("3 rows fall inside the calibration's recording (95–205 s)")
    assert "it moved by up to 2e-09" in text and "shift its times past 205 s" in text
    # every row after the recording takes the moved bias: nothing to say
    assert check_log_times(_drift(), [300.0, 400.0], END_BIAS + 1.0).warnings == ()


def test_without_a_trajectory_nothing_is_checked():
    for drift in (None, dataclasses.replace(_drift(), model="none", coefficients=None)):
        check = check_log_times(drift, [-1e9, 150.0], END_BIAS + 5.0)
        assert (check.inside, check.warnings) == (0, ())


def test_compensate_batch_with_times_warns_through_logging(caplog):
    calibration = _calibration(10.0, _drift())
    compensator = Compensator(calibration)
    rotations = np.repeat(np.eye(3)[None], 2, axis=0)
    raw = np.tile(_reading_at_identity(calibration, END_BIAS), (2, 1))
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        compensator.compensate_batch(rotations, raw, times=[150.0, 160.0])
    assert caplog.records == []  # inside, not re-zeroed
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        compensator.compensate_batch(rotations, raw, times=[-2000.0, -1990.0])
    assert "are long before the calibration's recording" in caplog.text
    caplog.clear()
    compensator.set_bias(END_BIAS + [0.3, 0, 0, 0, 0, 0])  # a re-zero in the session
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        contact = compensator.compensate_batch(rotations, raw, times=[150.0, 160.0])
    assert "2 rows fall inside" in caplog.text and "moved by up to 0.3" in caplog.text
    # the rows inside used the trajectory at their time: 0.1 N below the end at 150 s, hence
    # contact = END_BIAS − bias(150 s) = +0.05 (a linear trajectory, half way)
    np.testing.assert_allclose(contact[0], np.full(6, 0.05), atol=1e-12)


# ------------------------------------------------------------------ re-zero
@pytest.mark.parametrize("weight", [1.0, 5.0])  # below the 2 N floor, and above it
def test_a_rezero_is_warned_of_when_the_force_bias_moves_more_than_the_tool_weight(weight, caplog):
    calibration = _calibration(weight)
    limit = max(weight, 2.0)  # the tool's weight, at least REZERO_WARNING_FORCE
    direction = np.array([3.0, 4.0, 0.0]) / 5.0
    for scale, said in ((1.0 - 1e-6, False), (1.0 + 1e-6, True)):
        push = np.concatenate([scale * limit * direction, [0.1, 0.0, 0.0]])
        assert bool(rezero_warnings(calibration, END_BIAS, END_BIAS + push)) is said
        compensator = Compensator(calibration)
        caplog.clear()
        with caplog.at_level(logging.WARNING, logger=LOGGER):
            bias = compensator.rezero(np.eye(3), _reading_at_identity(calibration, END_BIAS + push))
        np.testing.assert_allclose(bias, END_BIAS + push, atol=1e-12)
        assert ("more than the tool's weight" in caplog.text) is said
    assert f"the bias moved by {scale * limit:.4g} N" in caplog.text


def test_a_rezero_of_a_drifting_calibration_says_the_trajectory_stays(caplog):
    calibration = _calibration(10.0, _drift())
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        Compensator(calibration).rezero(np.eye(3), _reading_at_identity(calibration, END_BIAS))
    (record,) = caplog.records  # the bias did not move: only the trajectory is said
    assert record.getMessage().startswith(
        "this calibration has a drift trajectory (poly:1) over 95–205 s"
    )


def test_driver_zeroed_at_is_not_a_rezero_and_says_nothing(caplog):
    calibration = _calibration(10.0, _drift())
    with caplog.at_level(logging.WARNING, logger=LOGGER):
        bias = Compensator(calibration).driver_zeroed_at(np.eye(3))
    np.testing.assert_allclose(bias[:3], [0.0, 0.0, 10.0], atol=1e-12)  # −a
    assert caplog.records == []
