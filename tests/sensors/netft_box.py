"""An ATI Net F/T box on loopback, written from ATI's public RDT and netftapi2 description.

The box answers, as a real one does,

* HTTP ``GET /netftapi2.xml``: the calibration the client scales with, ``cfgcpf`` / ``cfgcpt``
  (counts per force / torque unit) and ``scfgfu`` / ``scfgtu`` (the unit names);
* UDP RDT requests ``>HHI`` (header 0x1234, command, sample count) on its RDT port: command
  0x0002 starts real-time streaming to the requesting address (count 0: until stopped), 0x0000
  stops it, 0x0042 is the software bias (only counted here: ftkin must never send it);

and streams 36-byte records ``>III6i`` (rdt_sequence, ft_sequence, status, Fx Fy Fz Tx Ty Tz in
counts) at a chosen rate. Faults are injected on demand: a status word, a stalled ft_sequence
(records keep coming with the acquisition frozen), silence (no records), lost records.

It runs in a child process (``python netft_box.py``, controlled by JSON lines on its stdin), so
the client's threads in the test process do not compete with it for the GIL at 7 kHz.
:class:`NetFTBox` is the test side. The wrench of record ``k`` is ``counts + dither(k)``
(:func:`dither`), known to the test exactly.
"""

from __future__ import annotations

import json
import os
import socket
import struct
import subprocess
import sys
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

REQUEST = struct.Struct(">HHI")
RECORD = struct.Struct(">III6i")
HEADER = 0x1234
STOP, START_REALTIME, BIAS = 0x0000, 0x0002, 0x0042
HOST = "127.0.0.1"


def dither(sequence: int, amplitude: int) -> list[int]:
    """The counts added to channel ``i`` of record ``sequence``: a known, never-constant pattern."""
    if amplitude == 0:
        return [0] * 6
    return [((sequence * 7919 + 104729 * i) % (2 * amplitude + 1)) - amplitude for i in range(6)]


# ------------------------------------------------------------------------------ the box (child)
class _Box:
    def __init__(self):
        self.lock = threading.Lock()
        self.calibration = {"cfgcpf": 1_000_000, "cfgcpt": 1_000_000, "scfgfu": "N", "scfgtu": "Nm"}
        self.rate = 1000.0
        self.counts = [0] * 6
        self.frozen = [0] * 6
        self.dither = 0
        self.status = 0
        self.fault = None  # None, "stall", "silence"
        self.drop_every = 0  # lose every n-th record (not sent, its sequence skipped)
        self.client = None
        self.rdt_sequence = 0
        self.ft_sequence = 0
        self.sent = 0
        self.first_sent = self.last_sent = None  # [s] monotonic, when records went out
        self.commands: dict[int, int] = {}
        self.http_requests = 0
        self.stream_generation = 0
        self.udp = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.udp.setsockopt(socket.SOL_SOCKET, socket.SO_SNDBUF, 1 << 20)
        self.udp.bind((HOST, 0))
        self.http = ThreadingHTTPServer((HOST, 0), _Handler)
        self.http.daemon_threads = True
        self.http.box = self

    def xml(self) -> bytes:
        with self.lock:
            fields = "".join(f"<{key}>{value}</{key}>" for key, value in self.calibration.items())
        return f'<?xml version="1.0"?><netft><prodname>emulated</prodname>{fields}</netft>'.encode()

    def serve_rdt(self) -> None:
        while True:
            payload, address = self.udp.recvfrom(64)
            if len(payload) != REQUEST.size:
                continue
            header, command, _count = REQUEST.unpack(payload)
            if header != HEADER:
                continue
            with self.lock:
                self.commands[command] = self.commands.get(command, 0) + 1
                if command == START_REALTIME:
                    self.client = address
                    self.stream_generation += 1
                    generation = self.stream_generation
                elif command == STOP:
                    self.client = None
                    self.stream_generation += 1
                    continue
                else:
                    continue
            threading.Thread(target=self.stream, args=(generation,), daemon=True).start()

    def stream(self, generation: int) -> None:
        start, due_sent = time.monotonic(), 0
        while True:
            with self.lock:
                if generation != self.stream_generation:
                    return
                rate = self.rate
            due = int((time.monotonic() - start) * rate) + 1
            while due_sent < due:
                self.send_one()
                due_sent += 1
            pause = due_sent / rate - (time.monotonic() - start)
            if pause > 0:
                time.sleep(pause)

    def send_one(self) -> None:
        with self.lock:
            if self.client is None or self.fault == "silence":
                return
            self.rdt_sequence += 1
            if self.drop_every and self.rdt_sequence % self.drop_every == 0:
                return
            if self.fault != "stall":
                self.ft_sequence += 1
                self.frozen = [
                    c + d for c, d in zip(self.counts, dither(self.rdt_sequence, self.dither))
                ]
            packet = RECORD.pack(self.rdt_sequence, self.ft_sequence, self.status, *self.frozen)
            client = self.client
            self.sent += 1
        self.udp.sendto(packet, client)
        now = time.monotonic()
        with self.lock:
            self.first_sent = self.first_sent or now
            self.last_sent = now

    def control(self, message: dict) -> dict:
        with self.lock:
            command = message.pop("command")
            if command == "set":
                for key, value in message.items():
                    if key == "calibration":
                        self.calibration.update(value)
                    elif key == "fault":
                        self.fault = value
                        if value is None:
                            self.status = 0
                    else:
                        setattr(self, key, value)
                return {"ok": True}
            if command == "stats":
                return {
                    "sent": self.sent,
                    "first_sent": self.first_sent,
                    "last_sent": self.last_sent,
                    "rdt_sequence": self.rdt_sequence,
                    "commands": {str(k): v for k, v in self.commands.items()},
                    "http_requests": self.http_requests,
                    "streaming": self.client is not None,
                    "now": time.monotonic(),
                }
        raise ValueError(f"unknown command {command!r}")


