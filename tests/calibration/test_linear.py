"""The paper's two-step linear calibration: synthetic round trips and refusals."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin import Samples, calibrate
from ftkin.calibration.information import (
    SensorNoise,
    covariance_from_information,
    fisher_information,
    standard_errors,
)
from ftkin.sim.sensor import SimulatedSensor

TOOL_DOWN = np.array([0.0, 0.0, -0.5236, 0.0, -1.0472, 0.0])


def _noise_free_samples(arm, truth, configurations):
    """Joint angles → FK → exact readings (independent of the simulator's noise path)."""
    rotations = arm.rotation_sensor_to_base(configurations)
    return Samples.from_joint_positions(arm, configurations, truth.predict(rotations))


def _rotation_about(axis, angle):
    axis = np.asarray(axis, dtype=float)
    return Rotation.from_rotvec(axis / np.linalg.norm(axis) * angle).as_matrix()


def test_noise_free_round_trip_recovers_truth(arm, rng, truth):
    configurations = arm.random_configurations(10, rng, margin=0.3)
    result = calibrate(_noise_free_samples(arm, truth, configurations), method="linear")
    np.testing.assert_allclose(result.to_vector(), truth.to_vector(), atol=1e-9)
    assert result.tool_weight == pytest.approx(truth.tool_weight, abs=1e-9)
    assert result.tool_mass == pytest.approx(truth.tool_mass, abs=1e-9)
    np.testing.assert_allclose(result.base_tilt, truth.base_tilt, atol=1e-9)
    np.testing.assert_allclose(result.residuals, 0.0, atol=1e-9)
    assert result.method == "linear"
    assert result.pose_count == 10 and result.sample_count == 10
    assert result.urdf == str(arm.urdf_path) and result.sensor_frame == "ft_sensor"


def test_noise_free_round_trip_with_simulated_sensor(arm, rng, truth):
    # the simulator with negligible noise, several readings per pose
    sensor = SimulatedSensor(truth, SensorNoise(1e-13, 1e-13))
    configurations = arm.random_configurations(6, rng, margin=0.3)
    samples = sensor.samples_at_configurations(arm, configurations, rng, readings_per_pose=3)
    result = calibrate(samples, method="linear")
    assert result.pose_count == 6 and result.sample_count == 18
    np.testing.assert_allclose(result.to_vector(), truth.to_vector(), atol=1e-9)


def test_noisy_round_trip_within_standard_errors(arm, rng, truth):
    noise = SensorNoise.paper()
    readings = 200
    configurations = arm.random_configurations(12, rng, margin=0.3)
    samples = SimulatedSensor(truth, noise).samples_at_configurations(
        arm, configurations, rng, readings
    )
    result = calibrate(samples, method="linear")
    rotations = arm.rotation_sensor_to_base(configurations)
    covariance = covariance_from_information(fisher_information(truth, rotations, noise, readings))
    errors = standard_errors(truth, covariance)
    # the two-step estimator is a little less efficient than the Cramér-Rao bound: allow 5 sigma
    for name in ("gravity_in_base", "force_offset", "torque_offset", "center_of_mass"):
        deviation = np.abs(getattr(result, name) - getattr(truth, name))
        assert np.all(deviation < 5 * errors[name]), (name, deviation / errors[name])
    assert abs(result.tool_weight - truth.tool_weight) < 5 * errors["tool_weight"]
    assert np.all(np.abs(np.subtract(result.base_tilt, truth.base_tilt)) < 5 * errors["base_tilt"])
    # and the noise is real: not recovered exactly
    assert np.abs(result.to_vector() - truth.to_vector()).max() > 1e-7
    # per-pose residuals are at the level of the averaged noise
    assert np.all(result.residual_rms < 5 * noise.channel_std / np.sqrt(readings))


def test_paper_euler_orientations_round_trip(truth):
    angles = np.array(
        [
            [90, 0, -180],
            [64.4, -0.7, -160.4],
            [86.6, -13.5, -165.7],
            [114.5, 6.3, 158.4],
            [76.7, -21.1, 171.3],
        ]
    )
    samples = Samples.from_euler_zyx_deg(
        angles, truth.predict(ftkin.kinematics.euler_zyx_deg_to_matrix(angles))
    )
    result = calibrate(samples, method="linear")
    np.testing.assert_allclose(result.to_vector(), truth.to_vector(), atol=1e-9)


# ----------------------------------------------------------------- refusals
def test_fewer_than_three_poses_refused(arm, truth):
    configurations = np.array([TOOL_DOWN, TOOL_DOWN + 0.4])
    with pytest.raises(
        ftkin.UnobservableParameters, match="only 2 distinct pose.*at least 3"
    ) as info:
        calibrate(_noise_free_samples(arm, truth, configurations), method="linear")
    assert set(info.value.names) == {
        "gravity_in_base",
        "force_offset",
        "torque_offset",
        "center_of_mass",
    }


def test_many_readings_of_two_poses_still_refused(arm, rng, truth):
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    samples = sensor.samples_at_configurations(arm, np.array([TOOL_DOWN, TOOL_DOWN + 0.4]), rng, 50)
    with pytest.raises(ftkin.UnobservableParameters, match="only 2 distinct"):
        calibrate(samples, method="linear")


def test_identical_orientations_refused(truth):
    rotations = np.repeat(
        ftkin.kinematics.euler_zyx_deg_to_matrix([[90.0, 0.0, -180.0]]), 5, axis=0
    )
    samples = Samples.from_rotations(rotations, truth.predict(rotations))
    with pytest.raises(ftkin.UnobservableParameters, match="orientations are all alike") as info:
        calibrate(samples, method="linear")
    assert set(info.value.names) == {"gravity_in_base", "force_offset"}
    assert info.value.singular_values is not None and info.value.singular_values[-1] < 1e-3


def test_orientations_differing_only_about_vertical_refused(truth):
    base = ftkin.kinematics.euler_zyx_deg_to_matrix([10.0, 25.0, -150.0])
    rotations = np.array(
        [_rotation_about([0, 0, 1], angle) @ base for angle in np.linspace(0, 5, 8)]
    )
    samples = Samples.from_rotations(rotations, truth.predict(rotations))
    with pytest.raises(ftkin.UnobservableParameters, match="about one axis") as info:
        calibrate(samples, method="linear")
    assert set(info.value.names) == {"gravity_in_base", "force_offset"}


def test_gravity_along_one_sensor_direction_refused(truth):
    # R_i = R0 · Rot(R0ᵀ ĝ, θ_i): gravity in the sensor frame R_iᵀ ĝ is the same in every pose
    gravity_direction = truth.gravity_in_base / truth.tool_weight
    base = ftkin.kinematics.euler_zyx_deg_to_matrix([30.0, -40.0, 120.0])
    rotations = np.array(
        [
            base @ _rotation_about(base.T @ gravity_direction, angle)
            for angle in np.linspace(0, 6, 7)
        ]
    )
    seen = np.einsum("nji,j->ni", rotations, gravity_direction)
    np.testing.assert_allclose(seen, np.broadcast_to(seen[0], seen.shape), atol=1e-14)
    samples = Samples.from_rotations(rotations, truth.predict(rotations))
    with pytest.raises(ftkin.UnobservableParameters, match="cannot determine.*gravity_in_base"):
        calibrate(samples, method="linear")


def test_two_gravity_directions_refused_naming_center_of_mass(truth):
    # two families of poses, each turning about gravity: the force step is determined,
    # but gravity is seen along only two sensor directions, so P along their difference is not
    gravity_direction = truth.gravity_in_base / truth.tool_weight
    rotations = []
    for angles in ([0.0, 0.0, 180.0], [0.0, 60.0, 180.0]):
        family_base = ftkin.kinematics.euler_zyx_deg_to_matrix(angles)
        for angle in (0.0, 1.5, 3.0):
            rotations.append(_rotation_about(gravity_direction, angle) @ family_base)
    rotations = np.array(rotations)
    seen = np.einsum("nji,j->ni", rotations, gravity_direction)
    assert len(np.unique(np.round(seen, 9), axis=0)) == 2
    samples = Samples.from_rotations(rotations, truth.predict(rotations))
    with pytest.raises(
        ftkin.UnobservableParameters, match="gravity is seen along one sensor direction"
    ) as info:
        calibrate(samples, method="linear")
    assert "center_of_mass" in info.value.names
    assert "gravity_in_base" not in info.value.names


def test_three_gravity_directions_accepted(truth):
    rotations = ftkin.kinematics.euler_zyx_deg_to_matrix(
        [[0.0, 0.0, 180.0], [0.0, 60.0, 180.0], [0.0, 0.0, 120.0]]
    )
    result = calibrate(Samples.from_rotations(rotations, truth.predict(rotations)), method="linear")
    np.testing.assert_allclose(result.to_vector(), truth.to_vector(), atol=1e-9)


# --------------------------------------------------------- grouping and g
def test_pose_grouping_equals_averaging_by_hand(arm, rng, truth):
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    configurations = arm.random_configurations(5, rng, margin=0.3)
    rotations = arm.rotation_sensor_to_base(configurations)
    # interleaved, unsorted pose ids with different counts per pose
    pose_ids = np.array([7, 3, 7, 11, 3, 2, 5, 7, 11, 2, 5, 5, 3, 7])
    index_of = {pose: i for i, pose in enumerate([7, 3, 11, 2, 5])}
    per_reading = rotations[[index_of[p] for p in pose_ids]]
    raw = sensor.read(per_reading, rng)
    grouped = calibrate(Samples.from_rotations(per_reading, raw, pose_ids), method="linear")

    means = np.array([raw[pose_ids == pose].mean(axis=0) for pose in index_of])
    by_hand = calibrate(Samples.from_rotations(rotations, means), method="linear")

    np.testing.assert_allclose(grouped.to_vector(), by_hand.to_vector(), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(grouped.pose_ids, list(index_of))
    np.testing.assert_allclose(grouped.pose_wrenches, means, atol=1e-14)
    np.testing.assert_allclose(grouped.residuals, by_hand.residuals, atol=1e-12)
    assert grouped.sample_count == len(pose_ids) and grouped.pose_count == 5


def test_g_override_changes_only_tool_mass(arm, rng, truth):
    sensor = SimulatedSensor(truth, SensorNoise.paper())
    samples = sensor.samples_at_configurations(
        arm, arm.random_configurations(6, rng, margin=0.3), rng, 5
    )
    standard = calibrate(samples, method="linear")
    paper_g = calibrate(samples, method="linear", g=9.8)
    assert standard.g == ftkin.calibration.STANDARD_GRAVITY and paper_g.g == 9.8
    for name in ("force_offset", "torque_offset", "gravity_in_base", "center_of_mass", "residuals"):
        np.testing.assert_allclose(
            getattr(standard, name), getattr(paper_g, name), rtol=1e-12, atol=1e-15
        )
    assert standard.tool_weight == pytest.approx(paper_g.tool_weight, rel=1e-12)
    np.testing.assert_allclose(standard.base_tilt, paper_g.base_tilt, rtol=1e-12, atol=1e-15)
    assert paper_g.tool_mass == pytest.approx(standard.tool_weight / 9.8, rel=1e-15)
    assert standard.tool_mass == pytest.approx(standard.tool_weight / 9.80665, rel=1e-15)


def test_result_is_frozen(arm, rng, truth):
    result = calibrate(
        _noise_free_samples(arm, truth, arm.random_configurations(4, rng, margin=0.3)),
        method="linear",
    )
    with pytest.raises(AttributeError):
        result.g = 1.0
    with pytest.raises(ValueError):
        result.force_offset[0] = 1.0


@pytest.mark.parametrize(
    ("kwargs", "pattern"),
    [
        (
            {"method": "nonlinear-magic"},
            "unknown calibration method 'nonlinear-magic'; expected one of.*linear",
        ),
        ({"method": "linear", "g": 0.0}, "g must be a finite positive number"),
        ({"method": "linear", "g": float("nan")}, "g must be a finite positive number"),
    ],
)
def test_bad_calibrate_arguments(arm, rng, truth, kwargs, pattern):
    samples = _noise_free_samples(arm, truth, arm.random_configurations(4, rng, margin=0.3))
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        calibrate(samples, **kwargs)


def test_calibrate_needs_samples():
    with pytest.raises(ftkin.InvalidInput, match="samples must be an ftkin.Samples, got ndarray"):
        calibrate(np.zeros((5, 6)), method="linear")


@pytest.mark.parametrize(
    ("build", "pattern"),
    [
        (lambda r: Samples(np.zeros((3, 6)), r[:2]), "3 wrenches but 2 orientations"),
        (lambda r: Samples(np.zeros((3, 5)), r), r"wrenches .* must have shape \(6,\) or \(N, 6\)"),
        (lambda r: Samples(np.zeros((0, 6)), r[:0]), "no samples"),
        (
            lambda r: Samples(np.zeros((3, 6)), r, pose_ids=[1, 2]),
            r"pose_ids must have shape \(3,\)",
        ),
        (
            lambda r: Samples(np.zeros((3, 6)), r, pose_ids=[1.0, 2.5, 3.0]),
            "pose ids must be integers",
        ),
        (lambda r: Samples(np.full((3, 6), np.nan), r), "finite"),
        (
            lambda r: Samples(np.zeros((3, 6)), 2 * r),
            r"rotation_sensor_to_base\[0\] is not a rotation matrix",
        ),
    ],
)
def test_bad_samples_are_refused(build, pattern):
    rotations = ftkin.kinematics.euler_zyx_deg_to_matrix([[0, 0, 180], [0, 60, 180], [0, 0, 120]])
    with pytest.raises(ftkin.InvalidInput, match=pattern):
        build(rotations)


def test_a_pose_id_grouping_different_orientations_is_refused(arm, rng):
    from ftkin import InvalidSamples, Samples

    q = arm.random_configurations(4, rng, margin=0.3)
    wrenches = np.zeros((4, 6))
    with pytest.raises(InvalidSamples, match="differ in orientation by up to"):
        Samples.from_joint_positions(arm, q, wrenches, pose_ids=[0, 0, 1, 1]).pose_averages()
    # encoder jitter within a pose is fine
    jitter = np.repeat(q[:2], 2, axis=0) + rng.normal(0, 1e-4, (4, arm.nq))
    assert (
        len(
            Samples.from_joint_positions(
                arm, jitter, wrenches, pose_ids=[0, 0, 1, 1]
            ).pose_averages()
        )
        == 2
    )
