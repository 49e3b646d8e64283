"""A UR controller's RTDE interface on loopback, for tests with the real ur_rtde client.

Written from UR's public description of the RTDE protocol (the "Real-Time Data Exchange (RTDE)
Guide"): TCP port 30004, packets ``>HB`` (size including the 3-byte header, command) then the
payload, big-endian. The emulator answers

* ``V`` (request protocol version, ``>H``): accepted (``>B`` 1) for version 2;
* ``v`` (get controller version): ``>IIII`` major, minor, bugfix, build (major 5: an e-Series, so
  ur_rtde asks for 500 Hz);
* ``O`` (setup outputs: ``>d`` frequency, then the comma-separated names, ur_rtde ends the list
  with a comma): recipe id 1 and the comma-separated types, ``NOT_FOUND`` for an unknown name;
* ``I`` (setup inputs): ``NOT_FOUND`` for every name (a receive-only client asks for none);
* ``S`` / ``P`` (start / pause): accepted;

and once started streams ``U`` data packages (recipe id, then the fields in the order asked) at
the frequency asked, to every client (a controller serves several), ``timestamp`` being the
controller's 500 Hz clock. It is the arm's state:

* ``actual_q``, ``target_q``, their speeds: the pose the test sets, or a motion to the next pose;
* ``actual_TCP_pose``, ``target_TCP_pose``: the flange (zero TCP offset) from this file's own DH
  products of UR's published parameters (plain numpy, no ftkin), as position [m] and rotation
  vector [rad];
* ``ft_raw_wrench``: a simulated tool on the built-in sensor (mass, centre of mass in the sensor
  frame = the flange's axes, bias, Gaussian noise, an optional contact wrench), the load on the
  sensor, expressed in base axes (``wrench_frame="base"``, UR's convention for the wrist
  sensor's wrench: see docs/other-robots.md) or in the sensor's (``"sensor"``, to test the check);
* every other output of the guide with a plausible constant (robot mode RUNNING, safety NORMAL).

With ``dashboard`` set, it also serves a minimal Dashboard Server on TCP port 29999 (UR's
Dashboard Server article; the command list of UR's client library): a greeting line, then one
line per command: ``get robot model`` answers ``dashboard`` (``"UR5"``), ``PolyscopeVersion``
``URSoftware 5.15.0.12345 (Dec 01 2026)`` (:data:`CONTROLLER_VERSION`), anything else
``could not understand: '...'``. Without it nothing listens on 29999.

It runs in a child process (ur_rtde holds the GIL while it connects: a server thread in the test
process would hang it), on TCP port 30004 (ur_rtde has no port argument) of a random loopback
address ``127.x.y.z`` (Linux routes all of 127/8 to the loopback interface), so parallel runs do
not collide. The test talks to it through a pipe: poses and motions, the tool, faults (``freeze``:
the connections stay up, the clock stands still and no package is sent;
:meth:`EmulatedController.kill`: the process dies).
"""

from __future__ import annotations

import json
import math
import os
import random
import socket
import struct
import subprocess
import sys
import time
from collections import deque
from dataclasses import asdict, dataclass, field
from multiprocessing.connection import Connection

import numpy as np

PORT = 30004
STANDARD_GRAVITY = 9.80665  # [m/s²]
CONTROLLER_VERSION = (5, 15, 0, 12345)
START_TIMESTAMP = 1000.0  # [s] the controller's clock at the first package
DASHBOARD_PORT = 29999
DASHBOARD_GREETING = "Connected: Universal Robots Dashboard Server"
POLYSCOPE_VERSION = "URSoftware {}.{}.{}.{} (Dec 01 2026)".format(*CONTROLLER_VERSION)

# UR's published DH parameters [m]: d1, a2, a3, d4, d5, d6 (a1 = a4 = a5 = a6 = 0, d2 = d3 = 0),
# typed in again here so that the test does not read them from ftkin
DH = {
    "ur3e": (0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921),
    "ur5e": (0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996),
    "ur10e": (0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655),
    "ur16e": (0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655),
    "ur20": (0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543),
    "ur30": (0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543),
}
ALPHA = (math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0)

