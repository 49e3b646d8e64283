"""A simulated FR3 with a wrist F/T sensor, served on localhost by franky-sim (extra ``franka``).

:class:`FrankaSim` builds franky-sim's MuJoCo scene with a force/torque sensor between the
flange and the Franka Hand (the sensor's own body fixed to the flange, the measuring plane at
the hand frame ``fr3_hand``), an attachable tool under the hand with a known mass, centre of
mass and inertia, and starts the libfranka protocol server in a thread. Connect to it with
:class:`~ftkin.robot.franka.FrankaRobot` (``realtime=False``) exactly as to a real robot.

:attr:`FrankaSim.sensor` reads the load on the sensor (MINUS MuJoCo's force/torque sensor,
which gives the wrench the sensor body exerts on the hand), plus a constant bias and Gaussian
noise, stamped with the simulation time; :meth:`FrankaSim.push` applies an external force on the
tool (MuJoCo ``xfrc_applied``). Faults for tests: :meth:`SimulatedWrenchSensor.inject`.

Two corrections to franky-sim 1.0.4's scene: joint 7 gets an armature of 0.3 (its hold PD
otherwise chatters on the light link, see docs/robot.md), and the configured end effector
(libfranka ``m_ee``, ``F_x_Cee``, ``I_ee``) is the MuJoCo hand's own inertia expressed in the
flange frame, as Franka Desk's hand setting is on a real robot.
"""

from __future__ import annotations

import math
import threading
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput, MissingDependency
from ..validation import as_vector

HAND_BODY = "robot0_hand"
SENSOR_BODY = "robot0_ft_sensor"
TOOL_BODY = "robot0_tool"
SENSOR_SITE = "robot0_ft_site"
HAND_MASS = 0.73
"""Mass of franky-sim's hand body [kg] (the fingers add 2 × 0.015 kg)."""
HAND_COM = (-0.01, 0.0, 0.03)
"""Centre of mass of franky-sim's hand body in the hand frame [m]."""
HAND_INERTIA = (0.001, 0.0025, 0.0017)
"""Principal inertia of franky-sim's hand body, hand axes [kg·m²]."""
HAND_YAW = -math.pi / 4
"""The hand frame is the flange turned by this angle about z [rad]."""
SIM_GRAVITY = 9.81
"""franky-sim's gravity [m/s²]."""


@dataclass(frozen=True)
class SimTool:
    """A tool under the hand, in the hand (= sensor) frame.

    Attributes:
        mass: [kg].
        center_of_mass: ``(3,)`` [m], hand frame.
        inertia: ``(3,)`` principal moments about the centre of mass, hand axes [kg·m²].
    """

    mass: float = 1.2
    center_of_mass: tuple = (0.02, -0.01, 0.09)
    inertia: tuple = (0.004, 0.005, 0.002)


@dataclass(frozen=True)
class SimSensorSpec:
    """The simulated sensor: its body above the measuring plane, bias and noise.

    Attributes:
        mass: The sensor body's mass [kg] (a datasheet value for the payload hand-off).
        center_of_mass: ``(3,)`` its centre of mass in the flange frame [m].
        bias: ``(6,)`` constant bias added to every reading [N, N·m].
        noise_std: ``(force [N], torque [N·m])`` standard deviation of white noise per reading.
        seed: Seed of the noise.
    """

    mass: float = 0.25
    center_of_mass: tuple = (0.0, 0.0, -0.01)
    bias: tuple = (1.5, -0.8, 2.2, 0.05, -0.03, 0.02)
    noise_std: tuple = (0.02, 0.001)
    seed: int = 0


@dataclass(frozen=True)
class SimTruth:
    """What the sensor carries in the simulation (hand, fingers and tool), for checks.

    Attributes:
        mass: [kg].
        center_of_mass: ``(3,)`` in the sensor frame ``fr3_hand`` [m].
        bias: ``(6,)`` [N, N·m].
        g: Gravity [m/s²].
        sensor_mass: The sensor body's mass [kg].
        sensor_com_flange: Its centre of mass in the flange frame [m].
    """

    mass: float
    center_of_mass: np.ndarray
    bias: np.ndarray
    g: float
    sensor_mass: float
    sensor_com_flange: np.ndarray


def hand_end_effector() -> tuple[float, tuple, tuple]:
    """franky-sim's hand as libfranka's end-effector setting ``(m_ee, F_x_Cee, I_ee)`` (flange)."""
    c, s = math.cos(HAND_YAW), math.sin(HAND_YAW)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    com = rotation @ np.array(HAND_COM)
    inertia = rotation @ np.diag(HAND_INERTIA) @ rotation.T
    return HAND_MASS, tuple(com.tolist()), tuple(inertia.reshape(-1, order="F").tolist())


