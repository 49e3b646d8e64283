"""The drawing side of :class:`~ftkin.viz.live.LiveView`: a separate process with its own meshcat
server.

The control process and this one share one small block of memory (a
:class:`StateLayout`): a sequence counter, the joint angles, the contact
wrench and the commanded twist. Only the control process's sampler thread
writes it (seqlock: the counter is odd while a write is in progress); this
process reads it at the view's frame rate, draws the arm, the contact force
and torque at the sensor and the commanded linear and angular velocity at the
control point, and counts the frames it drew.
"""

import os
import pickle
import sys
import time
from dataclasses import dataclass
from multiprocessing import resource_tracker, shared_memory

import numpy as np

from ..control.control_frame import ControlFrame
from .arrows import ArrowStyle, add_arrow_objects, arrow_placement
from .legend import CONTACT, Layer
from .server import import_meshcat, load_arm, start_visualizer, stop_server

TORQUE = Layer("torque", 0xFF8000, "contact torque, R_BS M′ (right-hand axis)")
VELOCITY = Layer("velocity", 0x00C000, "commanded linear velocity at the control point")
ANGULAR = Layer("angular", 0x0060FF, "commanded angular velocity (right-hand axis)")
LIVE_LAYERS = (CONTACT, TORQUE, VELOCITY, ANGULAR)
"""Arrows of the live view."""


class StateLayout:
    """Float64 slots of the shared block: ``[seq, q (nq), wrench (6), twist (6), frames drawn,
    stop]``.

    Attributes:
        nq: Number of joint angles.
        size: Number of float64 slots.
        body: Slice of ``q``, wrench and twist together (what the sampler writes).
        frames: Index of the drawn-frames counter (written by the view process).
        stop: Index of the stop flag (set to 1 by the control process).
    """

    def __init__(self, nq: int):
        self.nq, self.size, self.body = nq, nq + 15, slice(1, 13 + nq)
        self.frames, self.stop = 13 + nq, 14 + nq


@dataclass(frozen=True)
class ViewSettings:
    """What the view process needs (picklable).

    Attributes:
        arm: The :class:`~ftkin.kinematics.arm.Arm` (pickled to the process).
        shared_name: Name of the shared-memory block.
        fps: Frames per second drawn [1/s].
        force_scale: Arrow length per newton [m/N] (torque: per N·m).
        twist_scale: Arrow length per m/s (angular: per rad/s) [s].
        control_frame: The :class:`~ftkin.control.control_frame.ControlFrame` of the published
            twist: its axes and the control point.
        zmq_url: A running meshcat server to draw into, or None to start one.
    """

    arm: object
    shared_name: str
    fps: float
    force_scale: float
    twist_scale: float
    control_frame: ControlFrame
    zmq_url: str | None


def read_state(
    state: np.ndarray, layout: StateLayout, last_seq: float
) -> tuple[float, np.ndarray | None]:
    """A consistent copy of ``state[layout.body]`` newer than ``last_seq``, else None (seqlock
    read).
    """
    for _ in range(100):
        seq = state[0]
        if seq == last_seq:
            return last_seq, None
        if int(seq) % 2 == 1:
            time.sleep(0)
            continue
        body = state[layout.body].copy()
        if state[0] == seq:
            return seq, body
    return last_seq, None


