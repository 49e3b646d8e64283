"""The sensor mount R_M in the ML fit: parameterisation, Jacobian, recovery, observability."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin import (
    InvalidInput,
    Samples,
    SensorModel,
    SensorNoise,
    UnobservableParameters,
    calibrate,
    evaluate_poses,
)
from ftkin.calibration.ml import WeightedProblem
from ftkin.calibration.mount import (
    exp_so3,
    mount_jacobian,
    right_jacobian_so3,
    rotation_to_rpy,
)
from ftkin.kinematics.rotations import euler_zyx_to_matrix

NOISE = SensorNoise(0.02, 0.002)


def _readings(model, rotations_urdf, mount, rng, noise=NOISE):
    """Readings of the real sensor (R_BS = R_urdf R_Mᵀ) with Gaussian noise."""
    clean = model.predict(rotations_urdf @ mount.T)
    return clean + rng.normal(size=clean.shape) * noise.channel_std


def _joint_samples(arm, q, wrenches):
    return Samples.from_joint_positions(arm, q, wrenches)


def test_exp_and_right_jacobian_match_scipy():
    rng = np.random.default_rng(0)
    for _ in range(20):
        w = rng.normal(size=3) * rng.uniform(0.0, 2.5)
        np.testing.assert_allclose(exp_so3(w), Rotation.from_rotvec(w).as_matrix(), atol=1e-12)
        dw = rng.normal(size=3) * 1e-6
        step = Rotation.from_matrix(exp_so3(w).T @ exp_so3(w + dw)).as_rotvec()
        np.testing.assert_allclose(step, right_jacobian_so3(w) @ dw, atol=1e-11)
    np.testing.assert_allclose(exp_so3(np.zeros(3)), np.eye(3))


def test_rpy_matches_scipy():
    rng = np.random.default_rng(1)
    for _ in range(10):
        rotation = Rotation.random(random_state=rng)
        # URDF rpy: R = Rz(yaw) Ry(pitch) Rx(roll) = scipy extrinsic "xyz" with [roll, pitch, yaw]
        np.testing.assert_allclose(
            rotation_to_rpy(rotation.as_matrix()), rotation.as_euler("xyz"), atol=1e-10
        )


@pytest.mark.parametrize("mode", ["yaw", "full"])
def test_mount_jacobian_matches_finite_differences(mode, tool, rotations):
    count = 3 if mode == "full" else 1
    rng = np.random.default_rng(2)
    base = exp_so3([0.05, -0.03, 0.6])
    problem = WeightedProblem(
        rotations, np.zeros((len(rotations), 6)), np.ones(len(rotations)), np.ones(6), base, mode
    )
    x = np.concatenate([tool.to_vector(), rng.normal(size=count) * 0.3])
    analytic = problem.jacobian(x).reshape(-1, len(x))
    numeric = np.empty_like(analytic)
    for k in range(len(x)):
        step = np.zeros(len(x))
        step[k] = 1e-6
        numeric[:, k] = (
            -(problem.residuals(x + step) - problem.residuals(x - step)).reshape(-1) / 2e-6
        )
    np.testing.assert_allclose(analytic, numeric, atol=2e-7 * np.abs(numeric).max())
    # at δ = 0 the planner's Jacobian is the same
    at_zero = mount_jacobian(rotations, tool.gravity_in_base, tool.center_of_mass, mode, base)
    np.testing.assert_allclose(at_zero, problem.jacobian(tool.to_vector()), atol=1e-12)


def test_yaw_mount_recovered_within_three_sigma(arm, tool):
    rng = np.random.default_rng(3)
    q = arm.random_configurations(15, rng, margin=0.3)
    yaw = np.deg2rad(-40.0)
    mount = exp_so3([0.0, 0.0, yaw])
    samples = _joint_samples(arm, q, _readings(tool, arm.rotation_sensor_to_base(q), mount, rng))
    result = calibrate(samples, estimate_mount="yaw", noise=NOISE)
    sigma = np.deg2rad(result.mount_std_deg["mount[z]"])
    assert abs(np.deg2rad(result.mount_rpy_deg[2]) - yaw) < 3 * sigma
    assert result.mount_rpy_deg[:2] == pytest.approx([0.0, 0.0], abs=1e-9)
    # the parameters are the real sensor's: within 3σ of the truth
    errors = result.std_errors
    assert np.all(
        np.abs(result.center_of_mass - tool.center_of_mass) < 3 * errors["center_of_mass"]
    )
    assert np.all(np.abs(result.force_offset - tool.force_offset) < 3 * errors["force_offset"])


def test_full_mount_recovered_within_three_sigma_and_det_plus_one(arm, tool):
    rng = np.random.default_rng(4)
    misses = 0
    for _ in range(12):
        q = arm.random_configurations(14, rng, margin=0.3)
        truth = exp_so3(
            np.deg2rad([rng.uniform(-5, 5), rng.uniform(-5, 5), rng.uniform(-170, 170)])
        )
        samples = _joint_samples(
            arm, q, _readings(tool, arm.rotation_sensor_to_base(q), truth, rng)
        )
        result = calibrate(samples, estimate_mount="full", noise=NOISE)
        estimate = result.mount_rotation
        assert np.linalg.det(estimate) == pytest.approx(1.0, abs=1e-12)
        np.testing.assert_allclose(estimate @ estimate.T, np.eye(3), atol=1e-12)
        # error as a rotation vector about the real sensor's axes: R_est = R_true Exp(e)
        error = Rotation.from_matrix(truth.T @ estimate).as_rotvec()
        sigma = np.sqrt(np.diag(result.mount_covariance))
        misses += int(np.any(np.abs(error) > 3 * sigma))
    assert misses <= 1  # 3σ on 3 angles: about 1 % of trials miss by chance


def test_mount_refused_for_rotations_given_directly(tool, rotations):
    samples = Samples.from_rotations(rotations, tool.predict(rotations))
    with pytest.raises(InvalidInput, match="joint angles.*absorbed"):
        calibrate(samples, estimate_mount="yaw")
    with pytest.raises(InvalidInput, match="unknown estimate_mount"):
        calibrate(samples, estimate_mount="roll")


def _yaw_blind_rotations():
    """Sensor z axis always with the same horizontal part (tilted 30° toward base x, pointing down
    or up), spun about z.
    """
    rotations = []
    for tilt in (np.pi - np.deg2rad(30.0), np.deg2rad(30.0)):
        for spin in np.deg2rad([0.0, 70.0, 140.0, 210.0, 280.0]):
            rotations.append(
                euler_zyx_to_matrix([0.0, tilt, 0.0]) @ euler_zyx_to_matrix([spin, 0.0, 0.0])
            )
    rotations = np.array(rotations)
    axes = rotations[:, :, 2]
    assert np.allclose(axes[:, :2], axes[0, :2])  # same horizontal part at every pose
    return rotations


def test_yaw_unobservable_when_sensor_z_keeps_its_horizontal_part(tool):
    rotations = _yaw_blind_rotations()
    evaluate_poses(rotations)  # θ alone is determined by these poses
    with pytest.raises(UnobservableParameters, match="mount\\[z\\].*tilted"):
        evaluate_poses(rotations, estimate_mount="yaw")
    rng = np.random.default_rng(5)
    level = SensorModel.from_tool(
        tool.tool_mass, tool.center_of_mass, tool.force_offset, tool.torque_offset
    )
    wrenches = level.predict(rotations) + rng.normal(size=(len(rotations), 6)) * NOISE.channel_std
    samples = Samples(wrenches, rotations, joint_positions=np.zeros((len(rotations), 1)))
    with pytest.raises(UnobservableParameters) as caught:
        calibrate(samples, estimate_mount="yaw", noise=NOISE)
    assert caught.value.names == ["mount[z]"]
    assert "horizontal axes" in str(caught.value)
    # a base tilt of a few tenths of a degree makes the yaw barely observable: warned about, not
    # hidden
    wrenches = tool.predict(rotations) + rng.normal(size=(len(rotations), 6)) * NOISE.channel_std
    samples = Samples(wrenches, rotations, joint_positions=np.zeros((len(rotations), 1)))
    result = calibrate(samples, estimate_mount="yaw", noise=NOISE)
    assert result.mount_std_deg["mount[z]"] > 1.0
    assert any("mount is poorly determined (mount[z]" in message for message in result.warnings)


def test_estimating_the_mount_never_lowers_the_predicted_errors(rotations):
    known = evaluate_poses(rotations)
    for mode in ("yaw", "full"):
        estimated = evaluate_poses(rotations, estimate_mount=mode)
        assert np.all(estimated.vector_std >= known.vector_std * (1 - 1e-9))
        assert len(estimated.mount_std_deg) == (1 if mode == "yaw" else 3)
        assert "mount[z]" in estimated.report()
