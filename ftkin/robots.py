"""Robot models by name: ``--robot NAME`` on the command line.

``ftkin_c4`` is the bundled six-axis arm (default). Each entry says how to
load the URDF and where the sensor frame is.
"""

from __future__ import annotations

from collections.abc import Callable

from .arm import Arm
from .exceptions import InvalidInput

DEFAULT_ROBOT = "ftkin_c4"


def _bundled(sensor_offset=None) -> Arm:
    if sensor_offset is not None:
        raise InvalidInput("the bundled arm already has its ft_sensor frame; --sensor-offset is for robots without one")
    return Arm.default()


ROBOTS: dict[str, Callable[..., Arm]] = {
    DEFAULT_ROBOT: _bundled,
}
"""Loaders by robot name; each takes an optional ``SensorMount``-like offset."""


def load_robot(name: str, sensor_offset=None) -> Arm:
    """Load a robot by name (see :data:`ROBOTS`).

    Raises:
        InvalidInput: unknown name (the message lists the known ones).
    """
    if name not in ROBOTS:
        raise InvalidInput(f"unknown robot {name!r}; known robots: {', '.join(sorted(ROBOTS))}")
    return ROBOTS[name](sensor_offset)
