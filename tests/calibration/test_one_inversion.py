"""Every fit's problem shares one sign for its whitened Jacobian (the derivative of the whitened
prediction), and every fit names what a degenerate pose set leaves open by one rule, the
combination in the error's data (:mod:`ftkin.calibration.covariance`)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.calibration.covariance import (
    RCOND,
    covariance_in_sensor_axes,
    delta_method,
    invert_information,
    weakest_directions,
)
from ftkin.calibration.dynamic_fit import ALL_INDICES, STATIC_INDICES, DynamicProblem
from ftkin.calibration.dynamic_fit import theta_space as dynamic_theta_space
from ftkin.calibration.fused_problem import FusedStaticProblem
from ftkin.calibration.fused_samples import FusedSamples
from ftkin.calibration.imu_dynamic import ImuDynamicProblem, ImuMotion
from ftkin.calibration.imu_fit import calibrate_imu
from ftkin.calibration.imu_problem import ImuStaticProblem
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.ml import WeightedProblem
from ftkin.calibration.model import SensorModel
from ftkin.calibration.mount import exp_so3
from ftkin.exceptions import UnobservableParameters

G = 9.80665
IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()  # R_SI
TOOL = SensorModel.from_tool(
    15.0 / G, [0.03, -0.02, 0.08], [2.0, -1.5, 3.0], [0.10, -0.05, 0.02], base_tilt=[0.005, -0.003]
)
NINE_NOISE = np.array([0.02] * 3 + [0.05] * 3 + [0.003] * 3)
WRENCH_NOISE = np.array([0.05] * 3 + [0.003] * 3)


def check_jacobian_finite_diff(prediction, jacobian, x, step=1e-6, rtol=1e-6):
    """``jacobian(x)`` against central differences of ``prediction`` (pink's
    ``check_jacobian_finite_diff``): each column within ``rtol`` of the largest entry."""
    x = np.asarray(x, dtype=float)
    analytic = jacobian(x)
    numeric = np.empty_like(analytic)
    for i in range(len(x)):
        offset = np.zeros(len(x))
        offset[i] = step
        numeric[:, i] = (prediction(x + offset) - prediction(x - offset)) / (2.0 * step)
    np.testing.assert_allclose(analytic, numeric, rtol=0.0, atol=rtol * np.abs(numeric).max())


# ----------------------------------------------------------------------------- the problems
def _static(mode, rng):
    """The ``ml`` fit's problem (with a mount increment away from zero for yaw and full)."""
    rotations = Rotation.random(12, random_state=3).as_matrix()
    problem = WeightedProblem(
        rotations,
        TOOL.predict(rotations) + 0.1,
        np.arange(1.0, 13.0),
        WRENCH_NOISE,
        exp_so3([0.05, -0.03, 0.6]),
        mode,
    )
    x = np.concatenate([TOOL.to_vector(), rng.normal(0.0, 0.3, problem.parameter_count - 12)])

    def prediction(x):
        return ((problem.wrenches - problem.residuals(x)) * problem.weights).ravel()

    return prediction, problem.whitened_jacobian, x


def _imu_static(rng):
    """The IMU fit's problem at a point away from its recentred zero."""
    count = 6
    accel = rng.normal(0.0, 5.0, (count, 3))
    problem = ImuStaticProblem(
        accel,
        rng.normal(0.0, 5.0, (count, 6)),
        np.full(count, 3.0),
        NINE_NOISE,
        G,
        IMU_ROTATION,
        accel / np.linalg.norm(accel, axis=1)[:, None],
        rotation_free=True,
        scale_free=(0, 1, 2),
    )
    x = np.concatenate(
        [
            [2.0, -1.5, 3.0, 0.10, -0.05, 0.02],
            [1.7, 0.01, -0.02, 0.08],
            [0.3, -0.2, 0.1],  # δ
            [0.76, -0.30, 0.20],  # b
            [0.005, -0.003, 0.002],  # s
            rng.normal(0.0, 0.05, 2 * count),  # e
        ]
    )
    return lambda x: (problem.predict(x) * problem.weights).ravel(), problem.whitened_jacobian, x


