"""A sensor read by a background thread: ``read()`` returns the newest sample without blocking.

:class:`StreamingSensor` is the part every built-in adapter shares. A daemon thread takes each
record from the vendor's client as it comes and keeps the newest as a
:class:`~ftkin.sensors.sample.SensorSample`; ``read()`` only looks at it (no lock, no system
call but the clock: a few hundred nanoseconds). A fault **latches**: from the record that shows
it, every ``read()`` raises :class:`~ftkin.exceptions.SensorError` with its ``kind``, until
:meth:`~StreamingSensor.close`. ftkin stops the arm on the first one; a sensor that comes back
needs a new adapter, opened by someone who has looked at why it failed.

The kinds (``SensorError.kind``) an adapter raises:

* ``"status"``: the sensor flagged the sample (a nonzero status word, an error flag);
* ``"stall"``: records keep coming but the acquisition is frozen (the same sequence number);
* ``"silence"``: no new sample for ``silence_after`` [s];
* ``"lag"``: the sensor streams but the adapter's thread did not deliver a sample for
  ``silence_after`` (another thread of the process never releases the GIL);
* ``"not_finite"``: a value that is not a number;
* ``"units"``: the sensor reports in a unit ftkin does not convert;
* ``"configuration"``: the sensor's configuration cannot be used;
* ``"driver"``: the vendor's client raised or stopped;
* ``"connect"``: the constructor got no first sample within ``connect_timeout`` [s], or the
  first records showed a fault (the message says which);
* ``"closed"``: ``read()`` after :meth:`~StreamingSensor.close`.
"""

from __future__ import annotations

import logging
import math
import threading
import time

from ..exceptions import InvalidInput, SensorError
from .sample import SensorSample, StreamStats

logger = logging.getLogger(__name__)

JOIN_TIMEOUT = 2.0
"""How long :meth:`StreamingSensor.close` waits for the reading thread to end [s]."""


