"""Every RTDE data package of a UR controller, in order: what a log that misses none reads.

ur_rtde's ``RTDEReceiveInterface`` (:class:`~ftkin.robot.ur.UrArm`) keeps the newest package:
a client that polls its getters less often than the controller sends (a loaded machine, a pause of
the interpreter) skips packages, and its receive thread does too when it falls behind (its own
file recording included: 35 of 1501 packages were missing at load 1, ur_rtde 1.6.5 against
``tests/robot/rtde_controller.py``). A log that must hold every package reads them itself:
:class:`RtdePackages` opens a second RTDE connection (a controller serves several clients), asks
for ``timestamp``, ``actual_q`` and ``ft_raw_wrench``, and reads the packages from its socket in
the order they came. TCP keeps them while the reader is late: none is lost, some are late.

The protocol, from UR's "Real-Time Data Exchange (RTDE) Guide" (protocol version 2): a packet is
``>HB`` (its size including the 3-byte header, its command) then the payload, big-endian.

* ``V`` request protocol version: ``>H`` 2; answer ``>B`` accepted;
* ``O`` setup outputs: ``>d`` frequency [Hz], then the names, comma-separated; answer ``>B``
  recipe id, then the types, comma-separated (``NOT_FOUND`` for an unknown name);
* ``S`` start: answer ``>B`` accepted; then ``U`` data packages: ``>B`` recipe id, then the
  fields in the order asked (``DOUBLE`` ``>d``, ``VECTOR6D`` ``>6d``);
* ``M`` text messages from the controller may come at any time (skipped).
"""

from __future__ import annotations

import socket
import struct
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput, RobotConnectionLost

PORT = 30004
"""The RTDE port of a UR controller."""
PROTOCOL_VERSION = 2
OUTPUTS = ("timestamp", "actual_q", "ft_raw_wrench")
"""What the reader asks for: the controller's clock [s], the joints [rad], the built-in sensor's
wrench [N, N·m] (base axes on a UR: see :class:`~ftkin.robot.ur.UrArm`)."""
TYPES = ("DOUBLE", "VECTOR6D", "VECTOR6D")
_HEADER = struct.Struct(">HB")
_PACKAGE = struct.Struct(">B13d")  # recipe id, timestamp, actual_q, ft_raw_wrench
DEFAULT_TIMEOUT = 1.0
"""No package for this long [s] is a lost controller."""


@dataclass(frozen=True)
class Packages:
    """Consecutive data packages, in the order sent.

    Attributes:
        timestamps: ``(n,)`` the controller's clock [s].
        joint_positions: ``(n, 6)`` ``actual_q`` [rad].
        wrenches: ``(n, 6)`` ``ft_raw_wrench`` [N, N·m], as the controller sent it.
    """

    timestamps: np.ndarray
    joint_positions: np.ndarray
    wrenches: np.ndarray

    def __len__(self) -> int:
        return len(self.timestamps)