def _fused(mode, free, scale, rng):
    count = 7
    problem = FusedStaticProblem(
        Rotation.random(count, random_state=5).as_matrix(),
        rng.normal(0, 5, (count, 3)),
        rng.normal(0, 5, (count, 6)),
        np.full(count, 10.0),
        NINE_NOISE,
        G,
        Rotation.random(random_state=6).as_matrix(),
        IMU_ROTATION,
        mode,
        free,
        scale,
    )
    x = rng.normal(0, 0.1, problem.parameter_count)
    x[0:3] = [0.3, -0.2, -14.0]  # a [N]
    return lambda x: (problem.predict(x) * problem.weights).ravel(), problem.whitened_jacobian, x


THETA = np.array([1.5, 0.009, -0.018, 0.108, 0.0137, 2e-4, 0.0129, 1e-4, 2e-3, 2.8e-3])
"""A consistent body: mass [kg], first moment [kg·m], inertia about the sensor [kg·m²]."""


def _dynamic(free, phi, rng):
    count = 40
    problem = DynamicProblem(
        rng.normal(0.0, 5.0, (count, 6)),
        Rotation.random(count, random_state=8).as_matrix(),
        rng.normal(0.0, 0.5, (count, 6, 10)),
        WRENCH_NOISE,
        G,
        free,
    )
    x = np.concatenate([[2.0, -1.5, 3.0, 0.1, -0.05, 0.02, 0.02, -0.01], THETA[list(free)]])
    if phi:
        from ftkin.calibration.log_cholesky import log_cholesky_from_parameters

        x = np.concatenate([x[:8], log_cholesky_from_parameters(THETA)])

    def prediction(x):
        return (problem.predict(dynamic_theta_space(x) if phi else x) / WRENCH_NOISE).ravel()

    return prediction, lambda x: problem.whitened_jacobian(x, phi), x


def _imu_dynamic(phi, rng):
    count = 40
    motion = ImuMotion(
        rng.normal(0.0, 5.0, (count, 6)),
        rng.normal(0.0, 5.0, (count, 3)),
        rng.normal(0.0, 2.0, (count, 3)),
        rng.normal(0.0, 10.0, (count, 3)),
    )
    problem = ImuDynamicProblem(motion, WRENCH_NOISE, IMU_ROTATION, np.zeros(3), True, True)
    body = THETA
    if phi:
        from ftkin.calibration.log_cholesky import log_cholesky_from_parameters

        body = log_cholesky_from_parameters(THETA)
    x = np.concatenate(
        [[2.0, -1.5, 3.0, 0.10, -0.05, 0.02], body, [0.2, -0.1, 0.3], [0.021, -0.012, 0.027]]
    )

    def prediction(x):
        return (problem.predict(x, phi) / WRENCH_NOISE).ravel()

    return prediction, lambda x: problem.whitened_jacobian(x, phi), x


PROBLEMS = {
    "ml": lambda rng: _static("none", rng),
    "ml-mount-yaw": lambda rng: _static("yaw", rng),
    "ml-mount-full": lambda rng: _static("full", rng),
    "imu": _imu_static,
    "fused": lambda rng: _fused("none", True, (), rng),
    "fused-mount-yaw": lambda rng: _fused("yaw", False, (0, 2), rng),
    "fused-mount-full": lambda rng: _fused("full", True, (0, 1, 2), rng),
    "dynamic": lambda rng: _dynamic(ALL_INDICES, False, rng),
    "dynamic-static": lambda rng: _dynamic(STATIC_INDICES, False, rng),
    "dynamic-log-cholesky": lambda rng: _dynamic(ALL_INDICES, True, rng),
    "imu-dynamic": lambda rng: _imu_dynamic(False, rng),
    "imu-dynamic-log-cholesky": lambda rng: _imu_dynamic(True, rng),
}


