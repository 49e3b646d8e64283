"""The load in the hand, from the tracker to franky-sim's controller (issue 39), end to end.

One simulated FR3 (franky-sim, through franky as a real robot) with a tool and a place below the
hand for an object whose mass MuJoCo changes while the server runs. The truth is MuJoCo's own
bodies (``body_mass``; ``xipos`` in the flange ``fr3_link8`` through MuJoCo's ``xpos``/``xmat``,
:attr:`~ftkin.robot.franka_sim.SimTruth.bodies_in_flange`); the calibration is the simulated
tool's (its mass, centre of mass and bias as MuJoCo holds them), so what is tested is the load's
identification and its hand-off, not the calibration.
"""

from __future__ import annotations

import contextlib
import gc
import shlex
import threading
import time

import numpy as np
import pytest

pytest.importorskip("franky", reason="franky-control is not installed (extra 'franka')")
pytest.importorskip("franky_sim", reason="franky-sim is not installed (extra 'franka-sim')")

from ftkin.calibration.information import SensorNoise  # noqa: E402
from ftkin.calibration.model import SensorModel  # noqa: E402
from ftkin.calibration.result import CalibrationResult  # noqa: E402
from ftkin.cli import main  # noqa: E402
from ftkin.control import Compensator, LoadTracker  # noqa: E402
from ftkin.io.calibration_file import save_calibration  # noqa: E402
from ftkin.kinematics.fr3 import fr3_arm  # noqa: E402
from ftkin.robot import FrankaRobot, FrankaSim, SimHeld  # noqa: E402
from ftkin.robot.franka_sim import HELD_BODY  # noqa: E402
from ftkin.robot.load_handoff import MotionFlag  # noqa: E402

HELD_MASS = 0.45  # [kg]
WRIST_TURN = np.array([0.0, 0.0, 0.0, 0.0, 0.6, -1.0, 0.0])  # joints 5 and 6 [rad]
NOISE = SensorNoise(0.02, 0.001)  # the simulated sensor's (SimSensorSpec.noise_std)
# franky-sim's arm, holding a load its controller does not model, vibrates: the contact wobbles
# by 0.3 N (std, 1 s after a 0.45 kg grasp; up to 1.8 N just after it). A floor of the model
# [N, N·m], so that the vibration is not taken for a contact (it averages out of the mass)
MODEL_FLOOR = [0.3, 0.3, 0.3, 0.03, 0.03, 0.03]


@pytest.fixture(scope="module")
def sim():
    with FrankaSim(held=SimHeld()) as simulation:
        yield simulation


@contextlib.contextmanager
def connected(sim):
    """A FrankaRobot on ``sim``, dropped at the end: franky-sim serves one client at a time (the
    CLI's is another). A busy machine: libfranka's first attempt may time out."""
    for attempt in range(3):
        try:
            robot = FrankaRobot(sim.hostname, realtime=False, state_timeout=1.0)
            break
        except Exception:
            if attempt == 2:
                raise
            time.sleep(1.0)
    try:
        yield robot
    finally:
        del robot
        gc.collect()


@pytest.fixture
def robot(sim):
    with connected(sim) as robot:
        yield robot


@pytest.fixture(scope="module")
def calibration(sim):
    truth = sim.truth
    return SensorModel.from_tool(
        truth.mass, truth.center_of_mass, truth.bias[:3], truth.bias[3:], g=truth.g
    )


def expected_load(truth, end_effector, held_mass: float) -> tuple[float, np.ndarray]:
    """The controller's load from MuJoCo's bodies in fr3_link8 (sensor body, hand, fingers,
    tool, the held object with ``held_mass``) minus the end effector the robot reports."""
    bodies = dict(truth.bodies_in_flange)
    bodies[HELD_BODY] = (held_mass, bodies[HELD_BODY][1])
    masses = np.array([mass for mass, _ in bodies.values()])
    moments = np.array([mass * com for mass, com in bodies.values()])
    mass = masses.sum() - end_effector.mass
    return mass, (moments.sum(axis=0) - end_effector.mass * end_effector.center_of_mass) / mass


class Tracking:
    """The tracker fed with every new sample of the simulated sensor (its stamps as time)."""

    def __init__(self, sim, robot, calibration):
        self.sim, self.robot, self.arm = sim, robot, fr3_arm()
        self.compensator = Compensator(calibration, self.arm)
        gravity = [0.0, 0.0, -sim.truth.g]
        self.tracker = LoadTracker(NOISE, gravity, model_std=MODEL_FLOOR)
        self.motion = MotionFlag(self.tracker)  # only readings held still join the estimate
        self.stamp = None

    def tick(self, moving: bool = False) -> None:
        """One new sample; ``moving``: the arm is commanded to move (its readings are not still
        ones; the vibration of the holding arm is, to the floor above)."""
        stamp, raw = self.sim.sensor.read()
        if stamp == self.stamp:
            return
        self.stamp = stamp
        q = self.robot.joint_positions()
        self.motion.update(stamp, [1.0 if moving else 0.0])
        rotation = self.arm.rotation_sensor_to_base(q[None])[0]
        self.tracker.compensate(rotation, self.compensator.compensate(q, raw), time=stamp)

    def run(self, seconds: float) -> None:
        """Track for ``seconds`` [s] of simulated time (a loaded machine slows the simulation)."""
        start, give_up = self.sim.time, time.monotonic() + 20.0 * seconds + 10.0
        while self.sim.time - start < seconds:
            if time.monotonic() > give_up:  # the simulation stopped: fail, do not hang
                raise AssertionError(f"the simulation did not advance {seconds} s")
            self.tick()
            time.sleep(0.0005)