class RtdePackages:
    """An RTDE connection that reads every data package (module docstring).

    Args:
        host: The controller's address (port 30004).
        frequency: Packages per second asked for [Hz] (an e-Series sends up to 500).
        timeout: No answer or no package for this long is a lost controller [s].

    Raises:
        InvalidInput: a bad argument.
        RobotConnectionLost: nothing answers at ``host``, or the controller refused the setup
            (the message says which step).
    """

    def __init__(self, host: str, *, frequency: float = 500.0, timeout: float = DEFAULT_TIMEOUT):
        if not isinstance(host, str) or not host.strip():
            raise InvalidInput(f"host must be the controller's address, got {host!r}")
        if not (isinstance(frequency, int | float) and 0.0 < frequency <= 500.0):
            raise InvalidInput(f"frequency must be in (0, 500] Hz, got {frequency!r}")
        if not (isinstance(timeout, int | float) and 0.0 < timeout < 60.0):
            raise InvalidInput(f"timeout must be in (0, 60) s, got {timeout!r}")
        self.host, self.timeout = host, float(timeout)
        self._buffer = bytearray()
        try:
            self._socket = socket.create_connection((host, PORT), timeout=self.timeout)
        except OSError as error:
            raise RobotConnectionLost(
                f"cannot read RTDE from {host} (port {PORT})", host, str(error)
            ) from None
        self._socket.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        try:
            self._setup(float(frequency))
        except BaseException:
            self.close()
            raise

    def _setup(self, frequency: float) -> None:
        accepted = self._ask("V", struct.pack(">H", PROTOCOL_VERSION))
        if not accepted or not accepted[0]:
            self._refused(f"RTDE protocol version {PROTOCOL_VERSION}")
        answer = self._ask("O", struct.pack(">d", frequency) + ",".join(OUTPUTS).encode())
        types = tuple(answer[1:].decode(errors="replace").split(",")) if answer else ()
        if types != TYPES:
            self._refused(f"the outputs {', '.join(OUTPUTS)} (it answered {types})")
        self.recipe = answer[0]
        started = self._ask("S", b"")
        if not started or not started[0]:
            self._refused("the start of the data packages")

    def _refused(self, what: str):
        raise RobotConnectionLost(f"the controller at {self.host} refused {what}", self.host)

    def _ask(self, command: str, payload: bytes) -> bytes:
        """Send one packet; the payload of the controller's answer to it (text skipped)."""
        self._socket.sendall(_HEADER.pack(3 + len(payload), ord(command)) + payload)
        while True:
            kind, body = self._packet()
            if kind == ord(command):
                return body

    def _packet(self) -> tuple[int, bytes]:
        """The next whole packet ``(command, payload)``, reading the socket as needed."""
        while True:
            if len(self._buffer) >= 3:
                size, kind = _HEADER.unpack_from(self._buffer)
                if size < 3:
                    raise RobotConnectionLost(
                        f"the RTDE stream from {self.host} is corrupt (a packet of {size} bytes)",
                        self.host,
                    )
                if len(self._buffer) >= size:
                    body = bytes(self._buffer[3:size])
                    del self._buffer[:size]
                    return kind, body
            self._receive()

    def _receive(self) -> None:
        try:
            chunk = self._socket.recv(65536)
        except TimeoutError:
            raise RobotConnectionLost(
                f"no RTDE data from {self.host} for {self.timeout:g} s", self.host
            ) from None
        except OSError as error:
            raise RobotConnectionLost(
                f"the RTDE connection to {self.host} failed", self.host, str(error)
            ) from None
        if not chunk:
            raise RobotConnectionLost(f"the controller at {self.host} closed RTDE", self.host)
        self._buffer += chunk

    def read(self) -> Packages:
        """The data packages that have come since the last call (at least one: it waits up to
        ``timeout`` for the first), in the order sent.

        Raises:
            RobotConnectionLost: no package within ``timeout``, the connection closed, or a
                package that is not the recipe's.
        """
        rows = []
        while not rows or len(self._buffer) >= 3:
            if rows:  # more packets may be whole in the buffer: take them without waiting
                size, _ = _HEADER.unpack_from(self._buffer)
                if len(self._buffer) < size:
                    break
            kind, body = self._packet()
            if kind != ord("U"):
                continue  # a text message
            if len(body) != _PACKAGE.size or body[0] != self.recipe:
                raise RobotConnectionLost(
                    f"an RTDE package from {self.host} is not the recipe asked for "
                    f"({len(body)} bytes, recipe {body[:1].hex()})",
                    self.host,
                )
            rows.append(_PACKAGE.unpack(body)[1:])
        values = np.array(rows)
        return Packages(values[:, 0], values[:, 1:7], values[:, 7:13])

    def close(self) -> None:
        """Close the connection (the controller stops sending to it)."""
        self._socket.close()

    def __enter__(self) -> RtdePackages:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
