"""Dynamic calibration (regressor, log-Cholesky map, calibrate_dynamic) against MuJoCo and
Pinocchio.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from ftkin import Samples, UnobservableParameters, calibrate
from ftkin.calibration.dynamic import calibrate_dynamic
from ftkin.calibration.log_cholesky import (
    body_from_parameters,
    is_physically_consistent,
    log_cholesky_from_parameters,
    log_cholesky_jacobian,
    parameters_from_log_cholesky,
    pseudo_inertia,
)
from ftkin.calibration.regressor import MotionSamples, body_regressor, gravity_regressor
from ftkin.kinematics.rotations import gravity_in_base_from_tilt

mujoco_recording = pytest.importorskip("ftkin.sim.mujoco.recording")
pytest.importorskip("mujoco")

TOOL = mujoco_recording.ToolInertia(
    1.2,
    [0.01, -0.02, 0.08],
    [[0.004, 0.0003, 0.0001], [0.0003, 0.005, -0.0002], [0.0001, -0.0002, 0.003]],
)
TILT = (0.01, -0.02)
BIAS = np.array([0.5, -0.3, 0.2, 0.01, -0.02, 0.03])


@pytest.fixture(scope="module")
def recorder(arm):
    return mujoco_recording.MujocoRecorder(joint_names=arm.joint_names, tool=TOOL, base_tilt=TILT)


def _random_motion(arm, count, seed):
    rng = np.random.default_rng(seed)
    q = arm.random_configurations(count, rng)
    return q, rng.normal(0.0, 2.0, q.shape), rng.normal(0.0, 10.0, q.shape)


def test_regressor_matches_mujoco_inverse_dynamics_and_pinocchio(arm, recorder):
    q, dq, ddq = _random_motion(arm, 40, 1)
    wrenches = recorder.wrenches(q, dq, ddq)
    motion = MotionSamples.from_joint_trajectory(arm, q, dq, ddq, wrenches)
    upward = np.einsum("nji,j->ni", motion.rotations, -gravity_in_base_from_tilt(9.80665, *TILT))
    predicted = -((motion.regressor() + gravity_regressor(upward)) @ TOOL.parameters())
    np.testing.assert_allclose(predicted, wrenches, atol=1e-10)
    np.testing.assert_allclose(recorder.true_parameters(), TOOL.parameters(), atol=1e-14)
    for i in range(5):
        expected = pin.bodyRegressor(
            pin.Motion(motion.velocities[i]), pin.Motion(motion.accelerations[i])
        )
        np.testing.assert_allclose(
            body_regressor(motion.velocities[i], motion.accelerations[i])[0], expected, atol=1e-12
        )


def test_log_cholesky_round_trip_and_jacobian():
    rng = np.random.default_rng(3)
    for _ in range(20):
        box = pin.Inertia.FromBox(rng.uniform(0.1, 3.0), *rng.uniform(0.01, 0.3, 3))
        placement = pin.SE3(pin.exp3(rng.normal(size=3)), rng.normal(0.0, 0.1, 3))
        theta = placement.act(box).toDynamicParameters()  # a real body: consistent
        phi = log_cholesky_from_parameters(theta)
        np.testing.assert_allclose(parameters_from_log_cholesky(phi), theta, atol=1e-12)
        # Pinocchio builds the same pseudo-inertia from φ.
        np.testing.assert_allclose(
            pin.LogCholeskyParameters(phi).toPseudoInertia().toMatrix(),
            pseudo_inertia(theta),
            atol=1e-12,
        )
        phi = rng.normal(size=10)
        np.testing.assert_allclose(
            log_cholesky_from_parameters(parameters_from_log_cholesky(phi)), phi, atol=1e-9
        )
        step = 1e-6
        numeric = np.column_stack(
            [
                (
                    parameters_from_log_cholesky(phi + step * e)
                    - parameters_from_log_cholesky(phi - step * e)
                )
                / (2 * step)
                for e in np.eye(10)
            ]
        )
        np.testing.assert_allclose(log_cholesky_jacobian(phi), numeric, rtol=1e-6, atol=1e-8)
    with pytest.raises(ValueError, match="not physically consistent"):
        log_cholesky_from_parameters(
            np.array([1.0, 0, 0, 0, 1.0, 0, 1.0, 0, 0, 5.0])
        )  # violates the triangle inequality


def test_noise_free_mujoco_data_recovered(arm, recorder):
    q, dq, ddq = _random_motion(arm, 200, 2)
    motion = MotionSamples.from_joint_trajectory(
        arm, q, dq, ddq, recorder.wrenches(q, dq, ddq) + BIAS
    )
    result = calibrate_dynamic(motion)
    assert result.has_inertia and result.unconstrained_consistent
    assert abs(result.tool_mass - TOOL.mass) < 1e-6
    np.testing.assert_allclose(result.center_of_mass, TOOL.center_of_mass, atol=1e-6)
    np.testing.assert_allclose(
        result.inertia_about_com_in_sensor, TOOL.inertia_about_com, atol=1e-6
    )
    np.testing.assert_allclose(result.bias, BIAS, atol=1e-6)
    np.testing.assert_allclose(result.base_tilt, TILT, atol=1e-6)


def test_static_data_reports_inertia_unobservable(arm, recorder):
    q = arm.random_configurations(30, np.random.default_rng(4), margin=0.3)
    samples = Samples.from_joint_positions(arm, q, recorder.wrenches(q) + BIAS)
    with pytest.raises(UnobservableParameters, match="inertia") as error:
        calibrate_dynamic(samples)
    assert "inertia_about_com_in_sensor" in error.value.names
    # Without the inertia, one orientation still cannot separate weight from bias.
    single = Samples.from_joint_positions(
        arm, np.repeat(q[:1], 5, axis=0), recorder.wrenches(np.repeat(q[:1], 5, axis=0))
    )
    with pytest.raises(UnobservableParameters, match="force_offset|mass|base_tilt"):
        calibrate_dynamic(single, estimate_inertia=False)


def test_static_special_case_agrees_with_static_calibration(arm, recorder):
    rng = np.random.default_rng(5)
    q = arm.random_configurations(30, rng, margin=0.3)
    wrenches = recorder.wrenches(q) + BIAS + rng.normal(0.0, [0.02] * 3 + [0.002] * 3, (30, 6))
    samples = Samples.from_joint_positions(arm, q, wrenches)
    dynamic = calibrate_dynamic(samples, estimate_inertia=False)
    static = calibrate(samples)
    assert not dynamic.has_inertia
    # Both are ML fits of the same 12-parameter model; they differ only by the noise weights.
    np.testing.assert_allclose(
        dynamic.gravity_in_base,
        static.gravity_in_base,
        atol=3 * static.std_errors["gravity_in_base"].max(),
    )
    np.testing.assert_allclose(
        dynamic.bias, static.bias, atol=3 * max(static.std_errors["force_offset"].max(), 1e-3)
    )
    np.testing.assert_allclose(
        dynamic.center_of_mass,
        static.center_of_mass,
        atol=3 * static.std_errors["center_of_mass"].max(),
    )
    np.testing.assert_allclose(
        dynamic.std_errors["tool_mass"], static.std_errors["tool_mass"], rtol=0.3
    )


def test_result_physically_consistent_where_least_squares_is_not(arm):
    # A near point mass: tiny principal moments, so noise pushes the unconstrained estimate out of
    # the consistent set.
    point = mujoco_recording.ToolInertia(0.8, [0.0, 0.0, 0.06], np.diag([2e-7, 2e-7, 1e-7]))
    recorder = mujoco_recording.MujocoRecorder(joint_names=arm.joint_names, tool=point)
    q, dq, ddq = _random_motion(arm, 300, 6)
    rng = np.random.default_rng(6)
    wrenches = recorder.wrenches(q, dq, ddq) + rng.normal(0.0, [0.05] * 3 + [0.004] * 3, q.shape)
    result = calibrate_dynamic(MotionSamples.from_joint_trajectory(arm, q, dq, ddq, wrenches))
    assert result.unconstrained_consistent is False
    assert not is_physically_consistent(result.unconstrained_parameters)
    assert is_physically_consistent(result.inertial_parameters, tolerance=-1e-12)
    assert np.linalg.eigvalsh(pseudo_inertia(result.inertial_parameters))[0] >= -1e-12
    mass, _, about_com = body_from_parameters(result.inertial_parameters)
    assert abs(mass - 0.8) < 0.01
    assert np.linalg.eigvalsh(about_com)[0] >= -1e-9
