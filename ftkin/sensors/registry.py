"""Sensors by name: ``--sensor ati|bota`` with typed options, or ``MODULE:FACTORY`` for any other.

``ftkin robot calibrate --sensor ati --sensor-option host=192.168.1.1`` opens
:class:`~ftkin.sensors.ati.AtiNetFT`; ``--sensor bota --sensor-option config=bota.json`` opens
:class:`~ftkin.sensors.bota.BotaSensor`. Each built-in adapter declares its options once, in its
module's ``REGISTRATION`` (a :class:`SensorEntry`): name, type, unit and help, the default read
from the adapter's own signature. An unknown option is refused with the known ones named.

``--sensor my_lab.sensors:bota_serial`` imports ``my_lab.sensors`` and calls ``bota_serial()``
with the ``--sensor-option`` values as string keyword arguments; the object it returns must have
``read() -> (t [s], wrench (6,))`` (:class:`~ftkin.robot.protocols.ForceTorqueSensor`).
"""

from __future__ import annotations

import importlib
import inspect
import math
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass

from ..exceptions import FtkinError, InvalidInput

BUILT_IN = ("ati", "bota")
"""The built-in sensors, each a module ``ftkin.sensors.<name>`` with a ``REGISTRATION``."""

_SPEC = re.compile(r"^[A-Za-z_][\w.]*:[A-Za-z_]\w*$")
_TYPE_NAMES = {str: "text", int: "an integer", float: "a number"}


@dataclass(frozen=True)
class SensorOption:
    """One keyword of an adapter, as ``--sensor-option NAME=VALUE``.

    Attributes:
        name: The keyword (and the option's name on the command line).
        type: ``str``, ``int`` (decimal or ``0x`` hexadecimal) or ``float``.
        help: What it does, one line.
        unit: Its unit (``"s"``), or ``""``.
    """

    name: str
    type: type
    help: str
    unit: str = ""

    def parse(self, value, sensor: str):
        """``value`` (a command-line string, or already a value) as :attr:`type`.

        Raises:
            InvalidInput: the string is not of the type (the message names the option).
        """
        if not isinstance(value, str):
            return value
        text = value.strip()
        try:
            if self.type is int:
                return int(text, 0)
            if self.type is float:
                number = float(text)
                if not math.isfinite(number):
                    raise ValueError(text)
                return number
        except ValueError:
            unit = f" [{self.unit}]" if self.unit else ""
            raise InvalidInput(
                f"--sensor {sensor}: {self.name} must be {_TYPE_NAMES[self.type]}{unit}, "
                f"got {value!r}"
            ) from None
        if not text:
            raise InvalidInput(f"--sensor {sensor}: {self.name} must not be empty")
        return text


@dataclass(frozen=True)
class SensorEntry:
    """A built-in sensor: its name, what opens it, its options.

    Attributes:
        name: The ``--sensor`` name.
        summary: One line: the sensor and the vendor client it runs on.
        factory: The adapter class (its signature gives each option's default).
        options: Its options, every keyword of ``factory``.
    """

    name: str
    summary: str
    factory: Callable
    options: tuple[SensorOption, ...]

    def defaults(self) -> dict[str, object]:
        """``{option: default}``; a required option is absent."""
        parameters = inspect.signature(self.factory).parameters
        return {
            option.name: parameters[option.name].default
            for option in self.options
            if parameters[option.name].default is not inspect.Parameter.empty
        }

    def describe(self) -> str:
        """The options in one line: ``host (required): ..., rdt_port=49152: ...``."""
        defaults = self.defaults()
        parts = []
        for option in self.options:
            unit = f" [{option.unit}]" if option.unit else ""
            value = f"={defaults[option.name]!r}" if option.name in defaults else " (required)"
            parts.append(f"{option.name}{value}{unit}: {option.help}")
        return "; ".join(parts)

    def open(self, options: Mapping[str, object]):
        """The sensor, opened with ``options`` (strings are parsed by each option's type).

        Raises:
            InvalidInput: an unknown option (the known ones are named), a missing required one,
                or a value of the wrong type.
        """
        known = {option.name: option for option in self.options}
        unknown = sorted(set(options) - set(known))
        if unknown:
            raise InvalidInput(
                f"--sensor {self.name} has no option {', '.join(map(repr, unknown))}; its "
                f"options are {self.describe()}"
            )
        missing = [name for name in known if name not in options and name not in self.defaults()]
        if missing:
            raise InvalidInput(
                f"--sensor {self.name} needs "
                + ", ".join(f"--sensor-option {name}=..." for name in missing)
                + f" ({'; '.join(known[name].help for name in missing)})"
            )
        values = {name: known[name].parse(value, self.name) for name, value in options.items()}
        return self.factory(**values)


def sensor_entry(name: str) -> SensorEntry:
    """The registration of the built-in sensor ``name`` (its module is imported; the vendor's
    package is not).

    Raises:
        InvalidInput: ``name`` is not built in (the message names the built-in ones).
    """
    if name not in BUILT_IN:
        raise InvalidInput(
            f"unknown sensor {name!r}: built in are {', '.join(BUILT_IN)}; name any other as "
            "MODULE:FACTORY (e.g. my_lab.sensors:bota)"
        )
    return importlib.import_module(f".{name}", __package__).REGISTRATION


def open_sensor(spec: str, options: Mapping[str, object] | None = None):
    """The sensor named ``spec``: a built-in name (:data:`BUILT_IN`) or ``MODULE:FACTORY``.

    Args:
        spec: ``"ati"``, ``"bota"`` or ``"module.path:factory"``.
        options: The ``--sensor-option`` values by name (strings from the command line are
            parsed by the built-in sensor's option types; a factory gets them as given).

    Raises:
        InvalidInput: an unknown name, a malformed spec, a bad option (see
            :meth:`SensorEntry.open`), or a factory that fails.
        SensorError: a built-in sensor that cannot be opened (``kind`` says why).
        MissingDependency: the vendor's package is not installed (the message names the extra).
    """
    options = dict(options or {})
    if isinstance(spec, str) and ":" in spec:
        return load_sensor_factory(spec, **options)
    if not isinstance(spec, str):
        raise InvalidInput(f"a sensor is named by a string, got {spec!r}")
    return sensor_entry(spec).open(options)


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
    except FtkinError:  # already says what is wrong (a SensorError, a MissingDependency, ...)
        raise
    except Exception as error:  # a vendor driver may raise anything while connecting
        raise InvalidInput(
            f"the sensor factory {spec} failed: {type(error).__name__}: {error}"
        ) from None
    if not callable(getattr(sensor, "read", None)):
        raise InvalidInput(
            f"{spec} returned a {type(sensor).__name__}, which has no read() -> (t, wrench (6,))"
        )
    return sensor
