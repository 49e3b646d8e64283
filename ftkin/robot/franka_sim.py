"""A simulated FR3 with a wrist F/T sensor, served on localhost by franky-sim (``franka-sim``).

:class:`FrankaSim` builds franky-sim's MuJoCo scene with a force/torque sensor between the
flange and the Franka Hand (the sensor's own body fixed to the flange, the measuring plane at
the hand frame ``fr3_hand``), an attachable tool under the hand with a known mass, centre of
mass and inertia, and starts the libfranka protocol server in a child process (the robot is
another process, as a real one is). Connect to it with
:class:`~ftkin.robot.franka.FrankaRobot` (``realtime=False``) exactly as to a real robot.

:attr:`FrankaSim.sensor` reads the load on the sensor (MINUS MuJoCo's force/torque sensor,
which gives the wrench the sensor body exerts on the hand), plus a constant bias and Gaussian
noise, stamped with the simulation time; :meth:`FrankaSim.push` applies an external force on the
tool (MuJoCo ``xfrc_applied``). Faults for tests: :meth:`SimulatedWrenchSensor.inject` and
:meth:`FrankaSim.kill`. The two processes share a few numbers (a ``RawArray`` read under a
sequence lock): the sensor sample, the hand position, the push.

Two corrections to franky-sim 1.0.4's scene: joint 7 gets an armature of 0.3 (its hold PD
otherwise chatters on the light link, see docs/robot.md), and the configured end effector
(libfranka ``m_ee``, ``F_x_Cee``, ``I_ee``) is the MuJoCo hand's own inertia expressed in the
flange frame, as Franka Desk's hand setting is on a real robot.
"""

from __future__ import annotations

import contextlib
import json
import math
import mmap
import os
import subprocess
import sys
import tempfile
import threading
import time
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, RobotConnectionLost
from ..validation import as_vector

