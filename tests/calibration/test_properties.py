"""Property tests (hypothesis) over the core API: finite results or an ftkin error, never garbage.

Random rotations include gravity exactly along a sensor axis (signed axis
permutations), near-identical pose sets, huge and tiny (finite) magnitudes.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

import ftkin
from ftkin.io.calibration_file import load_calibration, save_calibration
from ftkin.kinematics.rotations import (
    euler_zyx_to_matrix,
    gravity_in_base_from_tilt,
    matrix_to_euler_zyx,
    matrix_to_quaternion,
    quaternion_to_matrix,
    tilt_from_gravity_in_base,
)
from ftkin.validation import MAX_WRENCH

SETTINGS = settings(
    max_examples=60,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)

finite = st.floats(min_value=-1e6, max_value=1e6, allow_nan=False, allow_infinity=False)
magnitude = st.sampled_from([1e-9, 1e-3, 1.0, 1e3, 1e6])


@st.composite
def rotations(draw):
    """A rotation: uniform random, or a signed axis permutation (gravity exactly on a sensor
    axis).
    """
    if draw(st.booleans()):
        quaternion = draw(arrays(np.float64, 4, elements=st.floats(-1, 1, allow_nan=False)))
        assume(np.linalg.norm(quaternion) > 1e-3)
        return quaternion_to_matrix(quaternion / np.linalg.norm(quaternion))
    permutation = draw(st.permutations([0, 1, 2]))
    signs = np.array(draw(st.lists(st.sampled_from([-1.0, 1.0]), min_size=3, max_size=3)))
    matrix = np.eye(3)[list(permutation)] * signs[:, None]
    if np.linalg.det(matrix) < 0:
        matrix[2] *= -1
    return matrix


@st.composite
def sensor_models(draw):
    scale = draw(magnitude)
    vector = lambda: np.array(
        draw(st.lists(st.floats(-1, 1, allow_nan=False), min_size=3, max_size=3))
    )  # noqa: E731
    gravity = vector() * scale
    assume(np.linalg.norm(gravity) > 0)
    return ftkin.SensorModel(
        vector() * scale, vector() * scale, gravity, vector() * draw(magnitude)
    )


@SETTINGS
@given(model=sensor_models(), rotation=rotations(), contact=arrays(np.float64, 6, elements=finite))
def test_compensating_a_simulated_reading_returns_the_injected_contact(model, rotation, contact):
    raw = model.predict(rotation) + contact
    if np.abs(raw).max() > MAX_WRENCH:  # refused, as the readers refuse such a reading
        with pytest.raises(ftkin.InvalidInput, match="beyond"):
            ftkin.Compensator(model).compensate_rotation(rotation, raw)
        return
    recovered = ftkin.Compensator(model).compensate_rotation(rotation, raw)
    scale = np.abs(raw).max() + np.abs(model.predict(rotation)).max() + 1.0
    assert np.all(np.isfinite(recovered))
    np.testing.assert_allclose(recovered, contact, atol=1e-12 * scale)


@SETTINGS
@given(angles=arrays(np.float64, 3, elements=st.floats(-np.pi, np.pi, allow_nan=False)))
def test_euler_conversion_round_trip(angles):
    matrix = euler_zyx_to_matrix(angles)
    np.testing.assert_allclose(euler_zyx_to_matrix(matrix_to_euler_zyx(matrix)), matrix, atol=1e-9)


@SETTINGS
@given(rotation=rotations())
def test_quaternion_conversion_is_the_inverse(rotation):
    np.testing.assert_allclose(
        quaternion_to_matrix(matrix_to_quaternion(rotation)), rotation, atol=1e-12
    )


@SETTINGS
@given(
    weight=st.floats(1e-6, 1e4),
    tilt=arrays(np.float64, 2, elements=st.floats(-1.5, 1.5, allow_nan=False)),
)
def test_tilt_conversion_is_the_inverse(weight, tilt):
    gravity = gravity_in_base_from_tilt(weight, *tilt)
    np.testing.assert_allclose(tilt_from_gravity_in_base(gravity), tilt, atol=1e-9)


@st.composite
def pose_sets(draw):
    """Pose sets from well spread to degenerate: repeated, near-identical, yaw-only."""
    count = draw(st.integers(1, 8))
    base = draw(rotations())
    kind = draw(st.sampled_from(["random", "repeated", "near", "yaw"]))
    if kind == "random":
        return np.array([draw(rotations()) for _ in range(count)])
    if kind == "repeated":
        return np.repeat(base[None], count, axis=0)
    if kind == "near":
        epsilon = draw(st.sampled_from([1e-12, 1e-8, 1e-5, 1e-3]))
        return np.array([euler_zyx_to_matrix(np.full(3, epsilon * i)) @ base for i in range(count)])
    return np.array([euler_zyx_to_matrix([0.7 * i, 0, 0]) @ base for i in range(count)])


@SETTINGS
@given(
    model=sensor_models(),
    poses=pose_sets(),
    method=st.sampled_from(list(ftkin.calibration.METHODS)),
)
def test_calibration_is_finite_or_an_ftkin_error(model, poses, method):
    try:  # readings beyond ±1e6 N are refused when the samples are made
        samples = ftkin.Samples.from_rotations(poses, model.predict(poses).reshape(-1, 6))
        result = ftkin.calibrate(samples, method=method)
    except ftkin.FtkinError:
        return
    for value in (
        result.force_offset,
        result.torque_offset,
        result.gravity_in_base,
        result.center_of_mass,
        result.residuals,
    ):
        assert np.all(np.isfinite(value))
    assert np.isfinite(result.tool_weight) and all(np.isfinite(result.base_tilt))


def _spread_poses(rng, count=8):
    return quaternion_to_matrix(rng.standard_normal((count, 4)) / 1.0)


@SETTINGS
@given(seed=st.integers(0, 2**32 - 1), method=st.sampled_from(list(ftkin.calibration.METHODS)))
def test_calibrate_save_load_compensate_gives_the_same_numbers(seed, method, tmp_path_factory):
    rng = np.random.default_rng(seed)
    quats = rng.standard_normal((8, 4))
    poses = quaternion_to_matrix(quats / np.linalg.norm(quats, axis=1, keepdims=True))
    truth = ftkin.sim.sensor.paper_like_truth()
    sensor = ftkin.SimulatedSensor(truth, ftkin.SensorNoise.paper())
    result = ftkin.calibrate(sensor.samples(poses, rng, readings_per_pose=3), method=method)
    path = tmp_path_factory.mktemp("calib") / "calib.json"
    save_calibration(result, path)
    loaded = load_calibration(path)
    raws = sensor.read(poses, rng)
    in_memory = ftkin.Compensator(result).compensate_batch(poses, raws)
    from_file = ftkin.Compensator(loaded).compensate_batch(poses, raws)
    np.testing.assert_allclose(in_memory, from_file, rtol=1e-12, atol=1e-12)
    for name in ("force_offset", "torque_offset", "gravity_in_base", "center_of_mass"):
        # the file holds the shortest repr of each float: these read back exactly
        np.testing.assert_array_equal(getattr(result, name), getattr(loaded, name))


@pytest.fixture(scope="module")
def bundled_arm():
    return ftkin.Arm.default()


@SETTINGS
@given(
    q=arrays(np.float64, 6, elements=st.floats(-3.0, 3.0, allow_nan=False)),
    singular=st.sampled_from([None, 4, 2]),
)
def test_kinematics_finite_at_and_near_singularities(bundled_arm, q, singular):
    if singular is not None:
        q = q.copy()
        q[singular] = 0.0  # joint5 = 0: wrist singularity; joint3 = 0: elbow stretched
    rotation = bundled_arm.rotation_sensor_to_base(q)
    np.testing.assert_allclose(rotation.T @ rotation, np.eye(3), atol=1e-12)
    assert np.all(np.isfinite(bundled_arm.jacobian(q, "tool")))


@SETTINGS
@given(bad=st.sampled_from([np.nan, np.inf, -np.inf]), index=st.integers(0, 5))
def test_non_finite_readings_are_refused(bundled_arm, bad, index):
    compensator = ftkin.Compensator(ftkin.sim.sensor.paper_like_truth(), bundled_arm)
    raw = np.zeros(6)
    raw[index] = bad
    with pytest.raises(ftkin.InvalidInput, match="finite"):
        compensator.compensate(np.zeros(6), raw)
    with pytest.raises(ftkin.InvalidInput, match="finite"):
        compensator.compensate_batch(np.eye(3)[None], raw[None])
