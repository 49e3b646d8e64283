"""The static calibration from the sensor's IMU: recovery from MuJoCo's own accelerometer, the
sphere constraint on the bias, identifiability, conventions, units and the Jacobian."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftkin
from ftkin.calibration.imu_fit import calibrate_imu
from ftkin.calibration.imu_options import ImuCalibrationOptions
from ftkin.calibration.imu_samples import ImuSamples
from ftkin.calibration.imu_start import sphere_fit
from ftkin.exceptions import InvalidInput, InvalidSamples, SuspectConvention, UnobservableParameters

G = 9.80665
IMU_ROTATION = Rotation.from_euler("xyz", [95.0, 89.0, -175.0], degrees=True).as_matrix()
BIAS = np.array([0.76, -0.30, 0.20])  # [m/s²]
SCALE = np.array([0.005, -0.003, 0.002])
WRENCH_BIAS = np.array([2.0, -1.5, 3.0, 0.10, -0.05, 0.02])
NOISE = np.array([0.05] * 3 + [0.003] * 3)
ACCEL_NOISE = 0.02


def hand_built(rotations_ws, rng, mass=1.7, com=(0.01, -0.02, 0.08), readings=40, bias=BIAS):
    """Static readings from first principles (not ftkin's model): the sensor at orientations
    ``R_WS`` under gravity ``[0, 0, −g]``; the accelerometer reads +g upward in its own axes."""
    com = np.asarray(com)
    accel, wrenches, ids = [], [], []
    for i, rotation in enumerate(rotations_ws):
        up_in_sensor = rotation.T @ np.array([0.0, 0.0, G])  # specific force at rest
        weight = -mass * up_in_sensor  # the tool's weight on the sensor: down
        wrench = np.concatenate([weight, np.cross(com, weight)]) + WRENCH_BIAS
        reading = (1.0 + SCALE) * (IMU_ROTATION.T @ up_in_sensor) + bias
        accel.append(reading + rng.normal(0.0, ACCEL_NOISE, (readings, 3)))
        wrenches.append(wrench + rng.normal(0.0, 1.0, (readings, 6)) * NOISE)
        ids += [i] * readings
    return np.concatenate(accel), np.concatenate(wrenches), np.array(ids)


def rotation_error_deg(estimate, truth) -> float:
    return float(np.rad2deg(np.linalg.norm(Rotation.from_matrix(estimate.T @ truth).as_rotvec())))


@pytest.fixture(scope="module")
def mujoco_static():
    """Twelve static poses of the bundled arm in MuJoCo with its accelerometer on a turned,
    offset site; bias, scale and noise added here."""
    pytest.importorskip("mujoco")
    from ftkin import Arm
    from ftkin.sim.mujoco.imu_recording import MujocoImuRecorder
    from ftkin.sim.mujoco.tool_inertia import ToolInertia

    arm = Arm.default()
    tool = ToolInertia(1.5, [0.006, -0.012, 0.072], np.diag([0.006, 0.005, 0.002]))
    recorder = MujocoImuRecorder(
        imu_rotation=IMU_ROTATION,
        imu_position=[0.021, -0.012, 0.027],
        joint_names=arm.joint_names,
        tool=tool,
    )
    rng = np.random.default_rng(7)
    q = rng.uniform(-2.5, 2.5, (12, arm.nq))
    wrench, accel, _ = recorder.readings(q)
    readings = 100
    ids = np.repeat(np.arange(12), readings)
    accel = (1.0 + SCALE) * accel[ids] + BIAS + rng.normal(0.0, ACCEL_NOISE, (len(ids), 3))
    wrench = wrench[ids] + WRENCH_BIAS + rng.normal(0.0, 1.0, (len(ids), 6)) * NOISE
    truth = recorder.true_parameters()
    return ImuSamples.from_arrays(accel, wrench, ids), truth


def test_recovers_mujoco_truth(mujoco_static):
    samples, truth = mujoco_static
    result = ftkin.calibrate(samples)
    mass, com = truth[0], truth[1:4] / truth[0]
    assert isinstance(result, ftkin.calibration.ImuCalibrationResult)
    assert abs(result.tool_mass - mass) / mass < 1e-3
    np.testing.assert_allclose(result.center_of_mass, com, atol=2e-4)
    np.testing.assert_allclose(result.force_offset, WRENCH_BIAS[:3], atol=0.02)
    np.testing.assert_allclose(result.torque_offset, WRENCH_BIAS[3:], atol=2e-3)
    assert rotation_error_deg(result.imu_rotation, IMU_ROTATION) < 0.1
    np.testing.assert_allclose(result.accel_bias, BIAS, atol=0.01)
    np.testing.assert_allclose(result.accel_scale, SCALE, atol=1e-3)
    assert all(result.scale_estimated)
    # the standard errors describe the errors (within 5σ)
    sigma = result.std_error_of(["accel_bias[x]", "accel_bias[y]", "accel_bias[z]"])
    assert np.all(np.abs(result.accel_bias - BIAS) < 5 * sigma)
    assert 0.5 < result.fit_test.chi_square / result.fit_test.dof < 1.6


def test_the_bias_comes_from_the_sphere_not_the_wrench(rng):
    """The wrench alone cannot tell a bias Δb from an offset m·R·Δb (F = F0 − m R (a − b)): a
    second data set whose forces differ by exactly that keeps the accelerometer's bias (fixed by
    |a − b| = g) and moves F0 by m R Δb instead."""
    rotations = Rotation.random(12, random_state=3).as_matrix()
    accel, wrenches, ids = hand_built(rotations, np.random.default_rng(1))
    first = calibrate_imu(ImuSamples(accel, wrenches, ids))
    shift = np.array([0.4, -0.2, 0.3])  # Δb [m/s²]
    offset = first.tool_mass * IMU_ROTATION @ (shift / (1.0 + SCALE))
    moved = wrenches + np.concatenate([offset, np.zeros(3)])
    second = calibrate_imu(ImuSamples(accel, moved, ids))
    np.testing.assert_allclose(first.accel_bias, BIAS, atol=0.01)
    np.testing.assert_allclose(second.accel_bias, first.accel_bias, atol=1e-6)
    np.testing.assert_allclose(second.force_offset, first.force_offset + offset, atol=1e-5)
    # the sphere holds at the solution: |(a − b) ⊘ (1 + s)| = g at every pose, within the noise
    means = ImuSamples(accel, wrenches, ids).pose_averages().specific_force
    norms = np.linalg.norm((means - first.accel_bias) / (1.0 + first.accel_scale), axis=1)
    np.testing.assert_allclose(norms, G, atol=5 * ACCEL_NOISE / np.sqrt(40))


def test_sphere_fit_exact_points():
    directions = Rotation.random(10, random_state=5).as_matrix()[:, :, 0]
    bias, scale = sphere_fit(1.004 * G * directions + BIAS, G, with_scale=True)
    np.testing.assert_allclose(bias, BIAS, atol=1e-9)
    np.testing.assert_allclose(scale, np.full(3, 0.004), atol=1e-11)  # isotropic: a start
    bias, scale = sphere_fit(G * directions + BIAS, G, with_scale=False)
    np.testing.assert_allclose(bias, BIAS, atol=1e-9)
    np.testing.assert_array_equal(scale, np.zeros(3))


def test_gravity_in_one_imu_plane_leaves_the_bias_open(rng):
    """Turning the tool about the IMU's z axis only keeps gravity in the IMU's x-y plane: the
    z bias then trades against F0 (and the z scale cannot be seen): refused by name."""
    axis = IMU_ROTATION @ np.array([0.0, 0.0, 1.0])  # IMU z in the sensor frame
    start = Rotation.align_vectors([[1.0, 0.0, 0.0]], [axis])[0]  # world x along IMU z
    angles = np.linspace(0.0, 2 * np.pi, 10, endpoint=False)
    rotations = [
        (Rotation.from_rotvec([a, 0.0, 0.0]) * start).as_matrix().T.T for a in angles
    ]  # R_WS: turned about world x, which is the IMU's z axis
    accel, wrenches, ids = hand_built(rotations, rng)
    with pytest.raises(UnobservableParameters) as caught:
        calibrate_imu(ImuSamples(accel, wrenches, ids), estimate_scale="no")
    assert "accel_bias[z]" in caught.value.names
    assert any(name.startswith("force_offset") for name in caught.value.names)
    with pytest.raises(UnobservableParameters, match="accel_bias"):
        calibrate_imu(ImuSamples(accel, wrenches, ids))  # auto: the scale dropped, bias still open


def test_too_few_poses(rng):
    accel, wrenches, ids = hand_built(Rotation.random(3, random_state=2).as_matrix(), rng)
    with pytest.raises(UnobservableParameters, match="at least 4"):
        calibrate_imu(ImuSamples(accel, wrenches, ids))


def test_scale_left_out_with_few_poses_and_when_asked(rng):
    rotations = Rotation.random(6, random_state=4).as_matrix()
    accel, wrenches, ids = hand_built(rotations, rng)
    result = calibrate_imu(ImuSamples(accel, wrenches, ids))
    assert result.scale_estimated == (False, False, False)
    assert any("scale not estimated" in w for w in result.warnings)
    rotations = Rotation.random(12, random_state=4).as_matrix()
    accel, wrenches, ids = hand_built(rotations, rng)
    fixed = calibrate_imu(ImuSamples(accel, wrenches, ids), estimate_scale=False)
    np.testing.assert_array_equal(fixed.accel_scale, np.zeros(3))


def test_given_rotation_is_kept(rng):
    rotations = Rotation.random(12, random_state=6).as_matrix()
    accel, wrenches, ids = hand_built(rotations, rng)
    result = calibrate_imu(ImuSamples(accel, wrenches, ids), imu_rotation=IMU_ROTATION)
    np.testing.assert_allclose(result.imu_rotation, IMU_ROTATION, atol=1e-12)
    assert "imu_rotation[x]" not in result.parameter_names
    assert abs(result.tool_mass - 1.7) < 2e-3
    transposed = IMU_ROTATION @ Rotation.from_euler("x", 180, degrees=True).as_matrix()
    with pytest.raises(SuspectConvention, match="mass"):
        calibrate_imu(ImuSamples(accel, wrenches, ids), imu_rotation=transposed)


def test_a_negated_accelerometer_is_named(rng):
    accel, wrenches, ids = hand_built(Rotation.random(12, random_state=8).as_matrix(), rng)
    with pytest.raises(SuspectConvention, match="specific force"):
        calibrate_imu(ImuSamples(-accel, wrenches, ids))


def test_units_g_and_ms2_give_the_same_fit(rng):
    accel, wrenches, ids = hand_built(Rotation.random(12, random_state=9).as_matrix(), rng)
    in_si = ftkin.calibrate(ImuSamples.from_arrays(accel, wrenches, ids))
    in_g = ftkin.calibrate(ImuSamples.from_arrays(accel / G, wrenches, ids, accel_unit="g"))
    np.testing.assert_allclose(in_g.accel_bias, in_si.accel_bias, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(in_g.tool_mass, in_si.tool_mass, rtol=1e-9)


@pytest.mark.parametrize(
    ("factor", "unit", "message"),
    [
        (1 / G, "m/s^2", "accel_unit='g'"),  # logged in g, read as m/s²
        (1.0, "g", "drop accel_unit='g'"),  # m/s² read as g
        (0.02, "m/s^2", "gravity removed"),  # a linear acceleration
        (3.0, "m/s^2", "another unit"),
    ],
)
def test_wrong_units_are_refused(rng, factor, unit, message):
    accel, wrenches, ids = hand_built(Rotation.random(6, random_state=1).as_matrix(), rng)
    with pytest.raises(InvalidSamples, match=message):
        ImuSamples.from_arrays(accel * factor, wrenches, ids, accel_unit=unit)


def test_bad_inputs(rng):
    accel, wrenches, ids = hand_built(Rotation.random(6, random_state=1).as_matrix(), rng)
    with pytest.raises(InvalidInput, match="unknown accelerometer unit"):
        ImuSamples.from_arrays(accel, wrenches, ids, accel_unit="ft/s^2")
    with pytest.raises(InvalidSamples, match="expected one each"):
        ImuSamples.from_arrays(accel[:-1], wrenches, ids)
    with pytest.raises(InvalidSamples, match="°/s"):
        ImuSamples.from_arrays(accel, wrenches, ids, angular_velocity=np.full((len(ids), 3), 90.0))
    moved = accel.copy()
    moved[ids == 2] = moved[ids == 3][: np.sum(ids == 2)]  # pose 2 half of another pose's
    moved[np.flatnonzero(ids == 2)[:5]] = accel[np.flatnonzero(ids == 2)[:5]]
    with pytest.raises(InvalidSamples, match="pose 2 turns"):
        ImuSamples(moved, wrenches, ids).pose_averages()
    samples = ImuSamples(accel, wrenches, ids)
    with pytest.raises(InvalidInput, match="unknown option"):
        ftkin.calibrate(samples, estimate_mount="full")
    with pytest.raises(InvalidInput, match="not options of a calibration from the IMU"):
        ftkin.calibrate(samples, ftkin.CalibrationOptions(method="linear"))
    with pytest.raises(InvalidInput, match="estimate_scale"):
        ImuCalibrationOptions(estimate_scale="maybe")
    with pytest.raises(InvalidInput, match="millimetres"):
        ImuCalibrationOptions(imu_position=[21.0, -12.0, 27.0])
    with pytest.raises(InvalidInput, match="differs"):
        ftkin.calibrate(samples, g=9.81)