@pytest.mark.parametrize("name", PROBLEMS)
def test_whitened_jacobian_is_the_derivative_of_the_whitened_prediction(name, rng):
    """One sign everywhere: ``whitened_jacobian`` is ``∂(prediction · w)/∂x`` (the dynamic fits'
    were the residuals', the opposite sign), checked column by column."""
    prediction, jacobian, x = PROBLEMS[name](rng)
    check_jacobian_finite_diff(prediction, jacobian, x)


# ------------------------------------------------------------------- one rule, one threshold
def test_invert_information_matches_numpy_and_refuses_on_both_sides_of_rcond():
    """A well-conditioned matrix inverts to numpy's inverse; a unit-diagonal matrix whose smallest
    eigenvalue is 0.5·RCOND (relative) is refused, one at 2·RCOND is inverted."""
    rng = np.random.default_rng(4)
    basis = np.linalg.qr(rng.normal(size=(4, 4)))[0]
    scale = np.array([1e3, 1.0, 1e-2, 5.0])
    well = basis @ np.diag([4.0, 2.0, 1.0, 0.5]) @ basis.T
    information = well * np.outer(scale, scale)
    np.testing.assert_allclose(
        invert_information(information, "abcd", ""), np.linalg.inv(information), rtol=1e-10
    )
    # a unit diagonal with eigenvalues (2 − ε, ε) on the pair (a, b): exact, by hand
    for factor, singular in ((0.5, True), (2.0, False)):
        epsilon = factor * RCOND * 2.0 / (1.0 + factor * RCOND)  # ε / (2 − ε) = factor · RCOND
        pair = np.array([[1.0, 1.0 - epsilon], [1.0 - epsilon, 1.0]])
        matrix = np.eye(3)
        matrix[:2, :2] = pair
        if singular:
            with pytest.raises(UnobservableParameters) as caught:
                invert_information(matrix, ("a", "b", "c"), "reason")
            assert caught.value.names == ["a", "b"]
            assert dict(caught.value.combination) == pytest.approx({"a": 1.0, "b": -1.0})
        else:
            inverse = invert_information(matrix, ("a", "b", "c"), "reason")
            np.testing.assert_allclose(inverse[:2, :2] @ pair, np.eye(2), atol=1e-3)


@pytest.mark.parametrize("share", [0.25, 0.29, 0.33, 0.35])
def test_named_parameters_around_the_share(share):
    """A null direction ``w = (1, share, 0.05, |k1 + share k2 + 0.05 k3|)`` of a Jacobian with
    unit-norm columns ``Q [k1 k2 k3 k4]`` (k1..k3 orthonormal, ``k4 = −Σ w_i k_i / w_4``): the
    second parameter is named when its share of the largest component is above 0.3, not below;
    the third never. Columns then scaled by (2, 10, 1, 0.5): the names stay, the combination is
    ``w_i / c_i`` in the parameters' own units, the first 1."""
    rng = np.random.default_rng(1)
    frame = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    w4 = np.sqrt(1.0 + share**2 + 0.05**2)
    k4 = -(frame @ [1.0, share, 0.05]) / w4
    unit = np.linalg.qr(rng.normal(size=(20, 3)))[0] @ np.column_stack([frame, k4])
    w = np.array([1.0, share, 0.05, w4])
    columns = np.array([2.0, 10.0, 1.0, 0.5])
    directions = weakest_directions(unit * columns, ("p", "q", "r", "s"))
    assert directions.relative < 1e-12
    named = share > 0.3 * w4
    assert directions.names == (("p", "q", "s") if named else ("p", "s"))
    combination = dict(directions.combination)
    physical = w / columns
    assert combination["p"] == 1.0
    assert combination["s"] == pytest.approx(physical[3] / physical[0], rel=1e-9)
    if named:
        assert combination["q"] == pytest.approx(physical[1] / physical[0], rel=1e-9)
    else:
        assert "q" not in combination


