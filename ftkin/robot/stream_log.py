"""The sensor's stream to a CSV as it comes: wrench, IMU and temperature with their stamps.

:func:`log_stream` is ``ftkin record --raw``: every new sample of a sensor (a new stamp) is one
row, for later use (a drift calibration, a dynamic one, compensation offline). Columns:

* ``t`` [s]: the sample's stamp (ftkin's adapters stamp on the host's ``time.monotonic()``);
* ``fx,fy,fz,mx,my,mz`` [N, N·m]: the raw wrench, sensor frame, as the sensor reports it;
* ``ax,ay,az`` [m/s², IMU frame] and ``wx,wy,wz`` [rad/s] where the sensor has an IMU, and
  ``temperature`` [°C] where it has one (decided from the first sample; a sensor with
  ``read_sample()``, :class:`~ftkin.sensors.sample.SensorSample`).

The rows are written in blocks, flushed and synced every ``flush_period``: an interrupted log
keeps whole rows up to the last block and the rows of the moment it stopped. It ends after
``duration``, on Ctrl-C, or on a sensor fault (:class:`~ftkin.exceptions.SensorError`: what came
before is written, the fault is in the result). The sensor is polled every ``poll_period``;
a sample newer than the last one read but replaced before the next poll is missed, and counted
where the sensor says how many it delivered (``stats()`` of :mod:`ftkin.sensors`).
"""

from __future__ import annotations

import logging
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path

from ..calibration.model import WRENCH_CHANNELS
from ..exceptions import InvalidInput, SensorError
from ..io.stream_join import ACCEL_COLUMNS, GYRO_COLUMNS
from ..io.time_columns import TIME_COLUMN
from ..progress import Progress
from .samples_log import interrupts_held
from .stillness import CheckedSensor, SampleTap

logger = logging.getLogger(__name__)

TEMPERATURE_COLUMN = "temperature"


@dataclass(frozen=True)
class StreamLog:
    """What :func:`log_stream` wrote.

    Attributes:
        path: The CSV.
        rows: Samples written.
        seconds: From the first stamp to the last [s].
        columns: The header.
        stop_reason: ``"duration"``, ``"interrupt"`` or ``"fault"``.
        fault: The sensor fault that ended it, or None.
        missed: New samples the sensor delivered that the polling did not see (None when the
            sensor does not count them).
    """

    path: Path
    rows: int
    seconds: float
    columns: tuple[str, ...]
    stop_reason: str
    fault: SensorError | None = None
    missed: int | None = None

    @property
    def rate_hz(self) -> float:
        """Rows per second of stamps [Hz] (0 before two rows)."""
        return (self.rows - 1) / self.seconds if self.rows > 1 and self.seconds > 0 else 0.0

    def report(self) -> str:
        """One line: rows, span, rate, and how it ended."""
        missed = "" if self.missed is None else f", {self.missed} missed by the polling"
        ending = {"duration": "the duration was reached", "interrupt": "interrupted (Ctrl-C)"}
        why = ending.get(self.stop_reason, f"sensor fault: {self.fault}")
        return (
            f"wrote {self.rows} samples over {self.seconds:.3f} s ({self.rate_hz:.1f} Hz{missed}) "
            f"to {self.path}; stopped: {why}"
        )


def _row_parts(sample) -> tuple[tuple[str, ...], list]:
    """The extra columns of a full sample and their values."""
    columns, values = [], []
    for names, value in (
        (ACCEL_COLUMNS, sample.specific_force),
        (GYRO_COLUMNS, sample.angular_velocity),
    ):
        if value is not None:
            columns += names
            values += [float(v) for v in value]
    if sample.temperature is not None:
        columns.append(TEMPERATURE_COLUMN)
        values.append(float(sample.temperature))
    return tuple(columns), values


def _stats_samples(sensor) -> int | None:
    stats = getattr(sensor, "stats", None)
    return int(stats().samples) if callable(stats) else None


def log_stream(
    sensor,
    path,
    *,
    duration: float | None = None,
    poll_period: float = 0.0002,
    flush_period: float = 0.5,
    stale_after: float = 0.1,
    progress: bool | None = None,
) -> StreamLog:
    """Log ``sensor``'s stream to the CSV ``path`` (module docstring).

    Args:
        sensor: ``read() -> (t, wrench)``, or ``read_sample()`` for the IMU and temperature.
        path: A new file (an existing one is refused: ftkin never overwrites an input).
        duration: Stop after this long [s, wall clock]; None: until Ctrl-C or a fault.
        poll_period: Sleep between polls [s].
        flush_period: Write, flush and sync the rows this often [s].
        stale_after: A stamp that does not advance for this long is a fault [s].
        progress: Draw a progress line (samples and rate; default: when stderr is a terminal).

    Raises:
        InvalidInput: the file exists, or a bad argument.
    """
    path = Path(path)
    for name, value in (("poll_period", poll_period), ("flush_period", flush_period)):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
            raise InvalidInput(f"{name} must be a finite number of seconds >= 0, got {value!r}")
    if duration is not None and not (
        isinstance(duration, (int, float)) and math.isfinite(duration) and duration > 0
    ):
        raise InvalidInput(f"duration must be a finite number of seconds > 0, got {duration!r}")
    if path.exists():
        raise InvalidInput(f"{path} already exists: choose another file for the stream")
    tap = SampleTap(sensor)
    checked = CheckedSensor(tap, stale_after)
    stamp, wrench, _ = checked.read()
    full = tap.sample is not None
    extra_columns, extra = _row_parts(tap.sample) if full else ((), [])
    columns = (TIME_COLUMN, *WRENCH_CHANNELS, *extra_columns)
    first_stamp, last_stamp, rows = stamp, stamp, 0
    delivered_at_start = _stats_samples(sensor)
    pending = [[stamp, *map(float, wrench), *extra]]
    stop_reason, fault = "duration", None
    start = last_flush = time.monotonic()
    with (
        open(path, "x", encoding="utf-8", newline="") as stream,
        Progress(None, "samples", enabled=progress) as bar,
    ):

        def flush() -> None:
            nonlocal rows
            with interrupts_held():  # whole rows, and ``rows`` counts what the file holds
                if pending:
                    stream.write("".join(",".join(map(repr, row)) + "\n" for row in pending))
                    rows += len(pending)
                    bar.advance(len(pending))
                    pending.clear()
                stream.flush()
                os.fsync(stream.fileno())

        stream.write(",".join(columns) + "\n")
        delivered = None
        try:
            while True:
                stamp, wrench, new = checked.read()
                if new:
                    values = _row_parts(tap.sample)[1] if full else []
                    if len(values) != len(extra):
                        raise SensorError("imu", "the sensor's samples changed their channels")
                    pending.append([stamp, *map(float, wrench), *values])
                    last_stamp = stamp
                now = time.monotonic()
                if duration is not None and now - start >= duration:
                    break
                if now - last_flush >= flush_period:
                    flush()
                    last_flush = now
                time.sleep(poll_period)
        except KeyboardInterrupt:
            stop_reason = "interrupt"
        except SensorError as error:
            stop_reason, fault = "fault", error
        finally:
            delivered = _stats_samples(sensor)  # at the last poll: not what came while stopping
            flush()
    missed = None
    if delivered is not None and delivered_at_start is not None:
        missed = (
            max(0, delivered - delivered_at_start + 1 - rows) if stop_reason != "fault" else None
        )
    return StreamLog(
        path, rows, float(last_stamp - first_stamp), columns, stop_reason, fault, missed
    )
