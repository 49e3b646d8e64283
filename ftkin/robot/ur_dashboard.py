"""What a UR controller says it is: its Dashboard Server's ``get robot model`` and version.

The Dashboard Server listens on TCP port 29999 of CB3 and e-Series controllers (PolyScope 3 and 5;
PolyScope X has none). It greets a new connection with one line, then answers each command (one
line ending in ``\\n``) with one line. Two queries say which arm it is (UR's command list, as UR's
own client library ``Universal_Robots_Client_Library`` checks their answers):

* ``get robot model``: ``UR3``, ``UR5``, ``UR10``, ``UR16``, ``UR20``, ``UR30`` (from PolyScope
  3.12 and 5.6). It names the size, not the series: a ``UR5`` is a CB3 UR5 or an e-Series UR5e;
* ``PolyscopeVersion``: ``URSoftware 5.15.0.12345 (Dec 01 2026)``; major version 5 is an
  e-Series controller (and the UR20 and UR30), 3 a CB3.

Together they give ftkin's ``--robot`` name (:func:`robot_name`): ``UR5`` on PolyScope 5 is
``ur5e``. An e-Series controller may refuse commands outside remote-control mode, and a
dashboard can be switched off or firewalled: any answer that is not a model, or no answer within
``timeout``, leaves the model unknown (:attr:`ControllerModel.robot` None, ``reason`` says why)
and ftkin falls back to ``--robot``. Nothing here changes the controller's state.
"""

from __future__ import annotations

import logging
import re
import socket
from dataclasses import dataclass

from ..exceptions import InvalidInput

logger = logging.getLogger(__name__)

PORT = 29999
"""The Dashboard Server's port."""
DEFAULT_TIMEOUT = 1.0
"""Connecting and each answer may take this long [s] before the model counts as unknown."""
E_SERIES_MODELS = ("UR3", "UR5", "UR10", "UR16")
"""Sizes that exist as CB3 arms and as e-Series arms (``ur3e`` ...): PolyScope's major version
decides which."""
E_SERIES_ONLY = ("UR20", "UR30")
"""Sizes that exist on PolyScope 5 only (ftkin's ``ur20``, ``ur30``)."""
_MODEL = re.compile(r"^UR(\d+)(E?)$", re.IGNORECASE)
_VERSION = re.compile(r"^URSoftware\s+(\d+)\.(\d+)", re.IGNORECASE)


@dataclass(frozen=True)
class ControllerModel:
    """What the controller's dashboard said.

    Attributes:
        host: The controller's address.
        model: The answer to ``get robot model`` (``"UR5"``), or ``""`` without one.
        software: The answer to ``PolyscopeVersion`` (``"URSoftware 5.15.0.12345 (...)"``), or
            ``""``.
        robot: ftkin's ``--robot`` name (``"ur5e"``), or None when the answers do not decide it.
        reason: Why ``robot`` is None (``""`` when it is known).
    """

    host: str
    model: str
    software: str
    robot: str | None
    reason: str = ""

    def describe(self) -> str:
        """``"a UR5 on URSoftware 5.15.0.12345 (...) (--robot ur5e)"``, or why it is unknown."""
        said = " on ".join(part for part in (self.model, self.software) if part)
        if self.robot is not None:
            return f"{said} (--robot {self.robot})"
        return f"{said}: {self.reason}" if said else self.reason

    def check_robot(self, robot: str | None) -> None:
        """Refuse a ``--robot`` name the controller contradicts (nothing to compare when either
        is unknown: ``robot`` None is an arm from a URDF).

        Raises:
            InvalidInput: the dashboard names another arm; the message says both.
        """
        if robot is None or self.robot is None or robot == self.robot:
            return
        raise InvalidInput(
            f"--robot {robot} contradicts the controller at {self.host}: its dashboard says "
            f"{self.describe()}; give --robot {self.robot}, or leave --robot out"
        )


def robot_name(model: str, software: str = "") -> tuple[str | None, str]:
    """ftkin's ``--robot`` name from a dashboard's answers, and ``""``; or None and why not.

    ``model``: the answer to ``get robot model``; ``software``: to ``PolyscopeVersion`` (``""``
    when there was none).
    """
    match = _MODEL.match(model.strip())
    if match is None:
        return None, f"the dashboard answered {model.strip()!r} to 'get robot model', not a model"
    size = f"UR{int(match.group(1))}"
    if size in E_SERIES_ONLY:
        return size.lower(), ""
    if size not in E_SERIES_MODELS:
        return None, f"ftkin has no model of a {size}: give --urdf"
    if match.group(2):  # "UR5e": the series is in the name
        return f"{size.lower()}e", ""
    version = _VERSION.match(software.strip())
    if version is None:
        return None, (
            f"a {size} of either series (CB3 or e-Series): the dashboard gave no PolyScope "
            f"version ({software.strip()!r})"
        )
    major = int(version.group(1))
    if major == 5:
        return f"{size.lower()}e", ""
    if major == 3:
        return None, f"a CB3 {size} (PolyScope 3): ftkin has no CB3 model; give --urdf"
    return None, f"PolyScope {major} is not a known series for a {size}"


def ask_controller_model(host: str, *, timeout: float = DEFAULT_TIMEOUT) -> ControllerModel:
    """Ask the controller at ``host`` its model (module docstring); never raises for a
    controller that does not answer: the result's ``robot`` is None and ``reason`` says why.

    Raises:
        InvalidInput: a bad ``host`` or ``timeout``.
    """
    if not isinstance(host, str) or not host.strip():
        raise InvalidInput(f"host must be the controller's address, got {host!r}")
    if not (isinstance(timeout, int | float) and 0.0 < timeout <= 60.0):
        raise InvalidInput(f"timeout must be in (0, 60] s, got {timeout!r}")
    try:
        with socket.create_connection((host, PORT), timeout=timeout) as connection:
            stream = connection.makefile("rwb")
            _line(stream)  # the greeting
            model = _ask(stream, "get robot model")
            software = _ask(stream, "PolyscopeVersion") if _MODEL.match(model) else ""
    except (OSError, EOFError) as error:
        reason = f"no answer from its dashboard (port {PORT}): {error or type(error).__name__}"
        logger.info("%s: %s", host, reason)
        return ControllerModel(host, "", "", None, reason)
    robot, reason = robot_name(model, software)
    result = ControllerModel(host, model, software, robot, reason)
    logger.info("%s's dashboard: %s", host, result.describe())
    return result


def _ask(stream, command: str) -> str:
    stream.write(command.encode() + b"\n")
    stream.flush()
    return _line(stream)


def _line(stream) -> str:
    line = stream.readline(4096)
    if not line.endswith(b"\n"):
        raise EOFError("the dashboard closed the connection or sent no whole line")
    return line.decode(errors="replace").strip()
