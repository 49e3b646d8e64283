"""The fast paths of the model (per-tick floats, blocked batch) give the model's numbers.

``raw − SensorModel.predict(R_BS)`` is the reference; the fast paths must agree to 1e-12
relative (the same IEEE operations up to the order of additions).
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ftkin.calibration.model import (
    _BLOCK,
    FloatModel,
    SensorModel,
    contact_batch,
    gravity_in_sensor,
    parameter_jacobian,
    predict,
)


def _model(rng) -> SensorModel:
    return SensorModel(
        rng.normal(size=3), 0.1 * rng.normal(size=3), [0.3, -0.2, -9.5], 0.05 * rng.normal(size=3)
    )


def test_float_model_equals_predict(rng):
    model = _model(rng)
    rotations = Rotation.random(200, random_state=3).as_matrix()
    raw = rng.normal(scale=5.0, size=(200, 6))
    expected = raw - model.predict(rotations)
    floats = FloatModel(model.gravity_in_base, model.center_of_mass, model.bias)
    got = np.array([floats.contact(r.tolist(), w.tolist()) for r, w in zip(rotations, raw)])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(raw).max())
    floats.set(model.gravity_in_base, model.center_of_mass, np.zeros(6))  # a bound method sees it
    contact = floats.contact
    np.testing.assert_allclose(
        contact(rotations[0].tolist(), raw[0].tolist()), expected[0] + model.bias, rtol=1e-12
    )


def test_contact_batch_equals_predict_over_several_blocks(rng):
    model = _model(rng)
    count = 2 * _BLOCK + 7
    rotations = Rotation.random(count, random_state=4).as_matrix()
    raw = rng.normal(scale=5.0, size=(count, 6))
    weight = gravity_in_sensor(rotations, model.gravity_in_base)
    tolerance = {"rtol": 1e-12, "atol": 1e-12 * np.abs(raw).max()}
    np.testing.assert_allclose(
        contact_batch(raw, weight, model.center_of_mass, model.bias),
        raw - model.predict(rotations),
        **tolerance,
    )
    bias = rng.normal(size=(count, 6))  # one bias per reading, as a drift model gives
    np.testing.assert_allclose(
        contact_batch(raw, weight, model.center_of_mass, bias),
        raw - model.tool_gravity_wrench(rotations) - bias,
        **tolerance,
    )


def test_predict_by_hand_and_jacobian_by_finite_differences(rng):
    model = _model(rng)
    rotations = Rotation.random(5, random_state=5).as_matrix()
    theta = model.to_vector()
    weight = np.einsum("nij,i->nj", rotations, model.gravity_in_base)  # R_BSᵀ a, written apart
    by_hand = np.hstack(
        [weight + model.force_offset, np.cross(model.center_of_mass, weight) + model.torque_offset]
    )
    np.testing.assert_allclose(predict(rotations, theta), by_hand, rtol=1e-12, atol=1e-13)
    analytic = parameter_jacobian(rotations, theta[0:3], theta[9:12])
    for k in range(12):
        step = np.zeros(12)
        step[k] = 1e-6
        numeric = (predict(rotations, theta + step) - predict(rotations, theta - step)) / 2e-6
        np.testing.assert_allclose(analytic[:, :, k], numeric, atol=1e-8)
