"""Noise-free readings (a simulation without sensor noise): exact estimates, a clear warning, no
false outliers; "noise-free" is said only when the repeated raw readings are identical, never from
a fit's residuals.
"""

from __future__ import annotations

import logging

import numpy as np
import pytest

from ftkin import Samples, calibrate
from ftkin.calibration.information import noise_floor
from ftkin.calibration.model import SensorModel

TRUTH = SensorModel.from_tool(
    1.2, [0.01, 0.02, 0.06], force_offset=[1.0, -2.0, 0.5], torque_offset=[0.1, 0.02, -0.03]
)


def _exact(arm, readings: int) -> Samples:
    q = arm.random_configurations(12, np.random.default_rng(3), margin=0.3)
    rotations = np.repeat(arm.rotation_sensor_to_base(q), readings, axis=0)
    times = 10.0 * np.arange(12 * readings) / readings
    ids = np.repeat(np.arange(12), readings)
    return Samples(TRUTH.predict(rotations), rotations, ids, times=times)


@pytest.mark.parametrize("drift", ["none", "auto", "random-walk", "poly:2"])
def test_identical_repeated_readings_give_the_truth_and_say_noise_free(arm, drift, caplog):
    samples = _exact(arm, 3)
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(samples, drift=drift)
    # independent: the generating model
    np.testing.assert_allclose(result.to_vector(), TRUTH.to_vector(), atol=1e-6)
    assert result.diagnostics.outlier_pose_ids == ()
    assert any("simulation without sensor noise" in w for w in result.diagnostics.warnings)
    assert np.all(
        result.diagnostics.noise.channel_std >= noise_floor(samples.wrenches) * (1 - 1e-9)
    )


@pytest.mark.parametrize("drift", ["none", "auto", "random-walk"])
def test_one_exact_reading_per_pose_is_not_called_noise_free(arm, drift):
    """Residuals at rounding level are a fact about the fit, not proof of noise-free readings."""
    result = calibrate(_exact(arm, 1), drift=drift)
    np.testing.assert_allclose(result.to_vector(), TRUTH.to_vector(), atol=1e-6)
    warnings = result.diagnostics.warnings
    assert not any("simulation" in w for w in warnings)
    assert any("rounding level" in w for w in warnings)
    assert result.diagnostics.outlier_pose_ids == ()
    if drift == "random-walk":  # the walk would take the (zero) noise: the fit says so
        assert result.drift.model == "none" and result.drift.selected_by == "auto"
        assert any("cannot be told apart" in w for w in warnings)


def test_noisy_readings_are_not_called_exact(arm):
    exact = _exact(arm, 1)
    rng = np.random.default_rng(0)
    noisy = Samples(
        exact.wrenches + rng.normal(0, [1e-4] * 3 + [1e-5] * 3, (12, 6)),
        exact.rotations,
        exact.pose_ids,
        times=exact.times,
    )
    result = calibrate(noisy, drift="none")
    assert not any("rounding" in w for w in result.diagnostics.warnings)
    assert result.diagnostics.noise.force_std[0] == pytest.approx(1e-4, rel=0.5)
