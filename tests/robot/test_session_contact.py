"""Issue 37, item 10: a robot session must not calibrate on a pose in contact.

Two causes, two defences. The planner kept no clearance between the URDF's triangle meshes, and
franky-sim's MuJoCo (its own meshes, collided as convex hulls) had link 5 in link 7 at a planned
pose: plans are checked here against MuJoCo's contacts, not ftkin's geometry. A reading taken in
contact (a push, a cable) is caught by the leave-one-out check as the session goes and measured
again; one that stays off stops the session, nothing calibrated or written.
"""

from __future__ import annotations

import logging
import pathlib
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from ftkin import Arm
from ftkin.calibration.information import SensorNoise
from ftkin.cli import main
from ftkin.exceptions import InconsistentPoses, InvalidInput
from ftkin.io.samples_csv import load_samples
from ftkin.robot import Stillness, calibrate_on_robot
from ftkin.robot.session import session_poses
from ftkin.sim.sensor import paper_like_truth
from tests.robot.fakes import FakeRobot

franky_sim = pytest.importorskip("franky_sim", reason="franky-sim is not installed")
FRANKY_URDF = pathlib.Path(franky_sim.__file__).parent / "assets" / "fr3.urdf"
CONTACT = np.array([0.0, 130.0 / np.sqrt(2), -130.0 / np.sqrt(2), 0.0, 0.0, 0.0])  # [N]


@pytest.fixture(scope="module")
def franky_arm():
    return Arm.from_urdf(FRANKY_URDF, "fr3_hand", "fr3_hand_tcp")  # fingers locked


@pytest.fixture(scope="module")
def franky_scene():
    """franky-sim's MuJoCo scene of one FR3 (its MJCF, its meshes), compiled."""
    mujoco = pytest.importorskip("mujoco")
    from franky_sim.mujoco_simulator import MujocoSimulator

    simulator = MujocoSimulator(enable_visualization=False)
    simulator.add_robot()
    return mujoco.MjModel.from_xml_string(ET.tostring(simulator.scene, encoding="unicode"))


def mujoco_contacts(model, configurations) -> list[list[tuple[str, str, float]]]:
    """Contacts between the robot's own bodies in franky-sim's MuJoCo ``model`` (the hand open
    4 cm as the simulator starts it) at each configuration ``(7,)`` [rad]: ``(body, body,
    distance [m])``. Nothing of ftkin's geometry is used."""
    import mujoco

    data = mujoco.MjData(model)

    def address(name: str) -> int:
        return model.jnt_qposadr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_JOINT, name)]

    arm = [address(f"robot0_fr3_joint{i}") for i in range(1, 8)]
    fingers = [address(f"robot0_fr3_finger_joint{i}") for i in (1, 2)]

    def body(geom: int) -> str:
        return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, model.geom_bodyid[geom])

    found = []
    for q in configurations:
        data.qpos[:] = 0.0
        data.qpos[arm], data.qpos[fingers] = q, 0.02
        mujoco.mj_forward(model, data)
        found.append(
            [
                (body(c.geom1), body(c.geom2), float(c.dist))
                for c in data.contact[: data.ncon]
                if "world" not in (body(c.geom1), body(c.geom2))
            ]
        )
    return found


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_planned_session_poses_are_free_in_mujoco(franky_arm, franky_scene, seed):
    """The session's default plan (seed 0 is the issue's: link 5 in link 7 at its 7th pose)."""
    poses = session_poses(franky_arm, 12, seed=seed)
    contacts = mujoco_contacts(franky_scene, poses)
    assert all(not found for found in contacts), [(i, c) for i, c in enumerate(contacts) if c]