# RTDE output types by name (UR's RTDE guide); registers by prefix
OUTPUT_TYPES = {
    "timestamp": "DOUBLE",
    **{
        name: "VECTOR6D"
        for name in (
            "target_q", "target_qd", "target_qdd", "target_current", "target_moment",
            "actual_q", "actual_qd", "actual_current", "joint_control_output",
            "actual_TCP_pose", "actual_TCP_speed", "actual_TCP_force", "target_TCP_pose",
            "target_TCP_speed", "joint_temperatures", "actual_joint_voltage", "ft_raw_wrench",
            "payload_inertia", "tcp_offset", "actual_current_window",
        )
    },
    "actual_digital_input_bits": "UINT64",
    "actual_digital_output_bits": "UINT64",
    "actual_execution_time": "DOUBLE",
    "robot_mode": "INT32",
    "joint_mode": "VECTOR6INT32",
    "safety_mode": "INT32",
    "safety_status": "INT32",
    "actual_tool_accelerometer": "VECTOR3D",
    "elbow_position": "VECTOR3D",
    "elbow_velocity": "VECTOR3D",
    "payload_cog": "VECTOR3D",
    "runtime_state": "UINT32",
    "robot_status_bits": "UINT32",
    "safety_status_bits": "UINT32",
    "analog_io_types": "UINT32",
    "tool_mode": "UINT32",
    "tool_analog_input_types": "UINT32",
    "tool_output_voltage": "INT32",
    "script_control_line": "UINT32",
    **{
        name: "DOUBLE"
        for name in (
            "speed_scaling", "target_speed_fraction", "actual_momentum", "actual_main_voltage",
            "actual_robot_voltage", "actual_robot_current", "standard_analog_input0",
            "standard_analog_input1", "standard_analog_output0", "standard_analog_output1",
            "io_current", "tool_analog_input0", "tool_analog_input1", "tool_output_current",
            "tool_temperature", "tcp_force_scalar", "payload", "joint_position_deviation_ratio",
            "collision_detection_ratio",
        )
    },
    "output_bit_registers0_to_31": "UINT32",
    "output_bit_registers32_to_63": "UINT32",
}  # fmt: skip
REGISTER_TYPES = {"output_int_register_": "INT32", "output_double_register_": "DOUBLE"}
STRUCT_CODES = {
    "DOUBLE": "d",
    "VECTOR6D": "6d",
    "VECTOR3D": "3d",
    "VECTOR6INT32": "6i",
    "INT32": "i",
    "UINT32": "I",
    "UINT64": "Q",
    "UINT8": "B",
    "BOOL": "?",
}


def output_type(name: str) -> str:
    """The RTDE type of an output name, or ``NOT_FOUND``."""
    if name in OUTPUT_TYPES:
        return OUTPUT_TYPES[name]
    for prefix, kind in REGISTER_TYPES.items():
        if name.startswith(prefix) and name[len(prefix) :].isdigit():
            return kind if int(name[len(prefix) :]) < 48 else "NOT_FOUND"
    return "NOT_FOUND"


# ---------------------------------------------------------------- kinematics (independent of ftkin)
def dh_transforms(robot: str, q) -> list[np.ndarray]:
    """``[T₁, T₁T₂, …, T₁⋯T₆]`` (4×4) of UR's standard DH: ``Tᵢ = Rz(θᵢ) Tz(dᵢ) Tx(aᵢ) Rx(αᵢ)``."""
    d1, a2, a3, d4, d5, d6 = DH[robot]
    d = (d1, 0.0, 0.0, d4, d5, d6)
    a = (0.0, a2, a3, 0.0, 0.0, 0.0)
    out, total = [], np.eye(4)
    for theta, di, ai, alpha in zip(q, d, a, ALPHA):
        ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
        step = np.array(
            [
                [ct, -st * ca, st * sa, ai * ct],
                [st, ct * ca, -ct * sa, ai * st],
                [0.0, sa, ca, di],
                [0.0, 0.0, 0.0, 1.0],
            ]
        )
        total = total @ step
        out.append(total)
    return out


