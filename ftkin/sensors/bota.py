"""A Bota Systems sensor through bota_driver (extra ``bota``): wrench, IMU and temperature.

:class:`BotaSensor` runs the vendor's driver through its whole lifecycle: ``configure()`` and
``activate()`` when opened, ``read_frame_blocking()`` for every frame, and ``deactivate()`` and
``shutdown()`` at the end, on :meth:`~StreamingSensor.close` or on a fault. The driver runs in a
process of its own (:mod:`ftkin.sensors.bota_process`): its blocking read holds Python's GIL
while it waits, which would stall a control loop in the same process for up to a frame period.
The adapter's thread takes the frames from that process and keeps the newest
(:class:`~ftkin.sensors.stream.StreamingSensor`). bota_driver has no per-frame callback.

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

import math
import os
import re
from pathlib import Path

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, SensorError
from .bota_process import DEFAULT_DRIVER, ERROR, FLAGS, READY, DriverProcess, dump_config
from .registry import SensorEntry, SensorOption
from .sample import SensorSample
from .stream import JOIN_TIMEOUT, StreamingSensor

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


class BotaSensor(StreamingSensor):
    """A Bota Systems sensor: ``read() -> (t [s], wrench (6,) [N, N·m])``, ``read_sample()``
    with the IMU and the temperature.

    Args:
        config: The vendor's JSON configuration file (a path), or a
            ``bota_driver.BotaDriverConfig``.
        silence_after: No new frame for this long is a fault [s] (``"silence"``, or
            ``"stall"`` when frames keep coming with a frozen timestamp).
        connect_timeout: Wait this long for the driver to start and send its first frame [s].
        driver: The driver class as ``MODULE:CLASS``, importable in the driver's process
            (default: the vendor's; a subclass can wrap it, as the tests do to inject faults).

    Attributes:
        timestep: The driver's expected frame period [s] (``get_expected_timestep_us()``).
        throttled: Frames the sensor flagged as throttled.

    Raises:
        InvalidInput: ``config`` is neither an existing file nor a ``BotaDriverConfig``, or
            ``driver`` is not ``MODULE:CLASS``.
        MissingDependency: bota_driver is not installed (``pip install -e '.[bota]'``).
        SensorError: ``"connect"``: the driver refused the configuration, ``configure()`` or
            ``activate()`` failed (its log says why), or no frame came in time.
    """

    def __init__(
        self,
        config,
        *,
        silence_after: float = 0.05,
        connect_timeout: float = 5.0,
        driver: str = DEFAULT_DRIVER,
    ):
        bota_driver = _bota_driver()
        if isinstance(config, (str, os.PathLike)):
            path = Path(config)
            if not path.is_file():
                raise InvalidInput(f"the Bota configuration file {str(path)!r} does not exist")
            source, description = str(path.resolve()), f"the Bota sensor of {path.name}"
        elif isinstance(config, bota_driver.BotaDriverConfig):
            source = dump_config(config)
            product, serial = config.product_name or "?", config.serial_number or "?"
            description = f"the Bota sensor {product} ({serial})"
        else:
            raise InvalidInput(
                "config must be the path of a bota_driver JSON configuration or a "
                f"bota_driver.BotaDriverConfig, got {type(config).__name__}"
            )
        if not isinstance(driver, str) or not re.fullmatch(r"[A-Za-z_][\w.]*:[A-Za-z_]\w*", driver):
            raise InvalidInput(
                f"driver must be MODULE:CLASS (e.g. {DEFAULT_DRIVER}), got {driver!r}"
            )
        super().__init__(description, silence_after, connect_timeout)
        self.throttled = 0
        self.timestep = math.nan
        self._process = DriverProcess(source, driver)
        self._start()

    def _connect_hint(self) -> str:
        return "the driver's log above says what it did"

    def _stream(self) -> None:
        message = self._process.next()
        if message is not None and message[0] == ERROR:
            raise SensorError(*message[1])
        if message is None or message[0] != READY:
            raise SensorError("connect", f"{self.description}: the driver's process ended")
        self.timestep = message[1] * 1e-6
        self._take_frames()

    def _take_frames(self) -> None:
        description, last_stamp = self.description, None
        while True:
            message = self._process.next()
            if message is None:
                if self._closed:
                    return
                code = self._process.wait(JOIN_TIMEOUT)
                raise SensorError(
                    "driver", f"{description}: the driver's process ended (exit code {code})"
                )
            tag, fields = message
            if tag == ERROR:
                kind, text = fields
                raise SensorError(kind, f"{description}: {text}")
            if self._closed:
                continue  # drain until the child has released the driver
            stamp, timestamp, flags = fields[:3]
            raised = [name for bit, name in enumerate(FLAGS) if flags >> bit & 1]
            faults = [name for name in raised if name in FAULT_FLAGS]
            if faults:
                raise SensorError("status", f"{description} flags its frame {', '.join(faults)}")
            if timestamp == last_stamp:
                self._repeat(stamp)
                continue
            last_stamp = timestamp
            if "throttled" in raised:
                self.throttled += 1
            values = np.array(fields[3:])
            if not math.isfinite(values.sum()):
                raise SensorError(
                    "not_finite",
                    f"{description} sent a value that is not finite: {values.tolist()} (wrench, "
                    "acceleration, angular rate, temperature)",
                )
            wrench, specific_force, angular_velocity = values[:6], values[6:9], values[9:12]
            for array in (wrench, specific_force, angular_velocity):
                array.flags.writeable = False
            self._deliver(
                SensorSample.trusted(
                    stamp, wrench, specific_force, angular_velocity, float(values[12])
                )
            )

    def _stop_stream(self) -> None:
        """Ask the driver's process to deactivate and shut the driver down (it ends the stream,
        which ends the reading thread)."""
        self._process.stop()

    def close(self) -> None:
        """Stop the stream; the driver is deactivated and shut down in its process, which then
        ends. Idempotent; never raises."""
        already = self._closed
        super().close()
        if not already and getattr(self, "_process", None) is not None:
            self._process.wait(JOIN_TIMEOUT)


REGISTRATION = SensorEntry(
    name="bota",
    summary="Bota Systems sensor, through bota_driver (extra 'bota')",
    factory=BotaSensor,
    options=(
        SensorOption("config", str, "the sensor's bota_driver JSON configuration file"),
        SensorOption("silence_after", float, "no new frame this long is a fault", "s"),
        SensorOption("connect_timeout", float, "wait this long for the first frame", "s"),
        SensorOption("driver", str, "the driver class as MODULE:CLASS (default: the vendor's)"),
    ),
)
