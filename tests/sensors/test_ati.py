"""AtiNetFT: the real pynetft client against an emulated Net F/T box on loopback.

The box (tests/sensors/netft_box.py, a child process) speaks ATI's RDT protocol and serves
netftapi2.xml; the numbers are checked against the counts it encodes.
"""

from __future__ import annotations

import socket
import sys
import time

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput, MissingDependency, SensorError

pytest.importorskip("pynetft", reason="pynetft is not installed (extra 'ati')")

from ftkin.sensors import AtiNetFT, SensorSample  # noqa: E402

from .netft_box import BIAS, NetFTBox, dither  # noqa: E402

COUNTS = [1_500_000, -2_500_000, 9_810_000, 120_000, -340_000, 56_000]  # 1e6 counts per N, N·m


def wait_for_fault(sensor, timeout: float = 5.0) -> tuple[SensorError, float]:
    """Read every millisecond until a read raises; the error and when it raised [s]."""
    error, seen, _ = read_until_fault(sensor, timeout)
    return error, seen


def read_until_fault(sensor, timeout: float = 5.0):
    """Read every millisecond until a read raises: the error, when it raised [s], and each
    successful read's ``(start [s], stamp of the sample it returned [s])`` (monotonic clock).

    The limits of a sensor are checked against these stamps, not against how fast this
    thread was scheduled: on a busy machine a read may come late, but it must never return a
    sample older than the limit, and must not raise while the newest one is younger."""
    reads = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        start = time.monotonic()
        try:
            t, _ = sensor.read()
        except SensorError as error:
            return error, time.monotonic(), reads
        reads.append((start, t))
        time.sleep(0.001)
    raise AssertionError(f"no fault within {timeout} s")


def free_port() -> int:
    """A loopback port nothing listens on (TCP and UDP)."""
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def test_read_gives_the_newest_wrench_in_si_with_a_monotonic_stamp(box, ports):
    box.set(counts=COUNTS)
    before = time.monotonic()
    with AtiNetFT(box.host, **ports) as sensor:
        t, wrench = sensor.read()
        now = time.monotonic()
        np.testing.assert_allclose(wrench, np.array(COUNTS) / 1e6, rtol=1e-12)
        assert before < t <= now and now - t < 0.05
        assert not wrench.flags.writeable
        time.sleep(0.01)
        assert sensor.read()[0] > t  # 1 kHz: newer samples came in
        box.set(counts=[-c for c in COUNTS])  # the newest, not a queued old one
        time.sleep(0.02)
        np.testing.assert_allclose(sensor.read()[1], -np.array(COUNTS) / 1e6, rtol=1e-12)
        sample = sensor.read_sample()
        assert isinstance(sample, SensorSample) and not sample.has_imu
        assert sample.specific_force is None and sample.temperature is None


def quiet_totals(box, sensor) -> tuple[int, int, int]:
    """Silence the box and wait until the adapter has taken every record sent: ``(records sent,
    samples delivered, records counted lost)`` since the start, read while nothing moves."""
    box.set(fault="silence")
    deadline, previous = time.monotonic() + 30.0, None
    while time.monotonic() < deadline:
        time.sleep(0.05)
        totals = (box.stats()["sent"], sensor.stats().samples, sensor.stats().lost)
        if totals == previous and totals[0] == totals[1] + totals[2]:
            return totals
        previous = totals
    return totals  # not settled: the caller's comparison shows what is missing