def test_delta_method_and_sensor_axes_by_hand():
    """``f(x) = [x0 x1, x0²]``: its gradient at (2, 3) is [[3, 2], [4, 0]] by hand; a rotation
    increment's covariance turns by ``R C Rᵀ``."""
    covariance = np.array([[0.04, 0.01], [0.01, 0.09]])
    gradient, out = delta_method(
        lambda x: np.array([x[0] * x[1], x[0] ** 2]), [2.0, 3.0], covariance
    )
    hand = np.array([[3.0, 2.0], [4.0, 0.0]])
    np.testing.assert_allclose(gradient, hand, rtol=1e-8)
    np.testing.assert_allclose(out, hand @ covariance @ hand.T, rtol=1e-8)
    rotation = Rotation.from_rotvec([0.1, -0.4, 0.7]).as_matrix()
    block = np.diag([1.0, 2.0, 3.0])
    full = np.eye(5)
    full[1:4, 1:4] = block
    turned = covariance_in_sensor_axes(full, rotation, 1)
    np.testing.assert_allclose(turned[1:4, 1:4], rotation @ block @ rotation.T, atol=1e-15)
    np.testing.assert_array_equal(covariance_in_sensor_axes(full, rotation, None), full)


# ------------------------------------------------------- the same combination, every fit
ANGLES = np.linspace(0.0, 2.0 * np.pi, 10, endpoint=False)
TURNED_ABOUT_X = Rotation.from_rotvec(np.outer(ANGLES, [1.0, 0.0, 0.0])).as_matrix()
"""Sensor orientations ``R_BS`` turned about the base x axis only (the sensor's x along it):
gravity never has a component along sensor x, so the force offset along x cannot be told from
the weight's component along it."""


def _readings(rotations, rng):
    wrenches = TOOL.predict(rotations)
    return np.repeat(wrenches, 5, axis=0) + rng.normal(0.0, 1.0, (5 * len(wrenches), 6)) * [
        0.05,
        0.05,
        0.05,
        0.003,
        0.003,
        0.003,
    ]


def _ml(rng):
    samples = ftkin.Samples.from_rotations(
        np.repeat(TURNED_ABOUT_X, 5, axis=0), _readings(TURNED_ABOUT_X, rng)
    )
    ftkin.calibrate(samples)


def _linear(rng):
    samples = ftkin.Samples.from_rotations(
        np.repeat(TURNED_ABOUT_X, 5, axis=0), _readings(TURNED_ABOUT_X, rng)
    )
    ftkin.calibrate(samples, method="linear")


def _dynamic_static(rng):
    samples = ftkin.Samples.from_rotations(
        np.repeat(TURNED_ABOUT_X, 5, axis=0), _readings(TURNED_ABOUT_X, rng)
    )
    ftkin.calibrate_dynamic(samples, estimate_inertia=False)


def _fused_fit(rng):
    """The orientation and the IMU together (``R_SI = I``): the accelerometer, like the wrench,
    never sees gravity along sensor x."""
    weight_direction = TOOL.gravity_in_base / TOOL.tool_weight
    up = -G * np.einsum("nji,j->ni", TURNED_ABOUT_X, weight_direction)  # specific force [m/s²]
    accel = np.repeat(up, 5, axis=0) + [0.3, -0.2, 0.1] + rng.normal(0.0, 0.02, (5 * len(up), 3))
    samples = ftkin.Samples.from_rotations(
        np.repeat(TURNED_ABOUT_X, 5, axis=0),
        _readings(TURNED_ABOUT_X, rng),
        pose_ids=np.repeat(np.arange(len(up)), 5),
    )
    ftkin.calibrate(FusedSamples.from_arrays(samples, accel))


def _imu(rng):
    """The IMU alone, turned about its own x axis (``R_SI = I``): the accelerometer never sees
    gravity along x, so its x bias trades against the force offset along x (and the torque
    offsets the weight's lever turns it into)."""
    mass, com = 1.7, np.array([0.01, -0.02, 0.08])
    accel, wrenches = [], []
    for rotation in TURNED_ABOUT_X:
        up = rotation.T @ [0.0, 0.0, G]  # specific force at rest, sensor (= IMU) frame
        weight = -mass * up
        accel.append(up + [0.3, -0.2, 0.1] + rng.normal(0.0, 1e-4, (40, 3)))  # [m/s²]
        wrench = np.concatenate([weight, np.cross(com, weight)]) + [2.0, -1.5, 3.0, 0.1, 0, 0]
        wrenches.append(wrench + rng.normal(0.0, 1.0, (40, 6)) * WRENCH_NOISE * 2e-3)
    ids = np.repeat(np.arange(len(TURNED_ABOUT_X)), 40)
    samples = ImuSamples(np.concatenate(accel), np.concatenate(wrenches), ids)
    calibrate_imu(samples, estimate_scale="no")