def test_a_load_taken_mid_session_is_identified_and_sent_in_the_flange_frame(
    sim, robot, calibration
):
    """Grasp (MuJoCo's body mass set at run time), hold, turn the wrist, send with set_load:
    mass within 1 %, COM within 2 mm of MuJoCo's bodies; release: back to the tool alone."""
    tracking = Tracking(sim, robot, calibration)
    options = {"sensor_mass": sim.truth.sensor_mass, "sensor_com": sim.truth.sensor_com_flange}
    end_effector = robot.end_effector()
    start = robot.joint_positions()
    tracking.run(0.5)
    assert tracking.tracker.state == "empty"
    sim.set_held_mass(HELD_MASS)
    tracking.run(0.8)
    assert [event.kind for event in tracking.tracker.events if event.kind != "contact"] == ["grasp"]
    robot.move_to(start + WRIST_TURN, while_moving=lambda: tracking.tick(moving=True))
    tracking.run(1.5)
    estimate = tracking.tracker.estimate()
    assert np.all(estimate.com_determined), estimate.summary()
    np.testing.assert_allclose(estimate.mass, HELD_MASS, rtol=0.01)

    sent = robot.set_load_from(tracking.tracker, calibration, **options)
    mass, com, inertia = robot.payload()  # float32 on the wire
    expected_mass, expected_com = expected_load(sim.truth, end_effector, HELD_MASS)
    print(  # seen with -s: the figures of the hand-off
        f"sent {mass:.5f} kg (MuJoCo {expected_mass:.5f}), COM off by "
        f"{np.linalg.norm(com - expected_com) * 1e3:.3f} mm; {estimate.summary()}"
    )
    np.testing.assert_allclose(mass, expected_mass, rtol=0.01)
    assert np.linalg.norm(com - expected_com) < 2e-3, (com, expected_com, estimate.summary())
    np.testing.assert_allclose(mass, sent.mass, rtol=1e-6)
    # the held load alone, as the sensor frame's point mass moved to the flange: parallel axis
    assert np.all(np.linalg.eigvalsh(inertia) > -1e-9)

    sim.set_held_mass(0.0)  # release
    tracking.run(0.8)
    assert tracking.tracker.events[-1].kind == "release"
    robot.set_load_from(tracking.tracker, calibration, **options)
    mass, com, _ = robot.payload()
    tool_mass, tool_com = expected_load(sim.truth, end_effector, 0.0)
    np.testing.assert_allclose(mass, tool_mass, rtol=0.01)
    assert np.linalg.norm(com - tool_com) < 2e-3, (com, tool_com)
    robot.move_to(start)


def test_guide_track_load_prints_a_grasp_and_sends_the_load(sim, calibration, tmp_path, capsys):
    """``ftkin robot guide --track-load --send-load``: an object taken mid-guide is printed as a
    grasp with its mass, and the robot's m_load becomes the tool's plus the object's (MuJoCo's
    bodies); held at one orientation, its COM across gravity (the flange's x, y here) is right."""
    path = tmp_path / "calib.json"
    save_calibration(CalibrationResult.from_model(calibration), path)
    sim.set_held_mass(0.0)
    grasp = threading.Timer(1.5, sim.set_held_mass, [HELD_MASS])
    grasp.start()
    truth = sim.truth
    body = [truth.sensor_mass, *truth.sensor_com_flange]
    try:
        code = main(
            [
                "robot",
                "guide",
                str(path),
                "--franka",
                sim.hostname,
                *shlex.split("--no-realtime --state-timeout 2 --stale-after 2"),
                *shlex.split(sim.sensor_spec()),
                *("--duration", "3.5", "--track-load", "--send-load"),
                *("--noise-force", "0.3", "--noise-torque", "0.03"),  # the vibration (above)
                *("--sensor-body", *map(str, body)),
            ]
        )
    finally:
        grasp.join()
    out = capsys.readouterr().out
    with capsys.disabled():  # seen with -s: what the command printed
        print("\n" + out)
    assert code == 0, out
    assert "sent the tool:" in out
    grasps = [line for line in out.splitlines() if ": grasp (mass" in line]
    assert len(grasps) == 1, out
    assert "sent the tool and the load (grasp)" in out, out
    gc.collect()  # the CLI's connection closes
    with connected(sim) as robot:
        mass, com, _ = robot.payload()
        end_effector = robot.end_effector()
    sim.set_held_mass(0.0)
    expected_mass, expected_com = expected_load(truth, end_effector, HELD_MASS)
    np.testing.assert_allclose(mass, expected_mass, rtol=0.01)
    assert np.linalg.norm(com[:2] - expected_com[:2]) < 2e-3, (com, expected_com, out)
