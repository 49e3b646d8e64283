"""The Bota driver in a process of its own, because its blocking read holds Python's GIL.

bota_driver 1.1's ``read_frame_blocking()`` keeps the GIL while it waits for the next frame (up
to a frame period, 3.7 ms at 270 Hz): a thread that calls it stalls every other thread of the
process, a control loop's included (measured here: pauses of up to 9 ms, half the main thread's
throughput gone). Its non-blocking ``read_frame()`` logs a warning on every call that finds no
frame. So the driver runs in a child process (this module's :func:`serve`) that
configures and activates it, takes every frame, stamps it with the host's ``time.monotonic()``
(one clock for every process of the machine) and writes it as a fixed-size record to a pipe; the
adapter's thread waits on the pipe, which releases the GIL. The driver's own log goes to the
terminal (the child's stderr) as it would in the parent.

The child's lifecycle: read the request (one JSON line on stdin: the configuration, a file path
or a ``BotaDriverConfig`` copied field by field, and the driver class), ``configure()``,
``activate()``, report ready (or the failure), stream until stdin closes or says ``stop``, then
``deactivate()`` and ``shutdown()``; a driver that raises is reported and released the same way.
"""

from __future__ import annotations

import importlib
import json
import os
import struct
import subprocess
import sys
import threading
import time

READY, FRAME, ERROR = b"R", b"F", b"E"
TIMESTEP = struct.Struct("<I")
"""After ``READY``: the driver's expected frame period [µs]."""
RECORD = struct.Struct("<dqB6d3d3dd")
"""After ``FRAME``: host stamp [s], the sensor's timestamp [µs], status flags (bits:
:data:`FLAGS`), force [N] and torque [N·m], acceleration [m/s²], angular rate [rad/s],
temperature [°C]."""
FLAGS = ("invalid", "overrange", "raw", "throttled")
"""``DataStatus`` flags, bit 0 first."""
LENGTHS = struct.Struct("<HI")
"""After ``ERROR``: the lengths of the kind and of the message (UTF-8 follows)."""
DEFAULT_DRIVER = "bota_driver:BotaDriver"


def dump_config(config) -> dict:
    """A ``bota_driver`` configuration object as nested dicts of its fields (``__class__``
    names each object's type), to be rebuilt in another process by :func:`load_config`."""
    if config is None or isinstance(config, (bool, int, float, str)):
        return config
    fields = {"__class__": type(config).__name__}
    for name in dir(config):
        if not name.startswith("_"):
            value = getattr(config, name)
            if not callable(value):
                fields[name] = dump_config(value)
    return fields


def load_config(fields, module):
    """The object :func:`dump_config` described, built from ``module``'s classes."""
    if not isinstance(fields, dict):
        return fields
    config = getattr(module, fields["__class__"])()
    for name, value in fields.items():
        if name != "__class__" and value is not None:
            setattr(config, name, load_config(value, module))
    return config


# ------------------------------------------------------------------------------------ parent
class DriverProcess:
    """The child process running the driver, seen from the adapter.

    Args:
        config: The JSON configuration's path, or :func:`dump_config` of a ``BotaDriverConfig``.
        driver: The driver class as ``MODULE:CLASS``, importable in the child.
    """

    def __init__(self, config, driver: str = DEFAULT_DRIVER):
        paths = [path for path in sys.path if path]  # this process's, first: the same ftkin
        start = f"import sys; sys.path[:0] = {paths!r}; from {__name__} import serve; serve()"
        self.process = subprocess.Popen(
            [sys.executable, "-c", start], stdin=subprocess.PIPE, stdout=subprocess.PIPE
        )
        request = json.dumps({"config": config, "driver": driver}) + "\n"
        self.process.stdin.write(request.encode())
        self.process.stdin.flush()

    def next(self):
        """The next message: ``(READY, timestep_us)``, ``(FRAME, fields)``, ``(ERROR, (kind,
        message))``, or None at the end of the stream. Blocks (without the GIL)."""
        stream = self.process.stdout
        tag = stream.read(1)
        if tag == READY:
            return READY, TIMESTEP.unpack(self._exactly(TIMESTEP.size))[0]
        if tag == FRAME:
            return FRAME, RECORD.unpack(self._exactly(RECORD.size))
        if tag == ERROR:
            kind_length, message_length = LENGTHS.unpack(self._exactly(LENGTHS.size))
            text = self._exactly(kind_length + message_length).decode()
            return ERROR, (text[:kind_length], text[kind_length:])
        return None

    def _exactly(self, size: int) -> bytes:
        data = self.process.stdout.read(size)
        if len(data) != size:
            raise EOFError("the Bota driver's process ended in the middle of a message")
        return data

    def stop(self) -> None:
        """Ask the child to deactivate and shut the driver down; never raises."""
        try:
            self.process.stdin.write(b"stop\n")
            self.process.stdin.close()
        except (OSError, ValueError):  # the child is gone already
            pass

    def wait(self, timeout: float) -> int | None:
        """The child's exit code, killing it if it does not end within ``timeout`` [s]."""
        try:
            return self.process.wait(timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.process.wait(timeout)
        finally:
            self.process.stdout.close()


# ------------------------------------------------------------------------------------- child
def _send(channel, tag: bytes, payload: bytes) -> None:
    channel.write(tag + payload)
    channel.flush()


def _error(channel, kind: str, message: str) -> None:
    kind_bytes, message_bytes = kind.encode(), message.encode()
    _send(
        channel,
        ERROR,
        LENGTHS.pack(len(kind_bytes), len(message_bytes)) + kind_bytes + message_bytes,
    )


def _frame_record(frame, stamp: float) -> bytes:
    status = frame.status
    flags = sum(1 << bit for bit, name in enumerate(FLAGS) if getattr(status, name))
    return RECORD.pack(
        stamp,
        int(frame.timestamp),
        flags,
        *frame.force,
        *frame.torque,
        *frame.acceleration,
        *frame.angular_rate,
        float(frame.temperature),
    )


def _open_driver(request: dict):
    module_name, class_name = request["driver"].split(":")
    driver_class = getattr(importlib.import_module(module_name), class_name)
    config = request["config"]
    if isinstance(config, dict):
        config = load_config(config, importlib.import_module("bota_driver"))
    return driver_class(config)


def serve() -> None:
    """The child's main: one driver, from the request on stdin to the end of the stream."""
    channel = os.fdopen(os.dup(1), "wb")  # the data pipe; the driver's log goes to stderr
    os.dup2(2, 1)
    request = json.loads(sys.stdin.readline())
    try:
        driver = _open_driver(request)
    except Exception as error:  # the driver refuses the configuration with any exception
        _error(channel, "connect", f"bota_driver refuses the configuration: {error}")
        return
    stopping = threading.Event()
    threading.Thread(target=lambda: (sys.stdin.read(), stopping.set()), daemon=True).start()
    try:
        for step in ("configure", "activate"):
            if not getattr(driver, step)():
                _error(channel, "connect", f"bota_driver's {step}() failed (its log says why)")
                return
        _send(channel, READY, TIMESTEP.pack(int(driver.get_expected_timestep_us())))
        while not stopping.is_set():
            frame = driver.read_frame_blocking()
            _send(channel, FRAME, _frame_record(frame, time.monotonic()))
    except BrokenPipeError:  # the adapter is gone
        return
    except Exception as error:  # the driver failed: report it, then release the driver
        _error(channel, "driver", f"{type(error).__name__}: {error}")
    finally:
        _release(driver)


def _release(driver) -> None:
    state = str(driver.get_driver_state())
    if state.endswith(".ACTIVE"):
        driver.deactivate()
    driver.shutdown()
