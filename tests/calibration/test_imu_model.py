"""The IMU model against the Newton–Euler equations written out, and the rigid-body kinematics of
the accelerometer's lever arm."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from ftkin.calibration.imu_model import (
    ImuFloatModel,
    point_mass_parameters,
    predict_imu,
    specific_force_in_sensor,
)
from ftkin.calibration.log_cholesky import parameters_from_body


def test_predict_is_newton_euler(rng):
    """Load on the sensor = bias − (the wrench that accelerates the tool), about the sensor."""
    mass, com = 1.3, np.array([0.02, -0.01, 0.09])
    turn = Rotation.random(random_state=2).as_matrix()
    inertia_com = turn @ np.diag([0.004, 0.003, 0.001]) @ turn.T
    theta = parameters_from_body(mass, com, inertia_com)
    bias = rng.normal(size=6)
    for _ in range(20):
        force, omega, alpha = rng.normal(0, 9, 3), rng.normal(0, 2, 3), rng.normal(0, 10, 3)
        com_acceleration = force + np.cross(alpha, com) + np.cross(omega, np.cross(omega, com))
        push = mass * com_acceleration
        turn_about_origin = (
            np.cross(com, push) + inertia_com @ alpha + np.cross(omega, inertia_com @ omega)
        )
        expected = bias - np.concatenate([push, turn_about_origin])
        got = predict_imu(bias, theta, force[None], omega[None], alpha[None])[0]
        np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)


def test_a_tool_hanging_below_pulls_down():
    """An upright sensor at rest: the accelerometer reads +g up, the tool's weight pulls −z."""
    up = np.array([[0.0, 0.0, 9.80665]])
    reading = predict_imu(np.zeros(6), point_mass_parameters(2.0, [0.0, 0.0, 0.1]), up)
    np.testing.assert_allclose(reading[0], [0.0, 0.0, -2.0 * 9.80665, 0.0, 0.0, 0.0], atol=1e-12)


def test_lever_arm_is_rigid_body_kinematics(rng):
    """The IMU at r reads f_origin + α × r + ω × (ω × r): undone by specific_force_in_sensor."""
    rotation = Rotation.random(random_state=4).as_matrix()
    position = np.array([0.02, -0.03, 0.01])
    origin = rng.normal(0, 9, (10, 3))
    omega, alpha = rng.normal(0, 2, (10, 3)), rng.normal(0, 10, (10, 3))
    at_imu = origin + np.cross(alpha, position) + np.cross(omega, np.cross(omega, position))
    bias, scale = np.array([0.3, -0.2, 0.5]), np.array([0.004, 0.001, -0.002])
    reading = (1.0 + scale) * (at_imu @ rotation) + bias  # IMU frame: R_SIᵀ f
    recovered = specific_force_in_sensor(reading, rotation, bias, scale, position, omega, alpha)
    np.testing.assert_allclose(recovered, origin, atol=1e-12)


def test_float_model_set_replaces_everything(rng):
    rotation = Rotation.random(random_state=5).as_matrix()
    model = ImuFloatModel(rotation, np.zeros(3), np.zeros(3), np.zeros(6), np.zeros(10))
    theta = parameters_from_body(1.1, [0.01, 0.0, 0.05], np.diag([1e-3, 2e-3, 3e-3]))
    bias = rng.normal(size=6)
    model.set(rotation, [0.1, 0.2, 0.3], [0.01, 0.0, 0.0], bias, theta, [0.01, 0.02, 0.03])
    raw, accel, gyro, rate = (
        rng.normal(size=6),
        rng.normal(size=3),
        rng.normal(size=3),
        rng.normal(size=3),
    )
    force = specific_force_in_sensor(
        accel[None],
        rotation,
        [0.1, 0.2, 0.3],
        [0.01, 0, 0],
        [0.01, 0.02, 0.03],
        (rotation @ gyro)[None],
        (rotation @ rate)[None],
    )
    expected = (
        raw - predict_imu(bias, theta, force, (rotation @ gyro)[None], (rotation @ rate)[None])[0]
    )
    got = model.contact_moving(raw.tolist(), accel.tolist(), gyro.tolist(), rate.tolist())
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)