def flange_transform(robot: str, q) -> np.ndarray:
    """``ᴮT_tool0`` (4×4) at ``q``."""
    return dh_transforms(robot, q)[-1]


def rotation_vector(rotation: np.ndarray) -> np.ndarray:
    """The rotation vector (axis × angle, angle in [0, π]) of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(rotation).as_rotvec()


def pose_vector(transform: np.ndarray) -> np.ndarray:
    """``[x, y, z, rx, ry, rz]`` [m, rad], RTDE's pose form."""
    return np.concatenate([transform[:3, 3], rotation_vector(transform[:3, :3])])


# ---------------------------------------------------------------- the simulated tool
@dataclass
class SimulatedTool:
    """The load on the built-in sensor.

    Attributes:
        mass: Tool mass [kg].
        com: Centre of mass in the sensor frame (the flange's axes and origin) [m].
        bias: Sensor bias ``[F0, M0]`` [N, N·m].
        force_noise, torque_noise: Standard deviation of the Gaussian noise [N], [N·m].
        contact: A contact wrench on the tool, sensor frame, about the sensor origin [N, N·m].
        wrench_frame: ``"base"`` (force and torque in base axes) or ``"sensor"``.
        seed: Noise seed.
    """

    mass: float = 1.2
    com: tuple = (0.01, -0.02, 0.06)
    bias: tuple = (1.5, -2.0, 3.0, 0.05, -0.04, 0.03)
    force_noise: float = 0.05
    torque_noise: float = 0.002
    contact: tuple = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    wrench_frame: str = "base"
    seed: int = 1
    gravity: float = field(default=STANDARD_GRAVITY)

    def wrench_in_sensor(self, rotation_flange_to_base: np.ndarray) -> np.ndarray:
        """The noiseless load on the sensor ``(6,)`` in the sensor frame at this orientation."""
        weight_in_sensor = rotation_flange_to_base.T @ np.array(
            [0.0, 0.0, -self.mass * self.gravity]
        )
        force = weight_in_sensor + np.asarray(self.bias[:3]) + np.asarray(self.contact[:3])
        torque = (
            np.cross(np.asarray(self.com), weight_in_sensor)
            + np.asarray(self.bias[3:])
            + np.asarray(self.contact[3:])
        )
        return np.concatenate([force, torque])


# ---------------------------------------------------------------- the server (child process)
class _Arm:
    """The arm's motion: a pose, or a smooth (cosine) move from one pose to the next."""

    def __init__(self, q):
        self.start = self.goal = np.asarray(q, dtype=float)
        self.t0, self.duration = 0.0, 0.0

    def move(self, goal, duration: float, now: float) -> None:
        self.start, self.goal = self.state(now)[0], np.asarray(goal, dtype=float)
        self.t0, self.duration = now, max(float(duration), 0.0)

    def state(self, now: float) -> tuple[np.ndarray, np.ndarray]:
        if self.duration <= 0.0 or now >= self.t0 + self.duration:
            return self.goal.copy(), np.zeros(6)
        s = (now - self.t0) / self.duration
        blend = 0.5 - 0.5 * math.cos(math.pi * s)
        speed = 0.5 * math.pi * math.sin(math.pi * s) / self.duration
        delta = self.goal - self.start
        return self.start + blend * delta, speed * delta


