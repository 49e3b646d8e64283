"""A live meshcat view of a control loop that costs the loop almost nothing.

:meth:`LiveView.publish` only swaps one reference (the latest ``(q, wrench,
twist)``); it neither copies, locks nor waits. A sampler thread in the
control process copies the latest state into a small shared-memory block at
the view's frame rate, and a separate process (:mod:`ftkin.viz.live_process`,
a fresh interpreter) draws it in meshcat: the arm, the contact force and
torque at the sensor and the commanded twist at the control point.

Attach to a :class:`~ftkin.control.joint_admittance.JointAdmittance` without
changing it::

    with LiveView.for_controller(controller) as view:
        print(view.url)
        loop = view.wrap(controller)  # loop.step(q, raw, dt) = controller.step + publish
        ...

or call ``view.publish(q, status.contact_wrench, status.twist)`` yourself.
The sampler thread takes the GIL for a few microseconds per frame (not per
tick); see ``benchmarks/bench_liveview.py`` for the cost per tick.
"""

import atexit
import os
import pickle
import select
import subprocess
import sys
import threading
from multiprocessing import shared_memory

import numpy as np

from ..control.control_frame import ControlFrame
from ..exceptions import FtkinError, InvalidInput
from ..kinematics.arm import Arm
from ..validation import as_positive
from .live_process import StateLayout, ViewSettings
from .server import import_meshcat

CHILD_COMMAND = "from ftkin.viz.live_process import main; main()"
"""What the view process runs (a fresh interpreter)."""

STARTUP_TIMEOUT = 120.0
"""Seconds to wait for the view process to start meshcat and load the arm [s]."""