def run_view(settings: ViewSettings, report) -> None:
    """Body of the view process: start meshcat, ``report(kind, text)`` its URL, draw until told to
    stop.

    Stops when the stop flag is set or the parent process is gone.
    """
    arm = settings.arm
    layout = StateLayout(arm.nq)
    block = shared_memory.SharedMemory(name=settings.shared_name)
    try:  # keep this process's resource tracker from unlinking the parent's block (Python < 3.13)
        resource_tracker.unregister(block._name, "shared_memory")
    except Exception:  # noqa: BLE001 - only a warning at exit is at stake
        pass
    state = np.ndarray((layout.size,), dtype=np.float64, buffer=block.buf)
    visualizer = None
    try:
        meshcat = import_meshcat()
        visualizer = start_visualizer(settings.zmq_url)
        robot = load_arm(arm, visualizer)
        style = ArrowStyle()
        for layer in LIVE_LAYERS:
            material = meshcat.geometry.MeshBasicMaterial(color=layer.color)
            add_arrow_objects(visualizer[f"live/{layer.name}"], meshcat.geometry, style, material)
        batch = PipelinedSender(visualizer.window)
        report("ready", visualizer.url())
    except BaseException as error:  # report to the parent instead of dying silently
        report("error", f"{type(error).__name__}: {error}")
        block.close()
        if visualizer is not None:
            stop_server(visualizer)
        return
    parent, period, seq = os.getppid(), 1.0 / settings.fps, -1.0
    try:
        while state[layout.stop] == 0.0 and os.getppid() == parent:
            start = time.perf_counter()
            seq, body = read_state(state, layout, seq)
            if body is not None:
                _draw(visualizer, robot, arm, settings, body, style)
                batch.flush()
                state[layout.frames] += 1.0
            time.sleep(max(period - (time.perf_counter() - start), 0.0))
    finally:
        del state
        block.close()
        batch.close()
        stop_server(visualizer)


class PipelinedSender:
    """Send meshcat commands without waiting for each reply; :meth:`flush` collects the replies.

    meshcat's client waits for the server's answer to every command (a REQ
    socket), about a millisecond each on a busy machine, and a frame of the
    arm is some twenty commands. A DEALER socket to the same REP server sends
    them back to back. Installed as the window's ``send`` once the scene is built.
    """

    def __init__(self, window):
        import umsgpack
        import zmq

        self._pack = umsgpack.packb
        self.socket = window.context.socket(zmq.DEALER)
        self.socket.connect(window.zmq_url)
        self.pending = 0
        window.send = self.send

    def send(self, command) -> None:
        data = command.lower()
        self.socket.send_multipart(
            [b"", data["type"].encode("utf-8"), data["path"].encode("utf-8"), self._pack(data)]
        )
        self.pending += 1

    def flush(self) -> None:
        while self.pending:
            self.socket.recv_multipart()
            self.pending -= 1

    def close(self) -> None:
        self.flush()
        self.socket.close(linger=0)


def _draw(
    visualizer, robot, arm, settings: ViewSettings, body: np.ndarray, style: ArrowStyle
) -> None:
    nq = arm.nq
    q, twist = body[:nq], body[nq + 6 :]
    wrench = np.nan_to_num(body[nq : nq + 6])  # a sensor-fault tick publishes NaN
    if not np.all(np.isfinite(q)):
        return
    robot.display(q)
    rotation, origin = arm.frame_placement(q, "sensor")
    control = settings.control_frame.placement_in_sensor(rotation)  # point r, axes R_SC
    point, twist_rotation = origin + rotation @ control.translation, rotation @ control.rotation
    vectors = (
        (CONTACT, origin, rotation @ wrench[:3], settings.force_scale),
        (TORQUE, origin, rotation @ wrench[3:], settings.force_scale),
        (VELOCITY, point, twist_rotation @ twist[:3], settings.twist_scale),
        (ANGULAR, point, twist_rotation @ twist[3:], settings.twist_scale),
    )
    for layer, start, vector, scale in vectors:
        arrow = arrow_placement(start, vector, scale, style)
        visualizer[f"live/{layer.name}/shaft"].set_transform(arrow.shaft.matrix())
        visualizer[f"live/{layer.name}/head"].set_transform(arrow.head.matrix())


def main() -> None:
    """The view process: pickled :class:`ViewSettings` on stdin, one status line on stdout, then
    draw.
    """
    run_view(pickle.loads(sys.stdin.buffer.read()), _report)


def _report(kind: str, text: str) -> None:
    print(f"{kind} {text}", flush=True)  # the status line the control process waits for
