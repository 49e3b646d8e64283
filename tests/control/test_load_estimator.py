"""LoadEstimator against batch least squares on the regressor module's matrices, Monte Carlo
spreads and MuJoCo's bodies."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftkin.calibration.information import SensorNoise
from ftkin.calibration.regressor import gravity_regressor, sensor_motion
from ftkin.control.load_estimator import LoadEstimator
from ftkin.exceptions import InvalidInput

GRAVITY = np.array([0.0, 0.0, -9.80665])


def random_rotations(count, rng):
    return Rotation.random(count, random_state=rng).as_matrix()


NOISE = SensorNoise([0.02, 0.03, 0.025], [0.002, 0.0015, 0.0025])


def _load_wrench(rotation, mass, com):
    """f = m R_BSᵀ γ, τ = c × f, by hand."""
    force = mass * rotation.T @ GRAVITY
    return np.concatenate([force, np.cross(com, force)])


def test_information_form_equals_batch_weighted_least_squares(rng):
    rotations = random_rotations(40, rng)
    mass, com = 0.42, np.array([0.012, -0.03, 0.075])
    wrenches = np.array([_load_wrench(r, mass, com) for r in rotations])
    wrenches += rng.normal(size=wrenches.shape) * NOISE.channel_std
    estimator = LoadEstimator(NOISE, GRAVITY)
    for rotation, wrench in zip(rotations, wrenches):
        estimator.add_still(rotation, wrench)
    estimate = estimator.estimate()
    # the batch: −gravity_regressor(g_up) (the regressor module's matrices), first four columns
    upward = -np.einsum("nji,j->ni", rotations, GRAVITY)
    design = -gravity_regressor(upward)[:, :, :4].reshape(-1, 4)
    whitening = np.tile(1.0 / NOISE.channel_std, len(rotations))
    theta, *_ = np.linalg.lstsq(design * whitening[:, None], wrenches.reshape(-1) * whitening)
    covariance = np.linalg.inv((design * whitening[:, None]).T @ (design * whitening[:, None]))
    np.testing.assert_allclose(estimate.mass, theta[0], rtol=1e-10)
    np.testing.assert_allclose(estimate.com_in_sensor, theta[1:] / theta[0], rtol=1e-9)
    np.testing.assert_allclose(estimate.mass_std, np.sqrt(covariance[0, 0]), rtol=1e-9)
    residual = (wrenches.reshape(-1) - design @ theta) * whitening
    np.testing.assert_allclose(estimate.chi_square, residual @ residual, rtol=1e-6)
    assert estimate.dof == 6 * 40 - 4 and estimate.com_determined.all()
    np.testing.assert_allclose(estimate.com_in_sensor, com, atol=5 * estimate.com_std.max())


@pytest.mark.parametrize("axis", [0, 1, 2])
def test_one_orientation_leaves_the_com_along_gravity_undetermined(axis):
    """Gravity along a sensor axis: that COM component is undetermined (NaN, std inf), the
    others and the mass are numbers."""
    rotation = np.eye(3)
    if axis != 2:  # turn the sensor so gravity lies along its axis `axis`
        rotation = np.array([[0, 0, 1], [0, 1, 0], [-1, 0, 0]]) if axis == 0 else None
        if axis == 1:
            rotation = np.array([[1, 0, 0], [0, 0, 1], [0, -1, 0]])
    gravity_in_sensor = rotation.T @ GRAVITY
    assert abs(abs(gravity_in_sensor[axis]) - 9.80665) < 1e-12
    com = np.array([0.01, -0.02, 0.05])
    estimator = LoadEstimator(NOISE, GRAVITY)
    for _ in range(50):
        estimator.add_still(rotation, _load_wrench(rotation, 0.3, com))
    estimate = estimator.estimate()
    np.testing.assert_allclose(estimate.mass, 0.3, rtol=1e-12)
    assert np.isnan(estimate.com_in_sensor[axis]) and np.isinf(estimate.com_std[axis])
    others = [i for i in range(3) if i != axis]
    np.testing.assert_allclose(estimate.com_in_sensor[others], com[others], atol=1e-12)
    assert np.all(np.isfinite(estimate.com_std[others]))
    assert "?" in estimate.summary()


def test_standard_errors_match_the_spread_and_shrink_as_the_wrist_turns():
    """Monte Carlo: the reported standard errors are the spread of the estimates (within 20 %), and
    a second orientation determines the whole COM."""
    still = np.eye(3)
    turned = random_rotations(1, np.random.default_rng(3))[0]
    mass, com = 0.25, np.array([0.0, 0.01, 0.06])
    masses, coms, reported = [], [], None
    for seed in range(200):  # the spread of a standard deviation from 200: ±5 %
        rng = np.random.default_rng(seed)
        estimator = LoadEstimator(NOISE, GRAVITY)
        for rotation in [still] * 20 + [turned] * 20:
            reading = _load_wrench(rotation, mass, com) + rng.normal(size=6) * NOISE.channel_std
            estimator.add_still(rotation, reading)
        estimate = estimator.estimate()
        masses.append(estimate.mass)
        coms.append(estimate.com_in_sensor)
        reported = estimate
    assert np.std(masses) == pytest.approx(reported.mass_std, rel=0.2)
    np.testing.assert_allclose(np.std(coms, axis=0), reported.com_std, rtol=0.2)
    one = LoadEstimator(NOISE, GRAVITY)
    for _ in range(20):
        one.add_still(still, _load_wrench(still, mass, com))
    assert np.isinf(one.estimate().com_std[2]) and np.isfinite(reported.com_std[2])


def test_motion_identifies_the_inertia_of_a_mujoco_body(arm):
    """The ten parameters from a moving recording: MuJoCo's inverse dynamics of a body of known
    inertia (ftkin's sensor motion from Pinocchio), noise-free."""
    pytest.importorskip("mujoco")
    from ftkin.sim.mujoco.recording import MujocoRecorder
    from ftkin.sim.mujoco.tool_inertia import ToolInertia

    inertia = np.array([[2.1e-3, 1e-4, -2e-4], [1e-4, 1.6e-3, 3e-4], [-2e-4, 3e-4, 1.2e-3]])
    body = ToolInertia(0.8, np.array([0.01, -0.02, 0.06]), inertia)
    recorder = MujocoRecorder(tool=body)
    rng = np.random.default_rng(11)
    q = arm.random_configurations(300, rng, margin=0.4)
    dq, ddq = rng.uniform(-1.5, 1.5, q.shape), rng.uniform(-6, 6, q.shape)
    raw = recorder.wrenches(q, dq, ddq)
    rotations, velocities, accelerations = sensor_motion(arm, q, dq, ddq)
    estimator = LoadEstimator(NOISE, recorder.model.opt.gravity)
    for i in range(len(q)):
        estimator.add_motion(rotations[i], velocities[i], accelerations[i], raw[i])
    estimate = estimator.estimate()
    truth = recorder.true_parameters()
    np.testing.assert_allclose(estimate.inertial_parameters, truth, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(estimate.com_in_sensor, body.center_of_mass, atol=1e-9)
    assert np.all(np.isfinite(estimate.inertia_std))


def test_bad_inputs_are_named():
    with pytest.raises(InvalidInput, match="SensorNoise"):
        LoadEstimator((0.02, 0.002))
    with pytest.raises(InvalidInput, match="gravity_in_base must not be zero"):
        LoadEstimator(NOISE, (0.0, 0.0, 0.0))
    estimator = LoadEstimator(NOISE)
    with pytest.raises(InvalidInput, match="load_wrench"):
        estimator.add_still(np.eye(3), [1.0, 2.0, np.nan, 0, 0, 0])
    with pytest.raises(InvalidInput):
        estimator.add_still(np.ones((3, 3)), np.zeros(6))
    empty = estimator.estimate()  # nothing added: nothing determined, said as such
    assert np.isinf(empty.mass_std) and np.all(np.isnan(empty.com_in_sensor))


def test_a_point_mass_has_pinocchios_parameters():
    """The held load's inertial wrench while moving uses a point mass at its COM."""
    import pinocchio as pin

    from ftkin.control.dynamic_compensation import point_mass_parameters

    mass, com = 0.7, np.array([0.02, -0.01, 0.09])
    expected = pin.Inertia(mass, com, np.zeros((3, 3))).toDynamicParameters()
    np.testing.assert_allclose(
        point_mass_parameters([mass, *(mass * com)]), expected, rtol=1e-12, atol=1e-15
    )
    np.testing.assert_allclose(point_mass_parameters([0.0, 0, 0, 0]), np.zeros(10))
