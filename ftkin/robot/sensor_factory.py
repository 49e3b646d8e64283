"""A sensor named on the command line: ``MODULE:FACTORY`` imported and called.

``ftkin robot calibrate --sensor my_lab.sensors:bota_serial`` imports ``my_lab.sensors`` and calls
``bota_serial()``; the object it returns must have ``read() -> (t [s], wrench (6,))``
(:class:`~ftkin.robot.protocols.ForceTorqueSensor`). docs/robot.md shows such factories for a
Bota driver, an ATI Net F/T and UR's built-in sensor.
"""

from __future__ import annotations

import importlib
import re

from ..exceptions import InvalidInput

_SPEC = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")


def load_sensor_factory(spec: str, *args, **kwargs):
    """Import ``MODULE:FACTORY`` and return ``FACTORY(*args, **kwargs)``, checked to be a sensor.

    Raises:
        InvalidInput: the spec is malformed, the module or the factory is missing, the factory
            fails, or what it returns has no ``read()``.
    """
    if not isinstance(spec, str) or not _SPEC.match(spec):
        raise InvalidInput(
            f"a sensor factory is named MODULE:FACTORY (e.g. my_lab.sensors:bota), got {spec!r}"
        )
    module_name, factory_name = spec.split(":")
    try:
        module = importlib.import_module(module_name)
    except ImportError as error:
        raise InvalidInput(
            f"cannot import the sensor module {module_name!r}: {error} (is it on PYTHONPATH?)"
        ) from None
    factory = getattr(module, factory_name, None)
    if not callable(factory):
        raise InvalidInput(f"{module_name!r} has no callable {factory_name!r}")
    try:
        sensor = factory(*args, **kwargs)
    except Exception as error:  # a vendor driver may raise anything while connecting
        raise InvalidInput(
            f"the sensor factory {spec} failed: {type(error).__name__}: {error}"
        ) from None
    if not callable(getattr(sensor, "read", None)):
        raise InvalidInput(
            f"{spec} returned a {type(sensor).__name__}, which has no read() -> (t, wrench (6,))"
        )
    return sensor