@pytest.mark.parametrize("rate", [1000.0, 7000.0])
def test_every_streamed_record_is_delivered(box, ports, rate):
    """Every record the box sent reaches ``read()``'s stream once, in order, or is counted lost
    (by its rdt_sequence: a gap or a step back is counted lost), at 1 and 7 kHz. The records
    are counted with the box silent, so the count does not depend on when this thread runs;
    how fast the box paces them is the box's business, not the adapter's (not checked)."""
    box.set(rate=rate, dither=5)
    with AtiNetFT(box.host, silence_after=30.0, **ports) as sensor:  # silent while counting
        sent_first, delivered_first, lost_first = quiet_totals(box, sensor)
        box.set(fault=None)
        deadline = time.monotonic() + 30.0
        while box.stats()["sent"] - sent_first < 0.5 * rate and time.monotonic() < deadline:
            time.sleep(0.05)  # half a second of records, however long the box takes for them
        sent, delivered, lost = quiet_totals(box, sensor)
        health = sensor.health()
    # every record is delivered or counted lost, none dropped on the way in: a receiver starved
    # by a busy machine may lose datagrams in the kernel at 7 kHz, which the sequence shows
    assert sent - sent_first >= 0.5 * rate
    assert delivered - delivered_first + lost - lost_first == sent - sent_first
    assert lost == health.lost_count and health.python_queue_dropped_count == 0


def test_records_lost_on_the_wire_are_counted(box, ports):
    box.set(drop_every=25)
    with AtiNetFT(box.host, **ports) as sensor:
        time.sleep(0.5)
        stats, sent = sensor.stats(), box.stats()
    dropped = sent["rdt_sequence"] - sent["sent"]  # sequence numbers the box skipped
    assert dropped > 10 and abs(stats.lost - dropped) <= 1  # the newest may be in flight


@pytest.mark.parametrize("status", [0x80020000, 0x80010000, 0x00000001])
def test_a_nonzero_status_word_is_a_latched_status_fault(box, ports, status):
    with AtiNetFT(box.host, silence_after=30.0, **ports) as sensor:
        box.set(status=status)
        error, _ = wait_for_fault(sensor, timeout=20.0)
        # the first bad record, not a timeout: the silence limit is far away
        assert error.kind == "status" and f"0x{status:08x}" in str(error)
        box.set(fault=None)  # the box recovers; the adapter stays faulted
        time.sleep(0.02)
        with pytest.raises(SensorError, match="status word") as again:
            sensor.read()
        assert again.value.kind == "status" and sensor.fault.kind == "status"


def test_ignored_status_bits_are_not_a_fault(box, ports):
    with AtiNetFT(box.host, ignore_status_bits=0x80010000, **ports) as sensor:
        box.set(status=0x80010000)
        time.sleep(0.05)
        sensor.read()
        box.set(status=0x80020000)
        assert wait_for_fault(sensor)[0].kind == "status"


@pytest.mark.parametrize("fault", ["stall", "silence"])
def test_a_stall_and_silence_are_faults_after_the_limit(box, ports, fault):
    """No read returns a sample older than the limit, and none raises before the newest
    sample is that old: both measured on the samples' own stamps, so a busy machine that
    runs this thread late changes when the fault is seen, not whether it is right."""
    limit = 0.05  # [s] the adapter's default
    with AtiNetFT(box.host, silence_after=limit, **ports) as sensor:
        box.set(fault=fault)
        error, seen, reads = read_until_fault(sensor)
        newest = sensor.stats().last_t  # the stamp of the last new sample
    assert error.kind == fault, error
    assert all(start - t <= limit for start, t in reads)  # never an older sample
    if fault == "silence":  # not before the limit (pynetft latches a stall itself, counting
        assert seen - newest > limit  # the repeated records, which may come in a burst)
    if fault == "stall":  # records kept coming: pynetft counted the stall
        assert sensor.health().ft_stall_count >= 1


def test_an_adapter_thread_that_falls_behind_is_a_lag_fault(box, ports):
    # The emulated box is another process: on a busy machine it may pause for tens of ms,
    # which pynetft (its receive timeout is silence_after) would rightly call a silence. A
    # limit of 0.3 s leaves the box room; the GIL is held for longer than it.
    limit = 0.3  # [s]
    with AtiNetFT(box.host, silence_after=limit, **ports) as sensor:
        start = time.monotonic()
        sum(range(50_000_000))  # one C call: holds the GIL throughout, no switch
        held = time.monotonic() - start
        assert held > limit + 0.05, f"the GIL was held only {held:.3f} s: use a larger range"
        with pytest.raises(SensorError, match="fell behind") as error:
            sensor.read()  # pynetft's native thread received all along; the adapter's did not
    assert error.value.kind == "lag"


