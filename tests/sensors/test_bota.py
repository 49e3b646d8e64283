"""BotaSensor: the real bota_driver through its ``Bota_Dummy`` interface (no hardware).

Faults the dummy never makes are injected by a subclass of the real ``BotaDriver`` that changes
what its ``read_frame_blocking`` returns (a frame's status, a repeated frame, a pause) or makes
the real driver fail (deactivated behind the adapter's back); the driver stack underneath is the
vendor's.
"""

from __future__ import annotations

import sys
import time
from types import SimpleNamespace

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput, MissingDependency, SensorError

bd = pytest.importorskip("bota_driver", reason="bota-driver is not installed (extra 'bota')")

from ftkin.sensors import BotaSensor  # noqa: E402

from .bota_dummy import DUMMY_JSON, dummy_config  # noqa: E402

FRAME_PERIOD = 3704e-6  # [s] the dummy's get_expected_timestep_us()


class Recording(bd.BotaDriver):
    """The real driver; its lifecycle calls are recorded, and after ``after`` frames ``fault``
    changes what ``read_frame_blocking`` gives."""

    calls: list[str] = []
    fault: str | None = None
    after = 20

    def __init__(self, config):
        super().__init__(config)
        self.frames = 0
        self.held = None

    def _record(self, name):
        Recording.calls.append(name)
        return getattr(super(), name)()

    def configure(self):
        return self._record("configure")

    def activate(self):
        return self._record("activate")

    def deactivate(self):
        return self._record("deactivate")

    def shutdown(self):
        return self._record("shutdown")

    def read_frame_blocking(self):
        self.frames += 1
        if self.frames <= self.after or Recording.fault is None:
            return super().read_frame_blocking()
        fault = Recording.fault
        if fault == "driver":  # the real driver, no longer streaming, raises RuntimeError
            if self.frames == self.after + 1:
                super().deactivate()
            return super().read_frame_blocking()
        if fault == "silence":
            time.sleep(0.5)
            return super().read_frame_blocking()
        frame = super().read_frame_blocking()
        if fault == "stall":  # frames keep coming, all the last one again
            self.held = self.held or frame
            return self.held
        flags = {name: getattr(frame.status, name) for name in ("invalid", "raw", "throttled")}
        flags.update(overrange=1, val=1)  # a saturated channel
        return SimpleNamespace(
            **{
                name: getattr(frame, name)
                for name in ("force", "torque", "acceleration", "angular_rate", "temperature")
            },
            timestamp=frame.timestamp,
            status=SimpleNamespace(**flags),
        )


def wait_for_fault(sensor, timeout: float = 2.0) -> SensorError:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            sensor.read()
        except SensorError as error:
            return error
        time.sleep(0.002)
    raise AssertionError(f"no fault within {timeout} s")


@pytest.fixture
def recording(monkeypatch):
    Recording.calls, Recording.fault = [], None
    monkeypatch.setattr(bd, "BotaDriver", Recording)
    return Recording


def test_the_dummy_streams_wrench_imu_and_temperature():
    with BotaSensor(dummy_config()) as sensor:
        t, wrench = sensor.read()
        now = time.monotonic()
        assert wrench.shape == (6,) and not wrench.flags.writeable
        assert 0 <= now - t < 0.05
        np.testing.assert_allclose(sensor.timestep, FRAME_PERIOD, rtol=1e-12)
        time.sleep(0.5)
        sample = sensor.read_sample()
        stats = sensor.stats()
    assert sample.has_imu and sample.angular_velocity.shape == (3,)
    np.testing.assert_allclose(sample.specific_force, [0.0, 0.0, -9.78], atol=0.25)
    np.testing.assert_allclose(sample.temperature, 25.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sample.wrench, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3], atol=0.3)
    np.testing.assert_allclose(stats.rate_hz, 1.0 / FRAME_PERIOD, rtol=0.05)  # ~270 Hz


def test_a_json_configuration_file_opens_the_same_sensor(tmp_path):
    path = tmp_path / "bota.json"
    path.write_text(DUMMY_JSON)
    with BotaSensor(path) as sensor:
        assert sensor.read()[1].shape == (6,)
        assert "bota.json" in sensor.description


def test_the_lifecycle_is_managed(recording):
    sensor = BotaSensor(dummy_config())
    assert recording.calls == ["configure", "activate"]
    sensor.read()
    sensor.close()
    assert recording.calls == ["configure", "activate", "deactivate", "shutdown"]
    with pytest.raises(SensorError, match="is closed"):
        sensor.read()


@pytest.mark.parametrize(
    ("fault", "kind", "message"),
    [
        ("status", "status", "flags its frame overrange"),
        ("driver", "driver", "RuntimeError: Driver"),
        ("stall", "stall", "records keep coming"),
        ("silence", "silence", "no new sample"),
    ],
)
def test_faults_latch_and_release_the_driver(recording, fault, kind, message):
    recording.fault = fault
    with BotaSensor(dummy_config(), silence_after=0.05) as sensor:
        error = wait_for_fault(sensor)
        assert error.kind == kind and message in str(error), error
        with pytest.raises(SensorError) as again:
            sensor.read()
        assert again.value.kind == kind
        if fault in ("status", "driver"):  # the reading thread ended and released the driver
            time.sleep(0.05)
            assert recording.calls[-1] == "shutdown"
    assert recording.calls.count("shutdown") == 1


def test_a_configuration_the_driver_refuses_is_a_connect_fault(tmp_path):
    path = tmp_path / "broken.json"
    path.write_text('{"not_a_driver_config": {}}')
    with pytest.raises(SensorError, match="refuses the configuration") as error:
        BotaSensor(path)
    assert error.value.kind == "connect"
    config = dummy_config()
    config.communication_interface_name = "Bota_Nowhere"
    with pytest.raises(SensorError) as error:
        BotaSensor(config)
    assert error.value.kind == "connect"


@pytest.mark.parametrize(
    ("config", "message"),
    [("no/such/bota.json", "does not exist"), (42, "config must be the path")],
)
def test_a_config_that_is_neither_a_file_nor_a_driver_config_is_refused(config, message):
    with pytest.raises(InvalidInput, match=message):
        BotaSensor(config)


def test_a_missing_bota_driver_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "bota_driver", None)
    with pytest.raises(MissingDependency, match=r"pip install 'ftkin\[bota\]'") as error:
        BotaSensor("bota.json")
    assert error.value.package == "bota-driver" and error.value.extra == "bota"
