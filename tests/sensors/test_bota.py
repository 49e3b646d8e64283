"""BotaSensor: the real bota_driver through its ``Bota_Dummy`` interface (no hardware).

Faults the dummy never makes are injected by :class:`~bota_dummy.FaultyDriver`, a subclass of
the real ``BotaDriver`` run in the adapter's driver process (``driver=``) that changes what its
``read_frame_blocking`` returns (a frame's status, a repeated frame, a pause) or makes the real
driver fail (deactivated behind the adapter's back); the driver stack underneath is the
vendor's.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ftkin.exceptions import InvalidInput, MissingDependency, SensorError

bd = pytest.importorskip("bota_driver", reason="bota-driver is not installed (extra 'bota')")

from ftkin.sensors import BotaSensor  # noqa: E402

from .bota_dummy import DUMMY_JSON, FAULT_DIRECTORY, Injector, dummy_config  # noqa: E402

FRAME_PERIOD = 3704e-6  # [s] the dummy's get_expected_timestep_us()


def wait_for_fault(sensor, timeout: float = 2.0) -> SensorError:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            sensor.read()
        except SensorError as error:
            return error
        time.sleep(0.002)
    raise AssertionError(f"no fault within {timeout} s")


FAULTY = "tests.sensors.bota_dummy:FaultyDriver"
ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def injector(tmp_path, monkeypatch):
    """The faults of :class:`~bota_dummy.FaultyDriver`, which runs in the driver's process."""
    monkeypatch.setenv(FAULT_DIRECTORY, str(tmp_path))
    monkeypatch.syspath_prepend(str(ROOT))  # the driver's process imports tests.sensors from it
    return Injector(tmp_path)


def test_the_dummy_streams_wrench_imu_and_temperature():
    with BotaSensor(dummy_config()) as sensor:
        t, wrench = sensor.read()
        now = time.monotonic()
        assert wrench.shape == (6,) and not wrench.flags.writeable
        assert 0 <= now - t < 1.0  # a recent stamp on the monotonic clock (a busy machine lags)
        np.testing.assert_allclose(sensor.timestep, FRAME_PERIOD, rtol=1e-12)
        time.sleep(0.5)
        sample = sensor.read_sample()
        stats = sensor.stats()
    assert sample.has_imu and sample.angular_velocity.shape == (3,)
    np.testing.assert_allclose(sample.specific_force, [0.0, 0.0, -9.78], atol=0.25)
    np.testing.assert_allclose(sample.temperature, 25.0, rtol=0, atol=1e-9)
    np.testing.assert_allclose(sample.wrench, [1.0, 2.0, 3.0, 0.1, 0.2, 0.3], atol=0.3)
    # the dummy streams at ~270 Hz: a reader starved by a busy machine gets fewer frames, never
    # more, so the rate is bounded above by the driver's period and is not zero
    assert 0 < stats.rate_hz <= 1.05 / FRAME_PERIOD


def test_a_json_configuration_file_opens_the_same_sensor(tmp_path):
    path = tmp_path / "bota.json"
    path.write_text(DUMMY_JSON)
    with BotaSensor(path) as sensor:
        assert sensor.read()[1].shape == (6,)
        assert "bota.json" in sensor.description


def test_the_lifecycle_is_managed(injector):
    sensor = BotaSensor(dummy_config(), driver=FAULTY)
    assert injector.calls() == ["configure", "activate"]
    sensor.read()
    sensor.close()
    assert injector.calls() == ["configure", "activate", "deactivate", "shutdown"]
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
def test_faults_latch_and_release_the_driver(injector, fault, kind, message):
    injector.set(fault, after=20)
    with BotaSensor(dummy_config(), silence_after=0.05, driver=FAULTY) as sensor:
        error = wait_for_fault(sensor)
        assert error.kind == kind and message in str(error), error
        with pytest.raises(SensorError) as again:
            sensor.read()
        assert again.value.kind == kind
        if kind == "driver":  # the driver's process reported it and shut the driver down
            time.sleep(0.1)  # (deactivated already, behind the adapter's back)
            assert injector.calls() == ["configure", "activate", "shutdown"]
    calls = injector.calls()
    assert calls.count("shutdown") == 1 and calls[-1] == "shutdown"
    assert calls.count("deactivate") == (0 if kind == "driver" else 1)


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
    with pytest.raises(MissingDependency, match=r"pip install -e '.*\[bota\]'") as error:
        BotaSensor("bota.json")
    assert error.value.package == "bota-driver" and error.value.extra == "bota"
