"""The view's vectors come from the model: a signed calibration's readings are signed once."""

from __future__ import annotations

import dataclasses

import numpy as np
from scipy.spatial.transform import Rotation

from ftkin import CalibrationResult, Samples
from ftkin.calibration.conventions import as_real_sensor
from ftkin.viz import pose_vectors


def test_contact_of_a_reaction_sensor_is_zero_at_a_free_pose(truth):
    calibration = dataclasses.replace(CalibrationResult.from_model(truth), sensor_sign=-1)
    rotations = Rotation.random(4, random_state=7).as_matrix()
    as_read = -truth.predict(rotations)  # the sensor reports the reaction
    real = as_real_sensor(Samples.from_rotations(rotations, as_read), calibration)
    for rotation, raw in zip(real.rotations, real.wrenches):
        vectors = pose_vectors(calibration, rotation, np.zeros(3), raw)
        np.testing.assert_allclose(vectors.contact_wrench, 0.0, atol=1e-12)
        np.testing.assert_allclose(vectors.measured_force, truth.gravity_in_base, atol=1e-12)
