"""A Bota Systems sensor through bota_driver (extra ``bota``): wrench, IMU and temperature.

:class:`BotaSensor` runs the vendor's driver through its whole lifecycle: ``configure()`` and
``activate()`` when opened, then a thread that takes every frame with ``read_frame_blocking()``
and keeps the newest (:class:`~ftkin.sensors.stream.StreamingSensor`), and ``deactivate()`` and
``shutdown()`` when it ends, on :meth:`~StreamingSensor.close` or on a fault. Every call into the
driver after opening is made by that thread. bota_driver has no per-frame callback.

A frame carries ``force`` [N] and ``torque`` [N·m] (the sensor frame; Bota reports the load on
the sensor, ftkin's ``sensor_sign=+1``), ``acceleration`` [m/s²] and ``angular_rate`` [rad/s]
(the IMU frame), ``temperature`` [°C], a ``timestamp`` [µs, the sensor's clock] and a
``status``. The sample's ``t`` is the host's receive time on ``time.monotonic()``'s clock (the
sensor's own clock is not the host's); a frame with the previous frame's timestamp is a repeat,
not a new sample. ``acceleration`` is passed on as the sample's ``specific_force`` as the driver
gives it (bota_driver's dummy interface reads about −9.78 m/s² on z at rest; its sign on a
real sensor is the IMU calibration's to check, see docs/bota.md).

Faults: a frame whose status flags ``invalid``, ``overrange`` (a saturated channel) or ``raw``
(uncompensated counts, not N) is ``"status"``; ``throttled`` (the sensor thinned its stream to
fit the link) is counted in :attr:`BotaSensor.throttled`, not a fault. A driver call that raises
is ``"driver"``; frames whose timestamp stops advancing are ``"stall"`` and no frame at all
``"silence"``, both after ``silence_after``. The driver logs to the terminal itself (in colour,
also when ``runtime_verbosity`` is off).
"""

from __future__ import annotations

import logging
import math
import os
import time
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, SensorError
from .registry import SensorEntry, SensorOption
from .sample import SensorSample
from .stream import StreamingSensor

logger = logging.getLogger(__name__)

FAULT_FLAGS = ("invalid", "overrange", "raw")
"""``DataStatus`` flags that make a frame a fault."""


def _bota_driver():
    try:
        import bota_driver
    except ImportError:
        raise MissingDependency(
            "bota-driver", "bota", "the Bota sensor adapter (BotaSensor)"
        ) from None
    return bota_driver


def _read_only(values) -> np.ndarray:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array


class BotaSensor(StreamingSensor):
    """A Bota Systems sensor: ``read() -> (t [s], wrench (6,) [N, N·m])``, ``read_sample()``
    with the IMU and the temperature.

    Args:
        config: The vendor's JSON configuration file (a path), or a
            ``bota_driver.BotaDriverConfig``.
        silence_after: No new frame for this long is a fault [s] (``"silence"``, or
            ``"stall"`` when frames keep coming with a frozen timestamp).
        connect_timeout: Wait this long for the first frame after ``activate()`` [s].

    Attributes:
        timestep: The driver's expected frame period [s] (``get_expected_timestep_us()``).
        throttled: Frames the sensor flagged as throttled.

    Raises:
        InvalidInput: ``config`` is neither an existing file nor a ``BotaDriverConfig``.
        MissingDependency: bota_driver is not installed (``pip install 'ftkin[bota]'``).
        SensorError: ``"connect"``: the driver refused the configuration, ``configure()`` or
            ``activate()`` failed (its log says why), or no frame came in time.
    """

    def __init__(self, config, *, silence_after: float = 0.05, connect_timeout: float = 5.0):
        bota_driver = _bota_driver()
        if isinstance(config, (str, os.PathLike)):
            path = Path(config)
            if not path.is_file():
                raise InvalidInput(f"the Bota configuration file {str(path)!r} does not exist")
            source, description = str(path), f"the Bota sensor of {path.name}"
        elif isinstance(config, bota_driver.BotaDriverConfig):
            source = config
            description = (
                f"the Bota sensor {config.product_name or '?'} ({config.serial_number or '?'})"
            )
        else:
            raise InvalidInput(
                "config must be the path of a bota_driver JSON configuration or a "
                f"bota_driver.BotaDriverConfig, got {type(config).__name__}"
            )
        super().__init__(description, silence_after, connect_timeout)
        self.throttled = 0
        self.timestep = math.nan
        try:
            self._driver = bota_driver.BotaDriver(source)
        except Exception as error:  # the driver refuses a configuration with any exception
            raise SensorError(
                "connect", f"bota_driver refuses the configuration of {description}: {error}"
            ) from None
        for step in ("configure", "activate"):
            if not self._call(step):
                self._release()
                raise SensorError(
                    "connect",
                    f"{description}: bota_driver's {step}() failed (its log above says why)",
                )
        self.timestep = self._driver.get_expected_timestep_us() * 1e-6
        self._start()

    def _call(self, step: str) -> bool:
        try:
            return bool(getattr(self._driver, step)())
        except Exception as error:  # a driver call may raise anything
            logger.warning("%s: bota_driver's %s() raised %s", self.description, step, error)
            return False

    def _release(self) -> None:
        """Deactivate (when active) and shut the driver down; never raises."""
        state = str(self._driver.get_driver_state())
        if state.endswith("ACTIVE") and not state.endswith("INACTIVE"):
            self._call("deactivate")
        self._call("shutdown")

    def _stream(self) -> None:
        try:
            self._take_frames()
        finally:
            self._release()

    def _take_frames(self) -> None:
        driver, description = self._driver, self.description
        last_stamp = None
        while not self._closed:
            frame = driver.read_frame_blocking()
            now = time.monotonic()
            if self._closed:
                return
            status = frame.status
            flags = [flag for flag in FAULT_FLAGS if getattr(status, flag)]
            if flags:
                raise SensorError("status", f"{description} flags its frame {', '.join(flags)}")
            if frame.timestamp == last_stamp:
                self._repeat(now)
                continue
            last_stamp = frame.timestamp
            if status.throttled:
                self.throttled += 1
            wrench = _read_only([*frame.force, *frame.torque])
            specific_force = _read_only(frame.acceleration)
            angular_velocity = _read_only(frame.angular_rate)
            temperature = float(frame.temperature)
            total = wrench.sum() + specific_force.sum() + angular_velocity.sum() + temperature
            if not math.isfinite(total):
                raise SensorError(
                    "not_finite",
                    f"{description} sent a value that is not finite: wrench {wrench.tolist()}, "
                    f"acceleration {specific_force.tolist()}, angular rate "
                    f"{angular_velocity.tolist()}, temperature {temperature}",
                )
            self._deliver(
                SensorSample.trusted(now, wrench, specific_force, angular_velocity, temperature)
            )

    def _stop_stream(self) -> None:
        """Nothing to call: the thread sees the flag after its next frame and releases the
        driver itself (every driver call stays in that thread)."""


REGISTRATION = SensorEntry(
    name="bota",
    summary="Bota Systems sensor, through bota_driver (extra 'bota')",
    factory=BotaSensor,
    options=(
        SensorOption("config", str, "the sensor's bota_driver JSON configuration file"),
        SensorOption("silence_after", float, "no new frame this long is a fault", "s"),
        SensorOption("connect_timeout", float, "wait this long for the first frame", "s"),
    ),
)