class LiveView:
    """Draw the latest published state of a control loop in meshcat, from a separate process.

    Args:
        arm: The arm being controlled.
        control_frame: The controller's :class:`~ftkin.control.control_frame.ControlFrame`
            (axes of the published twist, control point); None: base axes at the sensor.
        fps: Frames drawn per second [1/s] (the sampler runs at the same rate).
        force_scale: Arrow length per newton (and per N·m) [m/N].
        twist_scale: Arrow length per m/s (and per rad/s) [s].
        zmq_url: Draw into a running meshcat server instead of starting one.
    """

    def __init__(
        self,
        arm: Arm,
        *,
        control_frame: ControlFrame | None = None,
        fps: float = 30.0,
        force_scale: float = 0.02,
        twist_scale: float = 2.0,
        zmq_url: str | None = None,
    ):
        if not isinstance(arm, Arm):
            raise InvalidInput(f"arm must be an ftkin Arm, got {type(arm).__name__}")
        if control_frame is not None and not isinstance(control_frame, ControlFrame):
            raise InvalidInput(
                "control_frame must be an ftkin ControlFrame or None, got "
                f"{type(control_frame).__name__}"
            )
        import_meshcat()  # fail here, with the extra's name, not in the child
        self.fps = as_positive(fps, "fps [1/s]")
        scales = (
            as_positive(force_scale, "force_scale [m/N]"),
            as_positive(twist_scale, "twist_scale [s]"),
        )
        self.layout = StateLayout(arm.nq)
        self._block = shared_memory.SharedMemory(create=True, size=8 * self.layout.size)
        self._state = np.ndarray((self.layout.size,), dtype=np.float64, buffer=self._block.buf)
        self._state[:] = 0.0
        self._latest = None
        self._closed = False
        self._stop = threading.Event()
        self._sampler = threading.Thread(
            target=self._sample, name="ftkin-liveview-sampler", daemon=True
        )
        frame = control_frame or ControlFrame("base")
        settings = ViewSettings(arm, self._block.name, self.fps, *scales, frame, zmq_url)
        self._process = subprocess.Popen(
            [sys.executable, "-c", CHILD_COMMAND],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in sys.path if p)),
        )
        atexit.register(self.close)
        try:
            self._process.stdin.write(pickle.dumps(settings))
            self._process.stdin.close()
        except BrokenPipeError:
            pass  # the process died at once: reported below as no answer
        # One status line (written at once), or nothing within the timeout.
        answered = select.select([self._process.stdout], [], [], STARTUP_TIMEOUT)[0]
        line = self._process.stdout.readline() if answered else b""
        kind, _, message = line.decode("utf-8", "replace").partition(" ")
        if kind != "ready":
            self.close()
            reason = message.strip() or f"no answer within {STARTUP_TIMEOUT:g} s"
            raise FtkinError(f"the live view process failed: {reason}")
        self.url: str = message.strip()
        self._sampler.start()

    @classmethod
    def for_controller(cls, controller, **kwargs) -> "LiveView":
        """A view of a :class:`~ftkin.control.joint_admittance.JointAdmittance` (its arm and control
        frame).
        """
        return cls(controller.arm, control_frame=controller.frame, **kwargs)

    # --------------------------------------------------------------- hot path
    def publish(self, q, wrench, twist) -> None:
        """Hand over the latest state: joint angles [rad], contact wrench (sensor frame) [N, N·m],
        commanded twist.

        Keeps references only (no copy, no lock): pass arrays you do not change
        afterwards, or expect the view to show their newest values.
        """
        self._latest = (q, wrench, twist)

    def wrap(self, controller) -> "PublishingController":
        """``controller`` whose ``step`` also publishes its ``last_wrench_and_twist``."""
        return PublishingController(controller, self)

    # -------------------------------------------------------------- sampling
    def _sample(self) -> None:
        state, body, period = self._state, self._state[self.layout.body], 1.0 / self.fps
        sent = None
        while not self._stop.wait(period):
            latest = self._latest
            if latest is None or latest is sent:
                continue
            try:
                values = np.concatenate(
                    [np.asarray(v, dtype=np.float64).reshape(-1) for v in latest]
                )
            except (TypeError, ValueError):
                continue  # not numbers: nothing to draw
            if values.shape != body.shape:
                continue
            state[0] += 1.0  # odd: writing
            body[:] = values
            state[0] += 1.0
            sent = latest

    @property
    def frames_drawn(self) -> int:
        """Frames the view process has drawn so far."""
        return 0 if self._closed else int(self._state[self.layout.frames])

    @property
    def alive(self) -> bool:
        """Whether the view process is running."""
        return not self._closed and self._process.poll() is None

    # -------------------------------------------------------------- lifecycle
    def close(self, timeout: float = 10.0) -> None:
        """Stop the sampler and the view process (it stops its meshcat server); idempotent."""
        if self._closed:
            return
        self._closed = True
        atexit.unregister(self.close)
        self._stop.set()
        if self._sampler.is_alive():
            self._sampler.join(timeout)
        self._state[self.layout.stop] = 1.0
        try:
            self._process.wait(timeout)
        except subprocess.TimeoutExpired:
            self._process.kill()
            self._process.wait(timeout)
        self._process.stdout.close()
        del self._state
        self._block.close()
        self._block.unlink()

    def __enter__(self) -> "LiveView":
        return self

    def __exit__(self, *exc_info) -> None:
        self.close()


class PublishingController:
    """A controller whose :meth:`step` publishes ``(q, contact_wrench, twist)`` of each tick to a
    :class:`LiveView`.

    Other attributes are the wrapped controller's.
    """

    def __init__(self, controller, view: LiveView):
        self.controller, self.view = controller, view
        self._step = controller.step

    def step(self, q, raw_wrench, dt: float) -> np.ndarray:
        """``controller.step(q, raw_wrench, dt)``, then publish its status."""
        dq = self._step(q, raw_wrench, dt)
        latest = self.controller.last_wrench_and_twist
        if latest is not None:
            self.view._latest = (q, *latest)
        return dq

    def __getattr__(self, name):
        return getattr(self.controller, name)