HAND_BODY = "robot0_hand"
SENSOR_BODY = "robot0_ft_sensor"
TOOL_BODY = "robot0_tool"
HELD_BODY = "robot0_held"
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
SIM_NICENESS = -10
"""The simulation process's scheduling priority (niceness, where the user may raise it, e.g. as
root): its
physics (about half a core at 1 kHz) then keeps the robot's clock going while tests or a
background load share the cores, as a real robot's controller does on its own machine."""


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
class SimHeld:
    """A place for an object the gripper may hold, below the hand: a body without mass until
    :meth:`FrankaSim.set_held_mass` gives it one while the simulation runs (MuJoCo's
    ``body_mass`` changed between physics steps), a point mass.

    Attributes:
        center_of_mass: ``(3,)`` [m], hand (= sensor) frame.
    """

    center_of_mass: tuple = (0.015, -0.02, 0.16)


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
        bodies_in_flange: ``{MuJoCo body name: (mass [kg], centre of mass (3,) [m])}`` of every
            body from the sensor body down (sensor, hand, fingers, tool), the centre of mass in
            the flange frame ``fr3_link8`` as MuJoCo places it at the start pose: origin at the
            flange face (the sensor body's origin), axes of ``fr3_link7`` (the flange is that
            link's frame moved along its z). An independent truth for the payload hand-off.
    """

    mass: float
    center_of_mass: np.ndarray
    bias: np.ndarray
    g: float
    sensor_mass: float
    sensor_com_flange: np.ndarray
    bodies_in_flange: dict = field(default_factory=dict)


def hand_end_effector() -> tuple[float, tuple, tuple]:
    """franky-sim's hand as libfranka's end-effector setting ``(m_ee, F_x_Cee, I_ee)`` (flange)."""
    c, s = math.cos(HAND_YAW), math.sin(HAND_YAW)
    rotation = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    com = rotation @ np.array(HAND_COM)
    inertia = rotation @ np.diag(HAND_INERTIA) @ rotation.T
    return HAND_MASS, tuple(com.tolist()), tuple(inertia.reshape(-1, order="F").tolist())


# Shared state between the simulation process and this one: float64 slots of a RawArray.
_SEQ, _TIME, _WRENCH, _HAND, _PUSH, _PUSH_START, _PUSH_END = 0, 1, 2, 8, 11, 14, 15
_HELD_MASS = 16
_SLOTS = 17


def _snapshot(shared: np.ndarray) -> np.ndarray:
    """A consistent copy of the shared slots (a sequence lock: retry while the writer writes)."""
    while True:
        before = shared[_SEQ]
        copy = shared.copy()
        if before == shared[_SEQ] and before % 2 == 0:
            return copy


class SimulatedWrenchSensor:
    """The sensor of a :class:`FrankaSim`: ``read() -> (t [s], raw wrench (6,))``.

    The simulation samples MuJoCo's sensor after every physics step (1 kHz, simulation time);
    this adds the bias and white noise (one draw per sample). :meth:`inject` makes it return
    NaN (``"nan"``), repeat its last sample (``"stale"``) or raise (``"raise"``); ``None`` heals.
    """

    def __init__(self, shared: np.ndarray, spec: SimSensorSpec):
        self._shared = shared
        self.bias = np.asarray(spec.bias, dtype=float)
        self._noise = np.repeat(np.asarray(spec.noise_std, dtype=float), 3)
        self._rng = np.random.default_rng(spec.seed)
        self._lock = threading.Lock()
        self._last: tuple[float, np.ndarray] | None = None
        self._fault: str | None = None
        self.fault_time: float | None = None
        """``time.monotonic()`` when the last fault was injected, else None."""

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
            fault, last = self._fault, self._last
            if fault == "raise":
                raise OSError("simulated sensor: no answer from the sensor")
            if fault == "stale" and last is not None:
                return last[0], last[1].copy()
            values = _snapshot(self._shared)
            stamp = float(values[_TIME])
            if last is None or stamp != last[0]:
                wrench = -values[_WRENCH : _WRENCH + 6] + self.bias
                wrench += self._noise * self._rng.standard_normal(6)
                last = self._last = (stamp, wrench)
        if fault == "nan":
            return last[0], np.full(6, math.nan)
        return last[0], last[1].copy()


class FrankaSim:
    """A franky-sim FR3 with a wrist sensor and a tool, served on a loopback address.

    The simulation and its libfranka server run in a child process (the robot is another
    process, as a real one is; :meth:`kill` kills it as a crash would). Use as a context
    manager; :attr:`hostname` is the address for :class:`~ftkin.robot.franka.FrankaRobot`
    (``realtime=False``). Startup takes one to two seconds.

    Args:
        tool: The tool under the hand (None: no tool).
        sensor: The simulated sensor's body, bias and noise.
        initial_q: Start configuration ``(7,)`` [rad] (default: franky-sim's).
        realtime: Run the physics at wall-clock rate (1 kHz); False: as fast as it goes.
        start_timeout: Give up starting after this long [s].
        held: A place below the hand for an object taken mid-session (:meth:`set_held_mass`);
            None: none. Its centre of mass in the flange frame, from MuJoCo's bodies, is
            ``truth.bodies_in_flange[HELD_BODY]`` (mass 0 there: the mass given at start).
    """

    def __init__(
        self,
        tool: SimTool | None = SimTool(),
        sensor: SimSensorSpec = SimSensorSpec(),
        *,
        initial_q=None,
        realtime: bool = True,
        start_timeout: float = 60.0,
        held: SimHeld | None = None,
    ):
        try:
            import franky_sim  # noqa: F401
            import mujoco  # noqa: F401
        except ImportError as error:
            raise MissingDependency(
                "franky-sim", "franka-sim", "the simulated Franka robot"
            ) from error
        self.tool, self.spec, self.held = tool, sensor, held
        self.initial_q = None if initial_q is None else as_vector(initial_q, 7, "initial_q [rad]")
        self.realtime = bool(realtime)
        self.start_timeout = float(start_timeout)
        self._file = tempfile.NamedTemporaryFile(prefix="ftkin-franka-sim-", suffix=".bin")
        self._file.write(bytes(8 * _SLOTS))
        self._file.flush()
        self._map = mmap.mmap(self._file.fileno(), 8 * _SLOTS)
        self._shared = np.frombuffer(self._map, dtype=np.float64)
        self._shared[_PUSH_START] = self._shared[_PUSH_END] = math.inf
        self.sensor = SimulatedWrenchSensor(self._shared, sensor)
        self._process: subprocess.Popen | None = None
        self.hostname: str | None = None
        self.truth: SimTruth | None = None

    # ------------------------------------------------------------------ lifecycle
    def __enter__(self) -> FrankaSim:
        self.start()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def start(self) -> None:
        """Start the simulation process and wait until its server listens.

        Raises:
            InvalidInput: it runs already (``with FrankaSim() as sim`` starts it): a second
                process would write the same shared state, and :attr:`time`, the sensor and
                :meth:`hand_position` would read the two simulations in turn.
        """
        if self.alive:
            raise InvalidInput(
                "this FrankaSim runs already (a `with FrankaSim() as sim:` block starts it): "
                "start() it once, or close() it first"
            )
        config = {
            "tool": None if self.tool is None else vars_of(self.tool),
            "held": None if self.held is None else vars_of(self.held),
            "sensor": vars_of(self.spec),
            "initial_q": None if self.initial_q is None else self.initial_q.tolist(),
            "realtime": self.realtime,
            "shared": self._file.name,
        }
        self._process = subprocess.Popen(
            [sys.executable, "-m", __name__, json.dumps(config)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            start_new_session=True,  # Ctrl-C reaches this process, which closes the child
        )
        answer = self._answer()
        if "error" in answer:
            self.close()
            raise RobotConnectionLost(f"franky-sim failed to start: {answer['error']}")
        self.hostname = answer["hostname"]
        self.truth = SimTruth(
            answer["mass"],
            np.array(answer["com"]),
            self.sensor.bias.copy(),
            SIM_GRAVITY,
            float(self.spec.mass),
            np.asarray(self.spec.center_of_mass, dtype=float),
            {
                name: (float(values[0]), np.asarray(values[1:], dtype=float))
                for name, values in answer["bodies"].items()
            },
        )
        deadline = time.monotonic() + self.start_timeout
        while self._shared[_TIME] == 0.0 and time.monotonic() < deadline:
            time.sleep(0.005)  # the first physics step: the sensor has a sample

    def _answer(self) -> dict:
        """The child's first stdout line (JSON), within ``start_timeout``."""
        import selectors

        with selectors.DefaultSelector() as selector:
            selector.register(self._process.stdout, selectors.EVENT_READ)
            ready = selector.select(self.start_timeout)
        line = self._process.stdout.readline() if ready else ""
        if not line:
            self.close()
            raise RobotConnectionLost(
                f"franky-sim did not start within {self.start_timeout:g} s (or exited)"
            )
        return json.loads(line)

    def close(self) -> None:
        """Stop the server and the physics process (idempotent)."""
        process, self._process = self._process, None
        if process is not None:
            try:
                process.stdin.close()  # the child's signal to stop
                process.wait(10.0)
            except (OSError, subprocess.TimeoutExpired):
                process.kill()
                process.wait(5.0)
            process.stdout.close()
        self._file.close()  # the mapping stays valid for the sensor's last reads

    def kill(self) -> None:
        """Kill the simulation process (SIGKILL), as a crashed robot server: no goodbye.

        Returns at once (the process is reaped by :meth:`close`).
        """
        if self._process is not None:
            self._process.kill()

    @property
    def state_path(self) -> str:
        """The file the simulation shares its sensor sample through (for :func:`attach_sensor`
        from another process, while this one runs)."""
        return self._file.name

    def sensor_spec(self) -> str:
        """``--sensor`` and ``--sensor-option`` of this simulation's sensor, for a command run in
        another terminal (:func:`attach_sensor`)."""
        bias = ",".join(f"{value:g}" for value in self.spec.bias)
        noise = ",".join(f"{value:g}" for value in self.spec.noise_std)
        return (
            f"--sensor {__name__}:attach_sensor --sensor-option state={self.state_path} "
            f"--sensor-option bias={bias} --sensor-option noise={noise}"
        )

    @property
    def alive(self) -> bool:
        """True while the simulation process runs."""
        return self._process is not None and self._process.poll() is None

    # ------------------------------------------------------------------ pushes and state
    @property
    def time(self) -> float:
        """Simulation time [s] of the last step."""
        return float(_snapshot(self._shared)[_TIME])

    def push(self, force_in_base, duration: float, delay: float = 0.0) -> None:
        """Push the tool with ``force_in_base`` (3,) [N] for ``duration`` [s] after ``delay`` [s]
        (simulation time), at its centre of mass.
        """
        force = as_vector(force_in_base, 3, "push force [N]")
        start = self.time + float(delay)
        self._shared[_PUSH_START] = math.inf
        self._shared[_PUSH : _PUSH + 3] = force
        self._shared[_PUSH_END] = start + float(duration)
        self._shared[_PUSH_START] = start

    def set_held_mass(self, mass: float) -> None:
        """Give the held object (``held=SimHeld(...)``) this mass [kg] from the next physics
        step on (0: released): a grasp or a release, as the sensor and the arm feel it."""
        if self.held is None:
            raise InvalidInput("this simulation has no held object: FrankaSim(held=SimHeld())")
        mass = float(mass)
        if not (math.isfinite(mass) and mass >= 0.0):
            raise InvalidInput(f"the held mass must be finite and >= 0 kg, got {mass!r}")
        self._shared[_HELD_MASS] = mass

    @property
    def held_mass(self) -> float:
        """The held object's mass now [kg]."""
        return float(self._shared[_HELD_MASS])

    def hand_position(self) -> np.ndarray:
        """Position of the hand frame's origin (the sensor's) in the base frame [m], MuJoCo's."""
        return _snapshot(self._shared)[_HAND : _HAND + 3].copy()


def attach_sensor(state: str, bias: str = "0,0,0,0,0,0", noise: str = "0,0", seed: str = "0"):
    """The sensor of a :class:`FrankaSim` running in another process (``ftkin robot sim``), as a
    sensor factory: ``--sensor ftkin.robot.franka_sim:attach_sensor --sensor-option state=PATH``.

    Args:
        state: :attr:`FrankaSim.state_path` of the running simulation.
        bias: Six comma-separated numbers [N, N·m] added to every reading.
        noise: ``force,torque`` standard deviations of the white noise [N, N·m].
        seed: Seed of the noise.

    Raises:
        InvalidInput: no such state file, or options that are not numbers.
    """
    try:
        bias_values = tuple(float(value) for value in bias.split(","))
        noise_values = tuple(float(value) for value in noise.split(","))
        seed_value = int(seed)
    except ValueError:
        raise InvalidInput(
            f"bias takes 6 numbers, noise 2 and seed an integer, got {bias!r}, {noise!r}, {seed!r}"
        ) from None
    if len(bias_values) != 6 or len(noise_values) != 2:
        raise InvalidInput(f"bias takes 6 numbers and noise 2, got {bias!r} and {noise!r}")
    try:
        with open(state, "r+b") as stream:
            mapped = mmap.mmap(stream.fileno(), 8 * _SLOTS)
    except (OSError, ValueError) as error:
        raise InvalidInput(
            f"no running simulation shares {state!r} ({error}); start one with 'ftkin robot sim'"
        ) from None
    spec = SimSensorSpec(bias=bias_values, noise_std=noise_values, seed=seed_value)
    return SimulatedWrenchSensor(np.frombuffer(mapped, dtype=np.float64), spec)


def vars_of(spec) -> dict:
    """A frozen spec's fields as a plain dict (for the child process)."""
    return {name: getattr(spec, name) for name in spec.__dataclass_fields__}


# ---------------------------------------------------------------------- the simulation process
def main(argv=None) -> int:
    """The simulation process (``python -m ftkin.robot.franka_sim CONFIG_JSON``).

    Builds the scene, starts the server, writes one JSON line (the hostname and the truth, or
    an error) and serves until its stdin closes.
    """
    import logging as logging_
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the parent stops it (its stdin closes)
    with contextlib.suppress(OSError):  # a robot's clock must keep time on a busy machine
        os.setpriority(os.PRIO_PROCESS, 0, SIM_NICENESS)
    logging_.getLogger("franky_sim").setLevel(logging_.WARNING)
    config = json.loads((sys.argv[1:] if argv is None else argv)[0])
    with open(config["shared"], "r+b") as stream:
        shared = np.frombuffer(mmap.mmap(stream.fileno(), 8 * _SLOTS), dtype=np.float64)
    try:
        from franky_sim import RobotParameters, SimulationServer
        from franky_sim.mujoco_simulator import MujocoSimulator

        tool = None if config["tool"] is None else SimTool(**config["tool"])
        held = None if config.get("held") is None else SimHeld(**config["held"])
        spec = SimSensorSpec(**config["sensor"])
        m_ee, com_ee, inertia_ee = hand_end_effector()
        sim = MujocoSimulator(enable_visualization=False)
        sim.init()
        parameters = RobotParameters(ee_mass=m_ee, ee_com=com_ee, ee_inertia=inertia_ee)
        options = {"robot_parameters": parameters}
        if config["initial_q"] is not None:
            options["initial_q"] = tuple(config["initial_q"])
        robot = sim.add_robot(**options)
        _edit_scene(sim, tool, spec, held)
        server = SimulationServer(sim)
        server.init()
        mass, com = _bind(sim, shared)
        bodies = _bodies_in_flange(sim)
    except Exception as error:  # reported to the parent, which raises ftkin's error
        print(json.dumps({"error": f"{type(error).__name__}: {error}"}), flush=True)
        return 1
    try:
        server.run_async(realtime=config["realtime"])
        print(
            json.dumps(
                {"hostname": robot.hostname, "mass": mass, "com": com.tolist(), "bodies": bodies}
            ),
            flush=True,
        )
        sys.stdin.read()  # until the parent closes it (or dies)
    finally:
        server.cleanup()
        sim.cleanup()
    return 0


def _edit_scene(sim, tool: SimTool | None, spec: SimSensorSpec, held: SimHeld | None) -> None:
    """Sensor body between flange and hand, a site and F/T sensors at the hand, the tool, the
    held object's body (massless until given a mass)."""
    bodies = {body.get("name"): body for body in sim.worldbody.iter("body")}
    for joint in sim.worldbody.iter("joint"):
        if joint.get("name") == "robot0_fr3_joint7":
            joint.set("armature", "0.3")  # franky-sim 1.0.4's joint 7 chatters without it
    hand = bodies[HAND_BODY]
    link7 = next(body for body in bodies.values() if hand in list(body))
    sensor = ET.Element(
        "body", name=SENSOR_BODY, pos=hand.get("pos", "0 0 0"), quat=hand.get("quat", "1 0 0 0")
    )
    # The sensor body has the hand's orientation; its centre of mass is given in flange axes.
    c, s = math.cos(-HAND_YAW), math.sin(-HAND_YAW)
    x, y, z = spec.center_of_mass
    ET.SubElement(
        sensor,
        "inertial",
        pos=f"{c * x - s * y} {s * x + c * y} {z}",
        mass=str(spec.mass),
        diaginertia="1e-4 1e-4 1e-4",
    )
    link7.remove(hand)
    hand.set("pos", "0 0 0")
    hand.set("quat", "1 0 0 0")
    sensor.append(hand)
    link7.append(sensor)
    ET.SubElement(hand, "site", name=SENSOR_SITE, pos="0 0 0")
    if tool is not None:
        body = ET.SubElement(hand, "body", name=TOOL_BODY, pos="0 0 0")
        where = " ".join(str(v) for v in tool.center_of_mass)
        ET.SubElement(
            body,
            "inertial",
            pos=where,
            mass=str(tool.mass),
            diaginertia=" ".join(str(v) for v in tool.inertia),
        )
        ET.SubElement(
            body,
            "geom",
            type="cylinder",
            size="0.02 0.04",
            pos=where,
            contype="0",
            conaffinity="0",
            group="2",
            mass="0",
            rgba="0.9 0.5 0.1 1",
        )
    if held is not None:  # a fixed child: no degree of freedom, so a zero mass is allowed
        body = ET.SubElement(hand, "body", name=HELD_BODY, pos="0 0 0")
        where = " ".join(str(v) for v in held.center_of_mass)
        ET.SubElement(body, "inertial", pos=where, mass="0", diaginertia="0 0 0")
    sensors = ET.SubElement(sim.scene, "sensor")
    ET.SubElement(sensors, "force", name="robot0_ft_force", site=SENSOR_SITE)
    ET.SubElement(sensors, "torque", name="robot0_ft_torque", site=SENSOR_SITE)


def _bodies_in_flange(sim) -> dict[str, list]:
    """``{body: [mass, cx, cy, cz]}`` below the flange, centre of mass in the flange frame (see
    :attr:`SimTruth.bodies_in_flange`), from MuJoCo's own body data.
    """
    import mujoco

    model, data = sim.model, sim.data
    sensor = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, SENSOR_BODY)
    link7 = int(model.body_parentid[sensor])
    axes, origin = data.xmat[link7].reshape(3, 3), data.xpos[sensor]
    below = [sensor]
    for body in range(model.nbody):  # parents come before children in MuJoCo's body order
        if int(model.body_parentid[body]) in below and body not in below:
            below.append(body)
    return {
        mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_BODY, body): [
            float(model.body_mass[body]),
            *(axes.T @ (data.xipos[body] - origin)).tolist(),
        ]
        for body in below
    }