DYNAMIC = {
    "timestamp": "timestamp", "actual_q": "q", "target_q": "q", "actual_qd": "dq",
    "target_qd": "dq", "actual_TCP_pose": "pose", "target_TCP_pose": "pose",
    "ft_raw_wrench": "wrench", "actual_tool_accelerometer": "accelerometer",
}  # fmt: skip
"""Outputs computed every package, by the key of :meth:`_Server.values`."""
CONSTANTS = {
    "robot_mode": 7,  # RUNNING
    "safety_mode": 1,  # NORMAL
    "safety_status": 1,
    "joint_mode": [253] * 6,  # RUNNING
    "runtime_state": 2,  # PLAYING
    "robot_status_bits": 0b0011,  # power on, program running
    "safety_status_bits": 0b1,  # normal mode
    "speed_scaling": 1.0,
    "target_speed_fraction": 1.0,
    "actual_main_voltage": 48.0,
    "actual_robot_voltage": 48.0,
    "actual_robot_current": 0.9,
    "actual_execution_time": 0.3,
    "joint_temperatures": [31.5] * 6,
    "actual_joint_voltage": [47.9] * 6,
    "actual_current": [0.3] * 6,
    # distinctive values in the last fields: a type of the wrong size before them shows
    "payload": 0.75,
    "payload_cog": [0.001, 0.002, 0.003],
    "output_int_register_19": 19,
    "output_double_register_19": 19.5,
}
"""Outputs with a constant value (every other output reads 0)."""
CONTROLLER_PERIOD = 0.002  # [s] the controller's clock: 500 Hz


class _Client:
    """One RTDE client: its socket, its output recipe and whether it has started."""

    def __init__(self, connection: socket.socket):
        self.connection = connection
        connection.setblocking(False)
        connection.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.buffer = b""
        self.names: list[str] = []
        self.packer: struct.Struct | None = None
        self.every = 1  # a package every this many controller ticks
        self.started = False

    def send(self, command: str, payload: bytes = b"") -> None:
        self.connection.setblocking(True)
        try:
            self.connection.sendall(struct.pack(">HB", 3 + len(payload), ord(command)) + payload)
        finally:
            self.connection.setblocking(False)

    def packets(self) -> list[tuple[str, bytes]]:
        """The complete packets received so far (non-blocking)."""
        try:
            chunk = self.connection.recv(65536)
        except BlockingIOError:
            chunk = None
        if chunk == b"":
            raise ConnectionError("the client closed the connection")
        if chunk:
            self.buffer += chunk
        out = []
        while len(self.buffer) >= 3:
            size, command = struct.unpack(">HB", self.buffer[:3])
            if len(self.buffer) < size:
                break
            out.append((chr(command), self.buffer[3:size]))
            self.buffer = self.buffer[size:]
        return out

    def answer(self, command: str, payload: bytes) -> list[str] | None:
        """Answer one packet; returns the output names of an output setup."""
        if command == "V":
            (version,) = struct.unpack(">H", payload[:2])
            self.send("V", struct.pack(">B", 1 if version in (1, 2) else 0))
        elif command == "v":
            self.send("v", struct.pack(">IIII", *CONTROLLER_VERSION))
        elif command == "O":
            (frequency,) = struct.unpack(">d", payload[:8])
            names = [name for name in payload[8:].decode().split(",") if name]
            types = [output_type(name) for name in names]
            if 0.0 < frequency <= 1.0 / CONTROLLER_PERIOD and "NOT_FOUND" not in types:
                self.names, self.every = names, max(1, round(1.0 / (frequency * CONTROLLER_PERIOD)))
                self.packer = struct.Struct(">B" + "".join(STRUCT_CODES[t] for t in types))
                self.layout()
            self.send("O", struct.pack(">B", 1) + ",".join(types).encode())
            return names
        elif command == "I":
            names = [name for name in payload.decode().split(",") if name]
            self.send("I", struct.pack(">B", 0) + ",".join(["NOT_FOUND"] * len(names)).encode())
        elif command == "S":
            self.started = self.packer is not None
            self.send("S", struct.pack(">B", int(self.started)))
        elif command == "P":
            self.started = False
            self.send("P", struct.pack(">B", 1))
        return None  # "U" from the client (inputs) and text messages are ignored

    def layout(self) -> None:
        """The package as a template: constants filled in, ``(slice, key)`` for the rest."""
        template, slots = [1], []
        for name in self.names:
            kind = output_type(name)
            size = 6 if kind.startswith("VECTOR6") else 3 if kind.startswith("VECTOR3") else 1
            if name in DYNAMIC:
                slots.append((slice(len(template), len(template) + size), DYNAMIC[name]))
                template.extend([0.0] * size)
                continue
            value = CONSTANTS.get(name, 0)
            values = value if isinstance(value, list) else [value] * size
            integer = kind not in ("DOUBLE", "VECTOR6D", "VECTOR3D")
            template.extend(int(v) if integer else float(v) for v in values)
        self.template, self.slots = template, slots

    def package(self, values: dict) -> bytes:
        flat = self.template.copy()
        for where, key in self.slots:
            flat[where] = values[key]
        return self.packer.pack(*flat)


