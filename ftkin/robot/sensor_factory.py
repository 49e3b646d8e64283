"""A sensor named on the command line: ``MODULE:FACTORY``, now in :mod:`ftkin.sensors.registry`.

:func:`load_sensor_factory` stays importable from here and from :mod:`ftkin.robot`; the
registry also opens the built-in sensors by name (``--sensor ati``, ``--sensor bota``).
"""

from ..sensors.registry import load_sensor_factory

__all__ = ["load_sensor_factory"]