WEIGHT = TOOL.tool_weight  # [N]
COMBINATIONS = {
    # F_x = a_x + F0_x at every pose: (δa_x, δF0_x) = (1, −1)
    "ml": (_ml, {"gravity_in_base[x]": 1.0, "force_offset[x]": -1.0}),
    "linear": (_linear, {"gravity_in_base[x]": 1.0, "force_offset[x]": -1.0}),
    "fused": (_fused_fit, {"gravity_in_base[x]": 1.0, "force_offset[x]": -1.0}),
    # F_x = F0_x + m g sin V (γ's x component): δV = −δF0_x / (m g), at the check's unit mass
    "dynamic-static": (_dynamic_static, {"force_offset[x]": 1.0, "base_tilt[v]": -1.0 / G}),
    # a_x = g u_x + b_x, F_x = F0_x − m g u_x: δb_x = 1 moves u_x by −1/g and F0_x by −m
    # and M0 absorbs m c × (g δu): δM0_y = c_z δF0_x
    "imu": (_imu, {"force_offset[x]": 1.0, "accel_bias[x]": -1.0 / 1.7, "torque_offset[y]": 0.08}),
}


@pytest.mark.parametrize("name", COMBINATIONS)
def test_every_fit_names_the_same_combination(name, rng):
    """Poses turned about one axis only: each fit refuses them with UnobservableParameters whose
    combination holds the force offset along that axis against the gravity along it, in each
    fit's own parameters (hand-derived, in the comments above)."""
    run, expected = COMBINATIONS[name]
    with pytest.raises(UnobservableParameters) as caught:
        run(rng)
    combination = dict(caught.value.combination)
    first = next(iter(expected))
    scale = combination[first]
    for parameter, value in expected.items():
        assert combination[parameter] / scale == pytest.approx(value, rel=0.02), combination
    assert "the readings stay the same along" in str(caught.value)


def test_linear_starts_recover_a_known_body(rng):
    """Both dynamic fits start by linear least squares of ``[bias, θ]`` where the model is linear
    (zero tilt; the start rotation and position of the IMU). On readings made from a chosen body
    there, the start is that body: the IMU fit's solved the negated system (with the residuals'
    sign) and started from a mass of −1.5 kg for this 1.5 kg tool."""
    from dataclasses import replace

    from ftkin.calibration.dynamic_fit import fit_linear
    from ftkin.calibration.imu_dynamic import _lstsq_start

    bias = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])  # [N, N·m]
    count = 60
    imu = ImuDynamicProblem(
        ImuMotion(
            np.zeros((count, 6)),
            rng.normal(0.0, 5.0, (count, 3)),
            rng.normal(0.0, 2.0, (count, 3)),
            rng.normal(0.0, 10.0, (count, 3)),
        ),
        WRENCH_NOISE,
        IMU_ROTATION,
        np.array([0.021, -0.012, 0.027]),  # [m]
    )
    truth = np.concatenate([bias, THETA, np.zeros(3), imu.position0])
    imu = replace(imu, motion=replace(imu.motion, wrenches=imu.predict(truth)))
    np.testing.assert_allclose(_lstsq_start(imu), truth, rtol=0.0, atol=1e-9)
    joints = DynamicProblem(
        np.zeros((count, 6)),
        Rotation.random(count, random_state=9).as_matrix(),
        rng.normal(0.0, 0.5, (count, 6, 10)),
        WRENCH_NOISE,
        G,
    )
    truth = np.concatenate([bias, [0.0, 0.0], THETA])
    joints = replace(joints, wrenches=joints.predict(truth))
    np.testing.assert_allclose(fit_linear(joints), truth, rtol=0.0, atol=1e-9)