class ContactSensor:
    """A tool (the paper's truth) read at the fake robot's pose, with the paper's noise, and
    ``CONTACT`` added on the first ``touched[k]`` visits of planned pose ``k`` of ``poses``."""

    def __init__(self, robot, arm, poses, touched, seed=0):
        self.robot, self.arm, self.truth = robot, arm, paper_like_truth()
        self.poses, self.touched = poses, dict(touched)
        self.rng, self.count = np.random.default_rng(seed), 0
        self.noise = np.repeat(SensorNoise.paper().channel_std[[0, 3]], 3)

    def visits(self, pose: int) -> int:
        return sum(np.allclose(q, self.poses[pose]) for q in self.robot.moves)

    def read(self):
        self.count += 1
        rotation = self.arm.rotation_sensor_to_base(self.robot.q)
        wrench = self.truth.predict(rotation[None])[0] + self.noise * self.rng.standard_normal(6)
        here = [k for k in self.touched if np.allclose(self.robot.q, self.poses[k])]
        if here and self.visits(here[0]) <= self.touched[here[0]]:
            wrench = wrench + CONTACT
        return self.count * 1e-3, wrench


def fake_session(arm, tmp_path, touched, n_poses=8):
    """A fake robot, a sensor touched at ``{pose: visits}``, and the session's keywords."""
    robot = FakeRobot(nq=7)
    robot.q = 0.5 * (arm.lower_limits + arm.upper_limits)
    poses = session_poses(arm, n_poses, seed=0, readings_per_pose=10)
    run = dict(
        poses=poses,
        readings_per_pose=10,
        samples_path=tmp_path / "samples.csv",
        output=tmp_path / "calib.json",
        verify_poses=0,
        stillness=Stillness(window=5, stale_after=5.0),
    )
    return robot, ContactSensor(robot, arm, poses, touched), run


@pytest.mark.parametrize(
    ("pose", "order"),
    [
        (6, [0, 1, 2, 3, 4, 5, 6, 7, 6]),  # checked on arrival: not written, visited again last
        (2, [0, 1, 2, 3, 4, 5, 6, 7, 2]),  # checked once six are in: taken out of the file
    ],
)
def test_a_pose_in_contact_once_is_measured_again(franky_arm, tmp_path, caplog, pose, order):
    robot, sensor, run = fake_session(franky_arm, tmp_path, {pose: 1})
    with caplog.at_level(logging.WARNING, logger="ftkin.robot.session"):
        result = calibrate_on_robot(robot, sensor, franky_arm, **run)
    np.testing.assert_allclose(robot.moves, run["poses"][order])
    assert f"pose {pose}: 130 N" in caplog.text and "measuring it again" in caplog.text
    samples = load_samples(run["samples_path"], franky_arm).samples
    ids, counts = np.unique(samples.pose_ids, return_counts=True)
    np.testing.assert_allclose(ids, np.arange(8), atol=0.5)
    np.testing.assert_allclose(counts, 10, atol=0.5)
    truth = sensor.truth  # the tool the readings were written from, not a fit
    np.testing.assert_allclose(result.tool_weight, truth.tool_weight, rtol=0.01)
    np.testing.assert_allclose(result.center_of_mass, truth.center_of_mass, atol=0.002)


def test_a_pose_that_stays_in_contact_stops_the_session(franky_arm, tmp_path):
    """Pose 6 touched on all three visits: refused, named, nothing written; resumed once the
    contact is gone, the session finishes."""
    robot, sensor, run = fake_session(franky_arm, tmp_path, {6: 3})
    with pytest.raises(InconsistentPoses, match=r"pose\(s\) 6 do not fit") as caught:
        calibrate_on_robot(robot, sensor, franky_arm, **run)
    assert caught.value.pose_ids == [6] and "130 N" in str(caught.value)
    assert not run["output"].exists()
    recorded = np.unique(load_samples(run["samples_path"], franky_arm).samples.pose_ids)
    np.testing.assert_allclose(recorded, [0, 1, 2, 3, 4, 5, 7], atol=0.5)
    sensor.touched = {}
    result = calibrate_on_robot(robot, sensor, franky_arm, **{**run, "resume": True})
    np.testing.assert_allclose(result.tool_weight, sensor.truth.tool_weight, rtol=0.01)
    assert run["output"].exists()