def positive_seconds(value, name: str) -> float:
    """``value`` as a float of seconds, finite and > 0, or InvalidInput naming ``name``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InvalidInput(f"{name} must be a number of seconds > 0, got {value!r}")
    if not (math.isfinite(value) and value > 0):
        raise InvalidInput(f"{name} must be finite and > 0 [s], got {value!r}")
    return float(value)


class StreamingSensor:
    """The newest sample of a vendor stream, kept by a thread; a context manager.

    Subclasses open the vendor's client, then call :meth:`_start`; they implement
    :meth:`_stream` (runs in the thread: take records until closed, hand each new sample to
    :meth:`_deliver`, raise :class:`SensorError` on a fault) and :meth:`_stop_stream` (make
    :meth:`_stream` return), and may refine :meth:`_diagnose_silence`.

    Args:
        description: What the sensor is, for messages (``"the ATI Net F/T at 192.168.1.1"``).
        silence_after: No new sample for this long is the fault ``"silence"`` [s].
        connect_timeout: The constructor waits this long for the first sample [s].
    """

    def __init__(self, description: str, silence_after: float, connect_timeout: float):
        self.description = description
        self.silence_after = positive_seconds(silence_after, "silence_after")
        self.connect_timeout = positive_seconds(connect_timeout, "connect_timeout")
        self._latest: SensorSample | None = None
        self._fault: SensorError | None = None
        self._closed = False
        self._samples = self._lost = self._repeated = 0
        self._first_t: float | None = None
        self._record_at: float | None = None  # [s] the newest record of any kind (new or repeated)
        self._ready = threading.Event()
        self._thread: threading.Thread | None = None

    # ------------------------------------------------------------------ the control-loop side
    def read(self):
        """``(t [s], wrench (6,) [N, N·m])``: the newest sample, without blocking.

        ``t`` is the host's receive time on ``time.monotonic()``'s clock; the same ``t`` twice
        means no new sample came in between. The wrench array is read-only and shared.

        Raises:
            SensorError: the latched fault (its ``kind`` says which), or ``"silence"`` when the
                newest sample is older than ``silence_after``.
        """
        sample = self._latest
        if (
            self._fault is not None
            or self._closed
            or sample is None
            or time.monotonic() - sample.t > self.silence_after
        ):
            self._fail()
        return sample.t, sample.wrench

    def read_sample(self) -> SensorSample:
        """The newest :class:`~ftkin.sensors.sample.SensorSample` (IMU and temperature where the
        sensor has them), without blocking; raises as :meth:`read` does."""
        sample = self._latest
        if (
            self._fault is not None
            or self._closed
            or sample is None
            or time.monotonic() - sample.t > self.silence_after
        ):
            self._fail()
        return sample

    def stats(self) -> StreamStats:
        """What the stream delivered, skipped and repeated so far."""
        latest = self._latest
        return StreamStats(
            samples=self._samples,
            lost=self._lost,
            repeated=self._repeated,
            first_t=self._first_t,
            last_t=None if latest is None else latest.t,
        )

    @property
    def fault(self) -> SensorError | None:
        """The latched fault, or None."""
        return self._fault

    def close(self) -> None:
        """Stop the stream and release the vendor's client; ``read()`` then raises ``"closed"``.

        Idempotent; never raises.
        """
        if self._closed:
            return
        self._closed = True
        try:
            self._stop_stream()
        except Exception as error:  # closing must not raise: log what the vendor said
            logger.warning("%s: stopping the stream failed: %s", self.description, error)
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(JOIN_TIMEOUT)
            if thread.is_alive():
                logger.warning("%s: the reading thread did not end", self.description)

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else "faulted" if self._fault else "streaming"
        return f"<{type(self).__name__} {self.description}: {state}>"

    # ------------------------------------------------------------------ the subclass side
    def _start(self) -> None:
        """Start the reading thread and wait for the first sample.

        Raises:
            SensorError: ``"connect"`` when no sample came within ``connect_timeout`` or the
                first records showed a fault (the message says which; the adapter is closed).
        """
        self._thread = threading.Thread(
            target=self._run, name=f"ftkin {type(self).__name__}", daemon=True
        )
        self._thread.start()
        self._ready.wait(self.connect_timeout)
        if self._latest is not None and self._fault is None:
            return
        fault = self._fault
        self.close()
        if fault is not None:
            raise SensorError("connect", f"cannot open {self.description}: {fault}")
        raise SensorError(
            "connect",
            f"no sample from {self.description} within {self.connect_timeout:g} s: "
            + self._connect_hint(),
        )

    def _connect_hint(self) -> str:
        """What to check when no first sample came (the subclass knows its vendor)."""
        return "is it powered, connected and configured?"

    def _stream(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _stop_stream(self) -> None:  # pragma: no cover - abstract
        raise NotImplementedError

    def _diagnose_silence(self, age: float) -> SensorError:
        """The fault for a newest sample ``age`` [s] old: ``"stall"`` when records still came
        within ``silence_after`` (all repeating the last sample), else ``"silence"``."""
        record_age = math.inf if self._record_at is None else time.monotonic() - self._record_at
        if record_age < self.silence_after:
            return SensorError(
                "stall",
                f"{self.description} is stalled: records keep coming but repeat the sample of "
                f"{age:.3f} s ago (limit {self.silence_after:g} s)",
            )
        return SensorError(
            "silence",
            f"{self.description} is silent: no new sample for {age:.3f} s "
            f"(limit {self.silence_after:g} s)",
        )

    def _deliver(self, sample: SensorSample) -> None:
        """Keep ``sample`` as the newest (called by :meth:`_stream`, in the thread)."""
        if self._first_t is None:
            self._first_t = sample.t
        self._samples += 1
        self._record_at = sample.t
        self._latest = sample
        if self._samples == 1:
            self._ready.set()

    def _repeat(self, at: float) -> None:
        """Count a record that repeats the newest sample, received at ``at`` [s]."""
        self._repeated += 1
        self._record_at = at

    def _run(self) -> None:
        try:
            self._stream()
            if not self._closed:
                self._latch(SensorError("driver", f"{self.description}: the stream ended"))
        except SensorError as error:
            self._latch(error)
        except Exception as error:  # a vendor client may raise anything: a driver fault
            self._latch(
                SensorError("driver", f"{self.description}: {type(error).__name__}: {error}")
            )
        finally:
            self._ready.set()

    def _latch(self, error: SensorError) -> None:
        if self._fault is None and not self._closed:
            self._fault = error
            logger.warning("sensor fault (%s): %s", error.kind, error)

    def _fail(self):
        """Raise the fault that stops ``read()`` (the cold path)."""
        if self._closed:
            raise SensorError("closed", f"{self.description} is closed")
        if self._fault is None:
            sample = self._latest
            age = math.inf if sample is None else time.monotonic() - sample.t
            self._latch(self._diagnose_silence(age))
        fault = self._fault
        raise SensorError(fault.kind, str(fault))
