"""An ATI Net F/T box through pynetft (extra ``ati``): the newest wrench in N and N·m.

pynetft's :class:`pynetft.Client` reads the box's calibration over HTTP (``/netftapi2.xml``) and
streams RDT records over UDP in a native thread; this adapter takes them in its own thread
(:class:`~ftkin.sensors.stream.StreamingSensor`) and keeps the newest. Three things pynetft
leaves to its caller are done here:

* **Units.** pynetft scales counts into the unit the box is set to (N, lbf, kgf, klbf, kN;
  N-m, N-mm, lbf-in, lbf-ft, kgf-cm, kN-m) and does not convert: every sample is converted to
  N and N·m by the units it carries (:mod:`ftkin.sensors.units`, exact factors); a unit ftkin
  does not know is the fault ``"units"``.
* **Status.** Any nonzero status word is the fault ``"status"``, including the bits pynetft
  counts as a warning (0x80010000), unless ``ignore_status_bits`` names them: ftkin sees the
  record (``deliver_samples_with_error_status=True``) and reports its status word.
* **Stall.** An ft_sequence that stops advancing while records keep coming is the fault
  ``"stall"``, after ``silence_after``: pynetft holds back the records that repeat the last
  acquisition, and its ``health().ft_stall_count`` tells a stall from silence. Records that
  reach pynetft but not this adapter's thread in time (a thread of the process that never
  sleeps holds the GIL the reading thread needs for every record) are ``"lag"``.

**Recovery policy.** pynetft runs with ``RecoveryPolicy.FAIL_STOP``: the first fault stops its
client, which raises :class:`pynetft.SensorFaultError` (its fault code becomes the ftkin kind),
and the fault latches here. Its default, ``RECONNECT``, drops bad records and reconnects behind
the caller's back, so a loop would see a gap (or nothing at all for a stall) and then data
again; ftkin stops the arm on a fault instead, and a sensor that comes back is opened anew.

**Bias.** The adapter never sends the box's bias command (RDT 0x0042): ftkin's calibration
expects raw readings and fits the bias itself. A box already biased in software (its web page,
another program) reports raw minus the stored bias; the calibration then fits the remainder as
its bias ``F0``/``M0``, and compensation and a re-zero stay consistent as long as nobody biases
the box again. Biasing it after calibrating shifts every reading: re-zero (``ftkin rezero``)
or recalibrate.

The wrench is the one the box reports: ATI's load on the sensor's tool side in the sensor
frame, so ftkin's ``sensor_sign=+1``; a box set up to report the reaction is
``sensor_sign=-1``.
"""

from __future__ import annotations

import numpy as np

from ..exceptions import InvalidInput, MissingDependency, SensorError
from .registry import SensorEntry, SensorOption
from .sample import SensorSample
from .stream import StreamingSensor
from .units import wrench_scale

RDT_PORT = 49152
"""The box's RDT port (UDP)."""
HTTP_PORT = 80
"""The box's web server (its calibration in ``/netftapi2.xml``)."""
QUEUE_SIZE = 4096
"""Records pynetft holds for this adapter's thread: 0.58 s at 7 kHz before one is dropped."""

_KINDS = {
    "serious_status": "status",
    "ft_stall": "stall",
    "ft_backward": "stall",
    "timeout": "silence",
    "sensor_configuration": "configuration",
}
"""pynetft's ``FaultCode`` values → ftkin's kinds (any other is ``"driver"``)."""


def _pynetft():
    try:
        import pynetft
    except ImportError:
        raise MissingDependency("pynetft", "ati", "the ATI Net F/T adapter (AtiNetFT)") from None
    return pynetft