def test_remeasure_is_checked(franky_arm, tmp_path):
    robot, sensor, run = fake_session(franky_arm, tmp_path, ())
    with pytest.raises(InvalidInput, match="remeasure"):
        calibrate_on_robot(robot, sensor, franky_arm, remeasure=-1, **run)


def test_the_clearance_flag_plans_and_is_checked(capsys):
    argv = ["plan", "--urdf", str(FRANKY_URDF), "--sensor-frame", "fr3_hand", "--n", "6"]
    assert main([*argv, "--clearance", "0.03"]) == 0
    assert "no self-collision (links at least 0.03 m apart)" in capsys.readouterr().out
    assert main([*argv, "--clearance", "-0.01"]) == 2
    assert "--clearance" in capsys.readouterr().err


class _PushedOnce:
    """The robot; after its ``at_move``-th move a push of the tool starts (``sim.push``)."""

    def __init__(self, robot, sim, at_move: int, force, duration: float):
        self.robot, self.sim, self.at_move, self.moves = robot, sim, at_move, 0
        self.force, self.duration = force, duration

    def move_to(self, q, while_moving=None):
        self.moves += 1
        done = self.robot.move_to(q, while_moving)
        if self.moves == self.at_move:
            self.sim.push(self.force, self.duration)
        return done

    def __getattr__(self, name):
        return getattr(self.robot, name)


def test_a_session_on_franky_sim_with_its_own_urdf_catches_a_push(franky_arm, tmp_path, caplog):
    """franky-sim's fr3.urdf, a 0.9 kg tool under the hand, seven planned poses; the tool is
    pushed (30 N for 1 s) as the arm reaches the sixth: that reading is caught, measured again
    after the seventh, and the calibration is MuJoCo's load (hand, fingers and tool: the
    simulation's bodies)."""
    pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
    from ftkin.robot import FrankaRobot, FrankaSim
    from ftkin.robot.franka_sim import SimTool
    from tests.robot.test_franka_sim import LOADED, PLAN, connect

    tool = SimTool(mass=0.9, center_of_mass=(0.01, -0.02, 0.07), inertia=(0.003, 0.003, 0.002))
    with FrankaSim(tool=tool) as sim:
        robot = connect(sim.hostname, realtime=False, speed=0.8, **LOADED)
        assert isinstance(robot, FrankaRobot)
        pushed = _PushedOnce(robot, sim, 6, [0.0, 30.0, 0.0], 1.0)
        with caplog.at_level(logging.WARNING, logger="ftkin.robot.session"):
            result = calibrate_on_robot(
                pushed,
                sim.sensor,
                franky_arm,
                n_poses=7,
                readings_per_pose=30,
                samples_path=tmp_path / "samples.csv",
                output=tmp_path / "calib.json",
                verify_poses=0,
                stillness=Stillness(stale_after=1.0),
                g=sim.truth.g,
                plan_options=PLAN,
            )
        truth = sim.truth  # MuJoCo's subtree mass and centre of mass below the sensor site
    assert "pose 5: " in caplog.text and "measuring it again" in caplog.text
    assert pushed.moves == 8
    np.testing.assert_allclose(result.tool_mass, truth.mass, rtol=0.01)
    assert np.linalg.norm(result.center_of_mass - truth.center_of_mass) < 0.002
    masses = [mass for mass, _ in truth.bodies_in_flange.values()]
    np.testing.assert_allclose(truth.mass, sum(masses) - truth.sensor_mass, rtol=1e-9)
    ids = np.unique(load_samples(tmp_path / "samples.csv", franky_arm).samples.pose_ids)
    np.testing.assert_allclose(ids, np.arange(7), atol=0.5)