class _Handler(BaseHTTPRequestHandler):
    def do_GET(self):  # noqa: N802 (http.server's name)
        box = self.server.box
        with box.lock:
            box.http_requests += 1
        body, code = (box.xml(), 200) if self.path == "/netftapi2.xml" else (b"", 404)
        self.send_response(code)
        self.send_header("Content-Type", "text/xml")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

    def log_message(self, *args):
        pass


def _child() -> None:
    box = _Box()
    threading.Thread(target=box.serve_rdt, daemon=True).start()
    threading.Thread(
        target=box.http.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True
    ).start()
    ports = {"rdt_port": box.udp.getsockname()[1], "http_port": box.http.server_address[1]}
    print(json.dumps(ports), flush=True)
    for line in sys.stdin:
        try:
            reply = box.control(json.loads(line))
        except Exception as error:  # reported to the test, which raises it
            reply = {"error": f"{type(error).__name__}: {error}"}
        print(json.dumps(reply), flush=True)


# ------------------------------------------------------------------------------ the test side
class NetFTBox:
    """The emulated box in a child process; a context manager.

    Attributes:
        host: ``127.0.0.1``.
        rdt_port: The UDP RDT port it listens on.
        http_port: The HTTP port serving ``/netftapi2.xml``.
    """

    host = HOST

    def __init__(self, **settings):
        self.process = subprocess.Popen(
            [sys.executable, os.path.abspath(__file__)],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
            bufsize=1,
        )
        ports = json.loads(self.process.stdout.readline())
        self.rdt_port, self.http_port = ports["rdt_port"], ports["http_port"]
        if settings:
            self.set(**settings)

    def _ask(self, **message) -> dict:
        self.process.stdin.write(json.dumps(message) + "\n")
        self.process.stdin.flush()
        reply = json.loads(self.process.stdout.readline())
        if "error" in reply:
            raise RuntimeError(f"the emulated box refused {message}: {reply['error']}")
        return reply

    def set(self, **settings) -> None:
        """Change ``rate`` [Hz], ``counts`` (6 ints), ``dither`` [counts], ``status`` (the status
        word), ``fault`` (None, ``"stall"``, ``"silence"``; None also clears the status),
        ``drop_every`` (lose every n-th record), ``calibration`` (``{"cfgcpf": ..., ...}``)."""
        self._ask(command="set", **settings)

    def stats(self) -> dict:
        """``sent`` records (``first_sent``, ``last_sent``: when the first and the last went out
        [s, monotonic]), the last ``rdt_sequence``, RDT ``commands`` by number (as strings),
        ``http_requests``, ``streaming``, the box's ``now`` [s, monotonic]."""
        return self._ask(command="stats")

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.stdin.close()
            self.process.kill()
            self.process.wait(5)
        self.process.stdout.close()

    def __enter__(self) -> NetFTBox:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


if __name__ == "__main__":
    _child()
