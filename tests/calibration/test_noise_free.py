"""Noise-free readings (a simulation without sensor noise): exact estimates, a clear warning, no
false outliers.
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


@pytest.fixture(scope="module")
def exact_samples(arm):
    q = arm.random_configurations(12, np.random.default_rng(3), margin=0.3)
    rotations = arm.rotation_sensor_to_base(q)
    return Samples(TRUTH.predict(rotations), rotations, np.arange(12), times=10.0 * np.arange(12))


@pytest.mark.parametrize("drift", ["none", "auto", "random-walk", "poly:2"])
def test_noise_free_readings_give_the_truth_and_say_so(exact_samples, drift, caplog):
    with caplog.at_level(logging.WARNING, logger="ftkin"):
        result = calibrate(exact_samples, drift=drift)
    np.testing.assert_allclose(
        result.to_vector(), TRUTH.to_vector(), atol=1e-6
    )  # independent: the generating model
    assert result.diagnostics.outlier_pose_ids == ()
    assert any("fit the model to rounding" in w for w in result.diagnostics.warnings)
    assert np.all(
        result.diagnostics.noise.channel_std >= noise_floor(exact_samples.wrenches) * (1 - 1e-9)
    )


def test_noisy_readings_are_not_called_exact(arm, exact_samples):
    rng = np.random.default_rng(0)
    noisy = Samples(
        exact_samples.wrenches + rng.normal(0, [1e-4] * 3 + [1e-5] * 3, (12, 6)),
        exact_samples.rotations,
        exact_samples.pose_ids,
        times=exact_samples.times,
    )
    result = calibrate(noisy, drift="none")
    assert not any("rounding" in w for w in result.diagnostics.warnings)
    assert result.diagnostics.noise.force_std[0] == pytest.approx(1e-4, rel=0.5)