def _bind(sim, shared: np.ndarray) -> tuple[float, np.ndarray]:
    """The truth (mass and centre of mass below the sensor) and the per-step callbacks."""
    import mujoco

    model, data = sim.model, sim.data

    def body_id(name: str) -> int:
        return mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)

    def sensor_address(name: str) -> int:
        return int(model.sensor_adr[mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_SENSOR, name)])

    hand = body_id(HAND_BODY)
    force, torque = sensor_address("robot0_ft_force"), sensor_address("robot0_ft_torque")
    rotation = data.xmat[hand].reshape(3, 3)
    com = rotation.T @ (data.subtree_com[hand] - data.xpos[hand])
    mass = float(model.body_subtreemass[hand])
    pushed = body_id(TOOL_BODY) if body_id(TOOL_BODY) >= 0 else hand
    held = body_id(HELD_BODY)
    ancestors = []  # the held body and its parents: their subtree masses follow its mass
    body = held
    while body > 0:
        ancestors.append(body)
        body = int(model.body_parentid[body])

    def before_step(_sim) -> None:
        if held >= 0 and model.body_mass[held] != shared[_HELD_MASS]:
            change = shared[_HELD_MASS] - model.body_mass[held]
            model.body_mass[held] = shared[_HELD_MASS]
            model.body_subtreemass[ancestors] += change
        if shared[_PUSH_START] <= data.time < shared[_PUSH_END]:
            data.xfrc_applied[pushed, :3] = shared[_PUSH : _PUSH + 3]
        else:
            data.xfrc_applied[pushed, :3] = 0.0

    def after_step(_sim) -> None:
        values = data.sensordata
        shared[_SEQ] += 1.0  # odd: writing
        shared[_TIME] = data.time
        shared[_WRENCH : _WRENCH + 3] = values[force : force + 3]
        shared[_WRENCH + 3 : _WRENCH + 6] = values[torque : torque + 3]
        shared[_HAND : _HAND + 3] = data.xpos[hand]
        shared[_SEQ] += 1.0  # even: done

    sim.register_pre_step_callback(before_step)
    sim.register_post_step_callback(after_step)
    return mass, com


if __name__ == "__main__":
    sys.exit(main())