class _Dashboard:
    """The Dashboard Server (module docstring): line-based, non-blocking, served each tick."""

    def __init__(self, address: str, model: str):
        self.model = model
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind((address, DASHBOARD_PORT))
        self.listener.listen(4)
        self.listener.setblocking(False)
        self.clients: dict[socket.socket, bytes] = {}

    def answer(self, command: str) -> str:
        if command == "get robot model":
            return self.model
        if command == "PolyscopeVersion":
            return POLYSCOPE_VERSION
        return f"could not understand: '{command}'"

    def serve(self) -> None:
        while True:
            try:
                connection, _ = self.listener.accept()
            except BlockingIOError:
                break
            connection.sendall(DASHBOARD_GREETING.encode() + b"\n")
            connection.setblocking(False)
            self.clients[connection] = b""
        for connection in list(self.clients):
            try:
                chunk = connection.recv(4096)
            except BlockingIOError:
                continue
            except OSError:
                chunk = b""
            if not chunk:
                connection.close()
                del self.clients[connection]
                continue
            buffer = self.clients[connection] + chunk
            *lines, self.clients[connection] = buffer.split(b"\n")
            for line in lines:
                reply = self.answer(line.decode(errors="replace").strip())
                connection.setblocking(True)
                connection.sendall(reply.encode() + b"\n")
                connection.setblocking(False)


