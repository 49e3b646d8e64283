"""MuJoCo's sensor against ftkin's model (static) and Pinocchio's regressor (in motion)."""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin
import pytest

from ftkin import InvalidInput, SensorModel
from ftkin.kinematics.arm import bundled_urdf_path

mujoco = pytest.importorskip("mujoco")

from ftkin.sim.mujoco import GraspedObject, MujocoSensor, build_arm_model  # noqa: E402

TILT = np.deg2rad([0.8, -0.5])


def _urdf_gripper():
    """Mass [kg], COM [m] and inertia about the COM [kg·m²] of the gripper link, read from the URDF
    text.
    """
    link = next(
        node
        for node in ET.parse(bundled_urdf_path()).getroot().iter("link")
        if node.get("name") == "gripper"
    )
    inertial = link.find("inertial")
    mass = float(inertial.find("mass").get("value"))
    com = np.array([float(x) for x in inertial.find("origin").get("xyz").split()])
    i = {k: float(v) for k, v in inertial.find("inertia").attrib.items()}
    inertia = np.array(
        [
            [i["ixx"], i["ixy"], i["ixz"]],
            [i["ixy"], i["iyy"], i["iyz"]],
            [i["ixz"], i["iyz"], i["izz"]],
        ]
    )
    return mass, com, inertia


@pytest.fixture(scope="module")
def sim(arm):
    return build_arm_model(arm, surfaces=(), surface_under=None, base_tilt=TILT)


def _inverse(sim, q, v, a):
    data = sim.data
    data.qpos[sim._arm_qpos], data.qvel[sim._arm_dof], data.qacc[sim._arm_dof] = q, v, a
    mujoco.mj_inverse(sim.model, data)
    return sim.ideal_wrench_in_sensor()


def test_static_wrench_equals_sensor_model_from_the_urdf(sim, arm):
    mass, com, _ = _urdf_gripper()
    model = SensorModel.from_tool(mass, com, base_tilt=TILT)
    rng = np.random.default_rng(3)
    configurations = arm.random_configurations(20, rng, margin=0.1)
    measured = np.array([_inverse(sim, q, np.zeros(6), np.zeros(6)) for q in configurations])
    expected = model.predict(arm.rotation_sensor_to_base(configurations)).reshape(-1, 6)
    np.testing.assert_allclose(measured, expected, rtol=0, atol=1e-9)
    # the sign: the tool hangs from the sensor, so with the sensor z down the load is +weight along
    # z
    load = _inverse(sim, sim.q0, np.zeros(6), np.zeros(6))
    assert load[2] == pytest.approx(mass * 9.80665, rel=1e-3) and sim.sensor_rotation()[
        2, 2
    ] == pytest.approx(-1.0, abs=1e-9)


def test_moving_wrench_equals_pinocchio_body_regressor(sim, arm):
    mass, com, inertia = _urdf_gripper()
    parameters = pin.Inertia(mass, com, inertia).toDynamicParameters()
    np.testing.assert_allclose(sim.tool_inertia().parameters(), parameters, atol=1e-12)
    gravity = sim.model.opt.gravity.copy()
    model, data, frame = arm.model, arm.data, arm.sensor_frame_id
    rng = np.random.default_rng(4)
    for q in arm.random_configurations(10, rng, margin=0.1):
        v, a = rng.uniform(-2, 2, 6), rng.uniform(-5, 5, 6)
        pin.forwardKinematics(model, data, q, v, a)
        pin.updateFramePlacements(model, data)
        velocity = pin.getFrameVelocity(model, data, frame, pin.LOCAL)
        acceleration = pin.getFrameAcceleration(model, data, frame, pin.LOCAL)
        rotation = data.oMf[frame].rotation
        lifted = pin.Motion(acceleration.linear - rotation.T @ gravity, acceleration.angular)
        on_tool = (
            pin.bodyRegressor(velocity, lifted) @ parameters
        )  # the wrench the sensor exerts on the tool
        np.testing.assert_allclose(_inverse(sim, q, v, a), -on_tool, atol=1e-6)


def test_object_adds_its_weight_and_inertia_excludes_it(arm):
    held = build_arm_model(
        arm, grasped_object=GraspedObject(mass=0.5), surfaces=(), surface_under=None
    )
    bare = build_arm_model(arm, surfaces=(), surface_under=None)
    for sim in (held, bare):
        sim.data.qvel[:] = 0
        _inverse(sim, sim.q0, np.zeros(6), np.zeros(6))
    difference = held.ideal_wrench_in_sensor() - bare.ideal_wrench_in_sensor()
    assert difference[2] == pytest.approx(0.5 * 9.80665, rel=1e-9)
    assert held.tool_inertia().mass == pytest.approx(bare.tool_inertia().mass)


def test_sensor_bias_noise_saturation_and_delay():
    ideal = [np.array([1.0, 2, 3, 0.1, 0.2, 0.3]) * k for k in range(1, 6)]
    sensor = MujocoSensor(bias=[1, 0, 0, 0, 0, 0], force_range=10.0, delay_ticks=1)
    out = [sensor.read(w, 1e-3) for w in ideal]
    np.testing.assert_allclose(out[0], ideal[0] + [1, 0, 0, 0, 0, 0])  # nothing older yet
    np.testing.assert_allclose(out[2], ideal[1] + [1, 0, 0, 0, 0, 0])  # one tick late
    assert out[4][2] == 10.0  # ideal[3] has fz = 12: clipped to the range
    slow = MujocoSensor(sample_rate=250.0, delay_ticks=0)
    readings = [slow.read(w, 1e-3)[0] for w in ideal]
    assert readings == [1.0, 1.0, 1.0, 1.0, 5.0]  # a new sample every 4 ms, held in between
    noisy = MujocoSensor(
        noise=pytest.importorskip("ftkin").SensorNoise(0.5, 0.01), delay_ticks=0, seed=1
    )
    spread = np.std([noisy.read(np.zeros(6), 1e-3)[0] for _ in range(2000)])
    assert spread == pytest.approx(0.5, rel=0.1)


def test_bad_arguments_are_invalid_input(arm):
    with pytest.raises(InvalidInput, match="surface_under"):
        build_arm_model(arm, surface_under="granite")
    with pytest.raises(InvalidInput, match="measured_body"):
        build_arm_model(arm, measured_body="nope")
    with pytest.raises(InvalidInput, match="child link of the sensor"):
        build_arm_model(arm, measured_body="tool")
    with pytest.raises(InvalidInput, match="sample_rate"):
        MujocoSensor(sample_rate=0.0)


def test_without_mujoco_the_error_names_the_extra(monkeypatch, arm):
    import sys

    from ftkin import MissingDependency

    monkeypatch.setitem(sys.modules, "mujoco", None)
    with pytest.raises(MissingDependency, match=r"ftkin\[sim\]"):
        build_arm_model(arm)
