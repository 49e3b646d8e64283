"""One sample of a wrist sensor: the wrench and its stamp, and the IMU and temperature it may have.

:class:`SensorSample` is what :meth:`~ftkin.sensors.stream.StreamingSensor.read_sample` returns;
``read()`` returns its ``(t, wrench)`` (the :class:`~ftkin.robot.protocols.ForceTorqueSensor`
contract). :class:`StreamStats` counts what a sensor's stream delivered and lost.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput


def _vector(value, name: str, size: int) -> np.ndarray:
    try:
        array = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise InvalidInput(f"{name} must be {size} numbers, got {value!r}") from None
    if array.shape != (size,) or not np.all(np.isfinite(array)):
        raise InvalidInput(f"{name} must be {size} finite numbers, got {value!r}")
    array.flags.writeable = False
    return array


@dataclass(frozen=True)
class SensorSample:
    """One sample, in SI units and the sensor's own frames.

    Attributes:
        t: When the host received it [s], on ``time.monotonic()``'s clock (the same ``t`` twice
            is the same sample).
        wrench: ``(6,)`` ``[fx, fy, fz, mx, my, mz]`` [N, N·m] in the sensor frame, as the
            sensor reports it: the load on the sensor for a sensor that reports the load (a
            sensor that reports the reaction is the calibration's ``sensor_sign=-1``), bias
            included. Read-only.
        specific_force: ``(3,)`` [m/s²] in the IMU frame, or None without an accelerometer:
            the accelerometer's reading, which at rest is ``+g`` pointing up (the reaction to
            gravity, not gravity). Read-only.
        angular_velocity: ``(3,)`` [rad/s] in the IMU frame, or None without a gyroscope.
        temperature: The sensor's temperature [°C], or None.
    """

    t: float
    wrench: np.ndarray
    specific_force: np.ndarray | None = None
    angular_velocity: np.ndarray | None = None
    temperature: float | None = None

    def __post_init__(self):
        if isinstance(self.t, bool) or not isinstance(self.t, (int, float)):
            raise InvalidInput(f"t must be a number of seconds, got {self.t!r}")
        if not math.isfinite(self.t):
            raise InvalidInput(f"t must be finite [s], got {self.t!r}")
        object.__setattr__(self, "t", float(self.t))
        object.__setattr__(self, "wrench", _vector(self.wrench, "wrench [N, N·m]", 6))
        for name, unit in (("specific_force", "m/s²"), ("angular_velocity", "rad/s")):
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, _vector(value, f"{name} [{unit}]", 3))
        if self.temperature is not None:
            temperature = self.temperature
            if isinstance(temperature, bool) or not isinstance(temperature, (int, float)):
                raise InvalidInput(f"temperature must be a number [°C], got {temperature!r}")
            if not math.isfinite(temperature):
                raise InvalidInput(f"temperature must be finite [°C], got {temperature!r}")
            object.__setattr__(self, "temperature", float(temperature))

    @classmethod
    def trusted(
        cls,
        t: float,
        wrench: np.ndarray,
        specific_force: np.ndarray | None = None,
        angular_velocity: np.ndarray | None = None,
        temperature: float | None = None,
    ) -> SensorSample:
        """The adapters' fast path: a sample built without the checks of the constructor.

        The caller guarantees what :meth:`__post_init__` would check: ``t`` a finite float,
        float arrays of shapes ``(6,)`` and ``(3,)`` (or None) already made read-only, a
        float or None temperature. A stream at 7 kHz builds one per record; the checks cost
        more than the rest of its path. Tested against the checked constructor.
        """
        sample = object.__new__(cls)
        setter = object.__setattr__
        setter(sample, "t", t)
        setter(sample, "wrench", wrench)
        setter(sample, "specific_force", specific_force)
        setter(sample, "angular_velocity", angular_velocity)
        setter(sample, "temperature", temperature)
        return sample

    @property
    def force(self) -> np.ndarray:
        """``(3,)`` [N], sensor frame."""
        return self.wrench[:3]

    @property
    def torque(self) -> np.ndarray:
        """``(3,)`` [N·m] about the sensor origin, sensor frame."""
        return self.wrench[3:]

    @property
    def has_imu(self) -> bool:
        """True when the sample carries an accelerometer reading."""
        return self.specific_force is not None


@dataclass(frozen=True)
class StreamStats:
    """What a sensor's stream delivered since it opened.

    Attributes:
        samples: New samples delivered to ``read()`` (each kept as the newest in turn).
        lost: Samples the stream skipped (gaps in the sensor's own sequence numbers: lost on
            the wire or dropped before ftkin saw them).
        repeated: Records that repeated the previous sample (not delivered as new).
        first_t: Stamp of the first sample [s], or None.
        last_t: Stamp of the newest sample [s], or None.
    """

    samples: int
    lost: int
    repeated: int
    first_t: float | None
    last_t: float | None

    @property
    def rate_hz(self) -> float:
        """Delivered rate ``(samples − 1) / (last_t − first_t)`` [Hz] (0 before two samples)."""
        if self.samples < 2 or self.first_t is None or self.last_t is None:
            return 0.0
        span = self.last_t - self.first_t
        return (self.samples - 1) / span if span > 0 else 0.0