class _Server:
    def __init__(self, address: str, robot: str, q0, tool: dict, pipe, dashboard=None):
        self.robot, self.pipe = robot, pipe
        self.dashboard = None if dashboard is None else _Dashboard(address, dashboard)
        self.arm = _Arm(q0)
        self.tool = SimulatedTool(**tool)
        self.rng = np.random.default_rng(self.tool.seed)
        self.frozen = False
        self.listener = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        self.listener.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        self.listener.bind((address, PORT))
        self.listener.listen(8)
        self.listener.setblocking(False)
        self.clients: list[_Client] = []
        self.tick = 0
        self.last: dict = {}
        self.requested: list[str] = []
        self.late = 0
        self.sent: deque = deque(maxlen=60_000)  # (timestamp, time.monotonic()) of each package
        self._kinematics_key, self._kinematics = None, None
        self._noise, self._noise_index = np.zeros((0, 6)), 0
        self.kinematics(self.arm.goal)  # imports scipy now, not at the first client's first tick

    # -- the arm and the tool
    def kinematics(self, q: np.ndarray) -> tuple:
        """Flange rotation, RTDE pose, accelerometer and the noiseless load on the sensor at ``q``
        (cached: the arm is mostly still; a new tool clears the cache).
        """
        key = tuple(q.tolist())
        if key != self._kinematics_key:
            flange = flange_transform(self.robot, q)
            rotation = flange[:3, :3]
            accelerometer = (rotation.T @ [0.0, 0.0, STANDARD_GRAVITY]).tolist()
            load = self.tool.wrench_in_sensor(rotation)
            self._kinematics = (rotation, pose_vector(flange).tolist(), accelerometer, load)
            self._kinematics_key = key
        return self._kinematics

    def noise(self) -> np.ndarray:
        if self._noise_index >= len(self._noise):
            scale = np.repeat([self.tool.force_noise, self.tool.torque_noise], 3)
            self._noise, self._noise_index = self.rng.normal(0.0, 1.0, (500, 6)) * scale, 0
        self._noise_index += 1
        return self._noise[self._noise_index - 1]

    def values(self, now: float) -> dict:
        """The dynamic outputs of this tick (:data:`DYNAMIC`'s keys)."""
        q, dq = self.arm.state(now)
        rotation, pose, accelerometer, load = self.kinematics(q)
        measured = load + self.noise()
        reported = (
            np.concatenate([rotation @ measured[:3], rotation @ measured[3:]])
            if self.tool.wrench_frame == "base"
            else measured
        )
        timestamp = START_TIMESTAMP + self.tick * CONTROLLER_PERIOD
        self.last = {"timestamp": timestamp, "q": q.tolist(), "wrench_in_sensor": measured.tolist()}
        return {
            "timestamp": [timestamp],
            "q": q.tolist(),
            "dq": dq.tolist(),
            "pose": pose,
            "wrench": reported.tolist(),
            "accelerometer": accelerometer,
        }

    # -- control from the test
    def control(self, now: float) -> None:
        while self.pipe.poll():
            command, *arguments = self.pipe.recv()
            reply = None
            if command == "pose":
                self.arm.move(arguments[0], 0.0, now)
            elif command == "move":
                self.arm.move(arguments[0], arguments[1], now)
            elif command == "tool":
                self.tool = SimulatedTool(**{**asdict(self.tool), **arguments[0]})
                self._noise_index = len(self._noise)  # new noise levels from the next package
                self._kinematics_key = None
            elif command == "freeze":
                self.frozen = bool(arguments[0])
            elif command == "sent":
                reply = list(self.sent)
            elif command == "state":
                reply = {
                    **self.last,
                    "requested": self.requested,
                    "late": self.late,
                    "clients": len(self.clients),
                    "started": sum(client.started for client in self.clients),
                    "moving": bool(self.arm.state(now)[1].any()),
                }
            self.pipe.send(("ok", reply))

    # -- the network
    def serve_clients(self) -> None:
        while True:  # new clients
            try:
                connection, _ = self.listener.accept()
            except BlockingIOError:
                break
            self.clients.append(_Client(connection))
        for client in list(self.clients):
            try:
                for command, payload in client.packets():
                    names = client.answer(command, payload)
                    if names is not None:
                        self.requested = names
            except OSError:  # closed or reset by the client
                self.drop(client)

    def drop(self, client: _Client) -> None:
        client.connection.close()
        self.clients.remove(client)

    def publish(self, now: float) -> None:
        """One controller tick: a package to every started client due at this tick."""
        due = [c for c in self.clients if c.started and self.tick % c.every == 0]
        if due:
            values = self.values(now)
            for client in due:
                try:
                    client.send("U", client.package(values))
                except OSError:
                    self.drop(client)
            self.sent.append((values["timestamp"][0], time.monotonic()))

    def run(self) -> None:
        self.pipe.send(("ready", None))
        clock = time.monotonic
        next_tick = clock()
        while True:
            now = clock()
            self.control(now)
            self.serve_clients()
            if self.dashboard is not None:
                self.dashboard.serve()
            if now >= next_tick:
                if not self.frozen:  # a frozen controller's clock stands still
                    self.publish(now)
                    self.tick += 1
                if now - next_tick > CONTROLLER_PERIOD:  # a tick sent a period late or more
                    self.late += any(client.started for client in self.clients)
                next_tick += CONTROLLER_PERIOD
                if now - next_tick > 0.5:  # stopped by the scheduler: do not burst
                    next_tick = now
            time.sleep(min(max(next_tick - clock(), 0.0), 0.0005))