class SimulatedWrenchSensor:
    """The sensor of a :class:`FrankaSim`: ``read() -> (t [s], raw wrench (6,))``.

    Samples are taken after every physics step (1 kHz, simulation time) with bias and noise.
    :meth:`inject` makes it return NaN (``"nan"``), repeat its last sample (``"stale"``) or
    raise (``"raise"``); ``None`` heals it.
    """

    def __init__(self, spec: SimSensorSpec):
        self.bias = np.asarray(spec.bias, dtype=float)
        self._noise = np.repeat(np.asarray(spec.noise_std, dtype=float), 3)
        self._rng = np.random.default_rng(spec.seed)
        self._lock = threading.Lock()
        self._sample: tuple[float, np.ndarray] | None = None
        self._fault: str | None = None
        self.fault_time: float | None = None
        """Wall-clock time (``time.monotonic()``) the last fault was injected."""

    def _record(self, t: float, wrench_on_hand: np.ndarray) -> None:
        """Called by the simulation after each step with MuJoCo's sensor values."""
        reading = -wrench_on_hand + self.bias + self._noise * self._rng.standard_normal(6)
        with self._lock:
            if self._fault != "stale":
                self._sample = (t, reading)

    def inject(self, fault: str | None) -> None:
        """Start a fault (``"nan"``, ``"stale"``, ``"raise"``) or end it (None)."""
        if fault not in (None, "nan", "stale", "raise"):
            raise InvalidInput(f"fault must be None, 'nan', 'stale' or 'raise', got {fault!r}")
        with self._lock:
            self._fault = fault
            self.fault_time = time.monotonic() if fault is not None else None

    def read(self) -> tuple[float, np.ndarray]:
        """The latest sample: time [s] and raw wrench (6,) [N, N·m], sensor frame."""
        with self._lock:
            sample, fault = self._sample, self._fault
        if fault == "raise":
            raise OSError("simulated sensor: no answer from the sensor")
        if sample is None:
            raise OSError("simulated sensor: the simulation has not started")
        t, wrench = sample
        if fault == "nan":
            return t, np.full(6, math.nan)
        return t, wrench.copy()


@dataclass
class _Push:
    force: np.ndarray = field(default_factory=lambda: np.zeros(3))
    start: float = math.inf
    end: float = math.inf


