"""Sensors: a vendor's client in, the newest wrench [N, N·m] and its stamp [s] out.

The built-in adapters satisfy :class:`~ftkin.robot.protocols.ForceTorqueSensor`, each in its
extra:

* :class:`AtiNetFT` (``ati``, pynetft): an ATI Net F/T box, every unit it reports converted to
  SI, its status word, a stalled ft_sequence and silence as faults; it never biases the box;
* :class:`BotaSensor` (``bota``, bota_driver): a Bota Systems sensor, its lifecycle managed,
  the IMU and the temperature in :meth:`~StreamingSensor.read_sample`.

``read() -> (t, wrench)`` returns the newest sample without blocking (a fraction of a
microsecond); ``read_sample()`` the whole :class:`SensorSample`. Both are context managers. A
fault raises :class:`~ftkin.exceptions.SensorError` whose ``kind`` names it
(:mod:`ftkin.sensors.stream` lists them) and latches until ``close()``. :func:`open_sensor`
opens a sensor by name (``ati``, ``bota``, or ``MODULE:FACTORY``), as ``--sensor`` does.

Depends on :mod:`ftkin.exceptions` only; the vendors' packages are imported when an adapter is
opened, with :class:`~ftkin.exceptions.MissingDependency` naming the extra when one is missing.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "AtiNetFT": ".ati",
    "BotaSensor": ".bota",
    "SensorEntry": ".registry",
    "SensorOption": ".registry",
    "SensorSample": ".sample",
    "StreamStats": ".sample",
    "StreamingSensor": ".stream",
    "load_sensor_factory": ".registry",
    "open_sensor": ".registry",
}
"""Public name → module, loaded on first access (PEP 562)."""

__all__ = sorted(_EXPORTS)
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