def test_the_box_is_never_biased(box, ports):
    with AtiNetFT(box.host, **ports) as sensor:
        assert not hasattr(sensor, "bias")
        sensor.read()
        box.set(status=1)
        wait_for_fault(sensor)
    commands = box.stats()["commands"]
    assert str(BIAS) not in commands and commands.get("2") == 1  # one start, no bias


def test_close_ends_the_stream(box, ports):
    sensor = AtiNetFT(box.host, **ports)
    sensor.read()
    sensor.close()
    sensor.close()  # idempotent
    with pytest.raises(SensorError, match="is closed") as closed:
        sensor.read()
    assert closed.value.kind == "closed" and "closed" in repr(sensor)
    time.sleep(0.05)
    assert box.stats()["streaming"] is False  # pynetft sent the stop command


def test_no_box_is_a_connect_fault_within_the_timeout():
    port = free_port()
    start = time.monotonic()
    with pytest.raises(SensorError, match="cannot open the ATI Net F/T at 127.0.0.1") as error:
        AtiNetFT("127.0.0.1", rdt_port=port, http_port=port, connect_timeout=0.3)
    assert error.value.kind == "connect" and "connect to server" in str(error.value)
    assert time.monotonic() - start < 1.5


def test_a_unit_pynetft_does_not_know_is_refused_while_connecting(box, ports):
    box.set(calibration={"scfgfu": "gf"})
    with pytest.raises(SensorError, match="unknown force unit") as error:
        AtiNetFT(box.host, connect_timeout=0.5, **ports)
    assert error.value.kind == "connect"


@pytest.mark.parametrize(
    ("arguments", "message"),
    [
        ({"host": ""}, "host must be"),
        ({"host": 192}, "host must be"),
        ({"rdt_port": 0}, "rdt_port must be a port"),
        ({"http_port": 70000}, "http_port must be a port"),
        ({"rdt_port": True}, "rdt_port must be a port"),
        ({"silence_after": 0.0}, "silence_after must be finite and > 0"),
        ({"connect_timeout": float("nan")}, "connect_timeout must be finite"),
        ({"ignore_status_bits": -1}, "32-bit mask"),
        ({"ignore_status_bits": 1 << 32}, "32-bit mask"),
        ({"queue_size": 0}, "queue_size must be an integer >= 1"),
    ],
)
def test_bad_arguments_are_refused_before_connecting(arguments, message):
    arguments = {"host": "127.0.0.1", **arguments}
    with pytest.raises(InvalidInput, match=message):
        AtiNetFT(arguments.pop("host"), **arguments)


def test_a_missing_pynetft_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "pynetft", None)  # import pynetft raises ImportError
    with pytest.raises(MissingDependency, match=r"pip install -e '.*\[ati\]'") as error:
        AtiNetFT("127.0.0.1")
    assert error.value.package == "pynetft" and error.value.extra == "ati"


def test_the_dither_the_box_adds_is_seen_exactly():
    """The emulator's dither is what the adapter reads: each record's own counts, none mixed."""
    with NetFTBox(rate=500.0, dither=7, counts=COUNTS) as dithered:
        with AtiNetFT(dithered.host, rdt_port=dithered.rdt_port, http_port=dithered.http_port) as s:
            wrenches = set()
            for _ in range(20):
                wrenches.add(tuple(np.round(s.read()[1] * 1e6).astype(int)))
                time.sleep(0.004)
    patterns = {tuple(c + d for c, d in zip(COUNTS, dither(k, 7))) for k in range(1, 2000)}
    assert len(wrenches) > 5 and wrenches <= patterns