class FrankaSim:
    """A franky-sim FR3 with a wrist sensor and a tool, served on a loopback address.

    Use as a context manager; :attr:`hostname` is the address for
    :class:`~ftkin.robot.franka.FrankaRobot`. Startup takes about a second.

    Args:
        tool: The tool under the hand (None: no tool).
        sensor: The simulated sensor's body, bias and noise.
        initial_q: Start configuration ``(7,)`` [rad] (default: franky-sim's).
        realtime: Run the physics at wall-clock rate (1 kHz); False runs it as fast as it goes.
    """

    def __init__(
        self,
        tool: SimTool | None = SimTool(),
        sensor: SimSensorSpec = SimSensorSpec(),
        *,
        initial_q=None,
        realtime: bool = True,
    ):
        try:
            import franky_sim  # noqa: F401
            import mujoco  # noqa: F401
        except ImportError as error:
            raise MissingDependency(
                "franky-sim", "franka", "the simulated Franka robot"
            ) from error
        self.tool, self.spec = tool, sensor
        self.initial_q = None if initial_q is None else as_vector(initial_q, 7, "initial_q [rad]")
        self.realtime = bool(realtime)
        self.sensor = SimulatedWrenchSensor(sensor)
        self._push = _Push()
        self._sim = self._server = None
        self.hostname: str | None = None
        self.truth: SimTruth | None = None

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> FrankaSim:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:
        """Build the scene, start the physics and the protocol server."""
        from franky_sim import RobotParameters, SimulationServer
        from franky_sim.mujoco_simulator import MujocoSimulator

        m_ee, com_ee, inertia_ee = hand_end_effector()
        parameters = RobotParameters(ee_mass=m_ee, ee_com=com_ee, ee_inertia=inertia_ee)
        self._sim = MujocoSimulator(enable_visualization=False)
        self._sim.init()
        options = {"robot_parameters": parameters}
        if self.initial_q is not None:
            options["initial_q"] = tuple(self.initial_q.tolist())
        robot = self._sim.add_robot(**options)
        self._edit_scene()
        self._server = SimulationServer(self._sim)
        try:
            self._server.init()
            self._bind()
            self._server.run_async(realtime=self.realtime)
        except BaseException:
            self.close()
            raise
        self.hostname = robot.hostname

    def close(self) -> None:
        """Stop the server thread and the physics (idempotent)."""
        server, self._server = self._server, None
        if server is not None:
            server.cleanup()
        sim, self._sim = self._sim, None
        if sim is not None and sim.is_started and not sim.is_cleaned_up:
            sim.cleanup()

    kill = close
    """Stop the server as a crash would: the client's next call finds no robot."""

    # ------------------------------------------------------------------ scene
    def _edit_scene(self) -> None:
        bodies = {body.get("name"): body for body in self._sim.worldbody.iter("body")}
        for joint in self._sim.worldbody.iter("joint"):
            if joint.get("name") == "robot0_fr3_joint7":
                joint.set("armature", "0.3")
        hand = bodies[HAND_BODY]
        link7 = next(body for body in bodies.values() if hand in list(body))
        sensor = ET.Element(
            "body", name=SENSOR_BODY, pos=hand.get("pos", "0 0 0"), quat=hand.get("quat", "1 0 0 0")
        )
        # The sensor body's centre of mass is given in the flange frame; the body has the hand's
        # orientation (the measuring frame), so turn it back by the hand's yaw.
        c, s = math.cos(-HAND_YAW), math.sin(-HAND_YAW)
        x, y, z = self.spec.center_of_mass
        ET.SubElement(
            sensor,
            "inertial",
            pos=f"{c * x - s * y} {s * x + c * y} {z}",
            mass=str(self.spec.mass),
            diaginertia="1e-4 1e-4 1e-4",
        )
        link7.remove(hand)
        hand.set("pos", "0 0 0")
        hand.set("quat", "1 0 0 0")
        sensor.append(hand)
        link7.append(sensor)
        ET.SubElement(hand, "site", name=SENSOR_SITE, pos="0 0 0")
        if self.tool is not None:
            tool = ET.SubElement(hand, "body", name=TOOL_BODY, pos="0 0 0")
            ET.SubElement(
                tool,
                "inertial",
                pos=" ".join(str(v) for v in self.tool.center_of_mass),
                mass=str(self.tool.mass),
                diaginertia=" ".join(str(v) for v in self.tool.inertia),
            )
            ET.SubElement(
                tool,
                "geom",
                type="cylinder",
                size="0.02 0.04",
                pos=" ".join(str(v) for v in self.tool.center_of_mass),
                contype="0",
                conaffinity="0",
                group="2",
                mass="0",
                rgba="0.9 0.5 0.1 1",
            )
        sensors = ET.SubElement(self._sim.scene, "sensor")
        ET.SubElement(sensors, "force", name="robot0_ft_force", site=SENSOR_SITE)
        ET.SubElement(sensors, "torque", name="robot0_ft_torque", site=SENSOR_SITE)

    def _bind(self) -> None:
        """After the model is compiled: ids, the truth, and the per-step callbacks."""
        import mujoco

        model, data = self._sim.model, self._sim.data
        ids = {
            name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)
            for name in (HAND_BODY, TOOL_BODY)
        }
        force_address = model.sensor_adr[
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "robot0_ft_force")
        ]
        torque_address = model.sensor_adr[
            mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, "robot0_ft_torque")
        ]
        hand = ids[HAND_BODY]
        rotation = data.xmat[hand].reshape(3, 3)
        com = rotation.T @ (data.subtree_com[hand] - data.xpos[hand])
        self.truth = SimTruth(
            float(model.body_subtreemass[hand]),
            com,
            self.sensor.bias.copy(),
            SIM_GRAVITY,
            float(self.spec.mass),
            np.asarray(self.spec.center_of_mass, dtype=float),
        )
        push_body = ids[TOOL_BODY] if ids[TOOL_BODY] >= 0 else hand
        push = self._push
        record = self.sensor._record

        def before_step(sim) -> None:
            t = data.time
            if push.start <= t < push.end:
                data.xfrc_applied[push_body, :3] = push.force
            else:
                data.xfrc_applied[push_body, :3] = 0.0

        def after_step(sim) -> None:
            values = data.sensordata
            wrench = np.concatenate(
                (values[force_address : force_address + 3], values[torque_address : torque_address + 3])
            )
            record(float(data.time), wrench)

        self._sim.register_pre_step_callback(before_step)
        self._sim.register_post_step_callback(after_step)
        self._tool_or_hand = push_body

    # ------------------------------------------------------------------ pushes and state
    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return float(self._sim.data.time)

    def push(self, force_in_base, duration: float, delay: float = 0.0) -> None:
        """Push the tool with ``force_in_base`` (3,) [N] for ``duration`` [s] after ``delay`` [s]."""
        force = as_vector(force_in_base, 3, "push force [N]")
        start = self.time + float(delay)
        self._push.force, self._push.end, self._push.start = force, start + float(duration), start

    def tool_position(self) -> np.ndarray:
        """Position of the hand-frame origin in the base frame [m] (MuJoCo's, not the robot's)."""
        import mujoco

        hand = mujoco.mj_name2id(self._sim.model, mujoco.mjtObj.mjOBJ_BODY, HAND_BODY)
        return np.array(self._sim.data.xpos[hand])