def _serve(address: str, robot: str, q0, tool: dict, pipe, dashboard=None) -> None:
    try:
        server = _Server(address, robot, q0, tool, pipe, dashboard)
    except OSError as error:
        pipe.send(("error", f"{type(error).__name__}: {error}"))
        return
    try:
        server.run()
    except (EOFError, OSError):  # the test's end of the pipe is gone: stop
        return


def main(argv: list[str]) -> None:
    """The child process: ``rtde_controller.py FD CONFIG_JSON`` (the pipe's file descriptor)."""
    from multiprocessing.connection import Connection

    config = json.loads(argv[2])
    _serve(
        config["address"],
        config["robot"],
        config["q"],
        config["tool"],
        Connection(int(argv[1])),
        config.get("dashboard"),
    )


# ---------------------------------------------------------------- the test's handle
class EmulatedController:
    """A controller emulator in a child process, on ``host``:30004.

    Args:
        robot: Which arm's kinematics (a key of :data:`DH`).
        q: Start pose ``(6,)`` [rad].
        dashboard: What its Dashboard Server answers to ``get robot model`` (``"UR5"``); None:
            no Dashboard Server (nothing listens on port 29999).
        tool: :class:`SimulatedTool` fields.
    """

    def __init__(
        self,
        robot: str = "ur5e",
        q=(0.0, -1.5, 1.4, -1.2, -1.6, 0.3),
        *,
        dashboard: str | None = None,
        **tool,
    ):
        self.robot = robot
        rng = random.Random(os.getpid() * 7919 + time.monotonic_ns())
        self.host = f"127.{rng.randint(1, 254)}.{rng.randint(1, 254)}.{rng.randint(1, 254)}"
        ours, theirs = socket.socketpair()
        config = {"address": self.host, "robot": robot, "q": list(map(float, q)), "tool": tool}
        config["dashboard"] = dashboard
        self.process = subprocess.Popen(
            [sys.executable, __file__, str(theirs.fileno()), json.dumps(config)],
            pass_fds=(theirs.fileno(),),
            stdin=subprocess.DEVNULL,
        )
        theirs.close()
        self._pipe = Connection(ours.detach())
        if not self._pipe.poll(20.0):
            self.kill()
            raise RuntimeError("the RTDE controller emulator did not start within 20 s")
        status, detail = self._pipe.recv()
        if status != "ready":
            self.process.wait(2.0)
            raise OSError(
                f"the RTDE controller emulator cannot listen on {self.host}:{PORT}: {detail}"
            )

    def _call(self, *message):
        self._pipe.send(message)
        if not self._pipe.poll(5.0):
            raise RuntimeError(f"the emulator did not answer {message[0]!r}")
        return self._pipe.recv()[1]

    def set_pose(self, q) -> None:
        """Put the arm at ``q`` [rad] now (no motion)."""
        self._call("pose", list(map(float, q)))

    def move(self, q, duration: float) -> None:
        """Move to ``q`` [rad] in ``duration`` [s] (a cosine blend: zero speed at both ends)."""
        self._call("move", list(map(float, q)), float(duration))

    def set_tool(self, **fields) -> None:
        """Change :class:`SimulatedTool` fields (contact, wrench_frame, noise, ...)."""
        self._call("tool", fields)

    def freeze(self, frozen: bool = True) -> None:
        """Stop (or resume) sending packages; the connection stays up."""
        self._call("freeze", frozen)

    def state(self) -> dict:
        """The last package sent (timestamp, q, the wrench in the sensor frame) and more."""
        return self._call("state")

    def sent(self) -> list[tuple[float, float]]:
        """``(timestamp, time.monotonic() when sent)`` of the packages sent (the last 60 000)."""
        return self._call("sent")

    def kill(self) -> None:
        """SIGKILL the controller process (its socket closes)."""
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait(5.0)

    def close(self) -> None:
        self.kill()
        self._pipe.close()

    def __enter__(self) -> EmulatedController:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


if __name__ == "__main__":
    main(sys.argv)