def _port(value, name: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 1 <= value <= 65535:
        raise InvalidInput(f"{name} must be a port number in 1..65535, got {value!r}")
    return value


class AtiNetFT(StreamingSensor):
    """An ATI Net F/T box: ``read() -> (t [s], wrench (6,) [N, N·m])``, the newest sample.

    Opening it starts the stream and waits for the first sample. ``t`` is the host's receive
    time of the record (pynetft's ``received_at_ns``, on ``time.monotonic()``'s clock).

    Args:
        host: The box's address (its default is 192.168.1.1).
        rdt_port: Its RDT port (UDP).
        http_port: Its web server's port (the calibration is read from it).
        silence_after: No new sample for this long is a fault [s] (``"silence"``, or
            ``"stall"`` when records keep coming with a frozen ft_sequence); also pynetft's
            ``receive_timeout``.
        connect_timeout: Wait this long for the first sample [s].
        ignore_status_bits: Status-word bits that are not a fault (default none: any nonzero
            status word is one). Name only bits the box's manual calls harmless for you.
        queue_size: Records pynetft buffers for the reading thread (it drops the oldest
            beyond): the thread may lag this many records behind without a loss.

    Raises:
        InvalidInput: an argument of the wrong type or range.
        MissingDependency: pynetft is not installed (``pip install -e '.[ati]'``).
        SensorError: ``"connect"``: no sample within ``connect_timeout``, or the first
            records showed a fault (nothing listening, a unit pynetft does not know, a status
            word: the message says which).
    """

    def __init__(
        self,
        host: str,
        *,
        rdt_port: int = RDT_PORT,
        http_port: int = HTTP_PORT,
        silence_after: float = 0.05,
        connect_timeout: float = 2.0,
        ignore_status_bits: int = 0,
        queue_size: int = QUEUE_SIZE,
    ):
        if not isinstance(host, str) or not host.strip():
            raise InvalidInput(f"host must be the box's address (a non-empty string), got {host!r}")
        rdt_port, http_port = _port(rdt_port, "rdt_port"), _port(http_port, "http_port")
        if (
            isinstance(ignore_status_bits, bool)
            or not isinstance(ignore_status_bits, int)
            or not 0 <= ignore_status_bits <= 0xFFFFFFFF
        ):
            raise InvalidInput(
                f"ignore_status_bits must be a 32-bit mask (0..0xFFFFFFFF), got "
                f"{ignore_status_bits!r}"
            )
        if isinstance(queue_size, bool) or not isinstance(queue_size, int) or queue_size < 1:
            raise InvalidInput(f"queue_size must be an integer >= 1, got {queue_size!r}")
        super().__init__(f"the ATI Net F/T at {host}", silence_after, connect_timeout)
        pynetft = _pynetft()
        self.host, self.rdt_port, self.http_port = host, rdt_port, http_port
        self.status_mask = ~ignore_status_bits & 0xFFFFFFFF
        config = pynetft.Config(
            sensor_host=host,
            rdt_port=rdt_port,
            http_port=http_port,
            receive_timeout=self.silence_after,
            configuration_connect_timeout=min(0.5, self.connect_timeout),
            configuration_timeout=min(1.0, self.connect_timeout),
            recovery_policy=pynetft.RecoveryPolicy.FAIL_STOP,
            deliver_samples_with_error_status=True,
        )
        try:
            self._client = pynetft.Client(config, queue_size=queue_size)
            self._client.start()
        except pynetft.ConfigurationError as error:
            raise InvalidInput(f"pynetft refuses the configuration of {host}: {error}") from None
        except pynetft.NetFTError as error:
            raise SensorError("connect", f"cannot open {self.description}: {error}") from None
        self._start()

    @property
    def client(self):
        """pynetft's :class:`pynetft.Client` under this adapter (to inspect; starting, stopping
        or biasing it behind the adapter's back breaks the adapter's guarantees)."""
        return self._client

    def health(self):
        """pynetft's :class:`pynetft.Health` snapshot (counters, state, the box's calibration)."""
        return self._client.health()

    def _connect_hint(self) -> str:
        last_error = self._client.health().last_error
        return (
            f"pynetft says {last_error!r}; " if last_error else ""
        ) + f"check the address, that {self.http_port} (HTTP) and {self.rdt_port} (UDP) reach it"

    def _stream(self) -> None:
        pynetft = _pynetft()
        units, scale, last_sequence = None, None, None
        mask, description = self.status_mask, self.description
        try:
            for sample in self._client.samples():
                if sample.status & mask:
                    raise SensorError(
                        "status",
                        f"{description} reports the status word 0x{sample.status:08x} (nonzero: "
                        "a saturated gauge, a failed self-test, ... see the box's manual; "
                        "ignore_status_bits admits bits known to be harmless)",
                    )
                if (sample.force_unit, sample.torque_unit) != units:
                    try:
                        scale = wrench_scale(sample.force_unit, sample.torque_unit)
                    except InvalidInput as error:
                        raise SensorError("units", f"{description}: {error}") from None
                    units = (sample.force_unit, sample.torque_unit)
                sequence = sample.rdt_sequence
                if last_sequence is not None:
                    gap = (sequence - last_sequence - 1) & 0xFFFFFFFF
                    if 0 < gap < 0x80000000:  # records pynetft saw go missing on the wire
                        self._lost += gap
                last_sequence = sequence
                wrench = np.array(sample.wrench) * scale
                wrench.flags.writeable = False
                self._deliver(SensorSample.trusted(sample.received_at_ns * 1e-9, wrench))
        except pynetft.SensorFaultError as error:
            health = error.health
            kind = _KINDS.get(error.fault_code.value, "driver")
            detail = health.last_error or error.fault_code.value
            if kind == "status":
                detail += f", status word 0x{health.last_status:08x}"
            raise SensorError(kind, f"{description}: pynetft stopped: {detail}") from None

    def _diagnose_silence(self, age: float) -> SensorError:
        health = self._client.health()
        if health.ft_stall_count:
            return SensorError(
                "stall",
                f"{self.description} is stalled: records keep coming but its ft_sequence has not "
                f"advanced for {age:.3f} s (limit {self.silence_after:g} s)",
            )
        record_age = health.last_record_age
        if record_age is not None and record_age < self.silence_after:
            return SensorError(
                "lag",
                f"{self.description} streams, but the adapter's thread fell behind: its newest "
                f"sample is {age:.3f} s old (limit {self.silence_after:g} s). Another thread of "
                "this process holds the CPU (Python's GIL) without pause: a control loop should "
                "sleep between its ticks",
            )
        return super()._diagnose_silence(age)

    def _stop_stream(self) -> None:
        self._client.stop()


REGISTRATION = SensorEntry(
    name="ati",
    summary="ATI Net F/T box over UDP RDT, through pynetft (extra 'ati')",
    factory=AtiNetFT,
    options=(
        SensorOption("host", str, "the box's address, e.g. 192.168.1.1"),
        SensorOption("rdt_port", int, "its RDT port (UDP)"),
        SensorOption("http_port", int, "its web server's port (the calibration is read there)"),
        SensorOption("silence_after", float, "no new sample this long is a fault", "s"),
        SensorOption("connect_timeout", float, "wait this long for the first sample", "s"),
        SensorOption("ignore_status_bits", int, "status-word bits that are not a fault (0x...)"),
        SensorOption("queue_size", int, "records buffered for the reading thread"),
    ),
)
