"""bota_driver's ``Bota_Dummy`` interface (the real driver stack without hardware, ~270 Hz), and
a driver that injects the faults the dummy never makes. Needs bota_driver."""

from __future__ import annotations

import os
import time
from pathlib import Path
from types import SimpleNamespace

import bota_driver as bd

DUMMY_JSON = """{
  "driver_config": {
    "product_name": "BFT-DUMMY-DUMMY-DUMMY",
    "serial_number": "SN000001",
    "communication_interface_name": "Bota_Dummy",
    "communication_interface_params": {},
    "sensor_operation_params": {"app_mode": 2, "app_submode": 7}
  }
}
"""
"""The dummy's configuration as the vendor's JSON file."""


def dummy_config():
    """The same configuration as a ``bota_driver.BotaDriverConfig``."""
    config = bd.BotaDriverConfig()
    config.product_name = "BFT-DUMMY-DUMMY-DUMMY"
    config.serial_number = "SN000001"
    config.communication_interface_name = "Bota_Dummy"
    config.dummy_communication_interface_params = bd.BotaDummyCommunicationInterfaceConfig()
    operation = bd.GenASensorOperationConfig()
    operation.app_mode = 2
    operation.app_submode = 7
    config.genA_sensor_operation_params = operation
    return config


FAULT_DIRECTORY = "FTKIN_TEST_BOTA_FAULTS"
"""The environment variable naming the folder through which a test drives :class:`FaultyDriver`
(in the adapter's driver process)."""


class Injector:
    """The test's side of :class:`FaultyDriver`: ``set`` a fault, read the lifecycle ``calls``.

    Args:
        folder: An empty folder; the environment variable :data:`FAULT_DIRECTORY` must name it
            when the sensor is opened (the driver's process inherits it).
    """

    def __init__(self, folder):
        self.folder = Path(folder)

    def set(self, fault: str | None, after: int = 0) -> None:
        """From the frame after ``after`` frames, ``fault``: None, ``"status"``, ``"driver"``,
        ``"stall"``, ``"silence"``."""
        path = self.folder / "fault"
        if fault is None:
            path.unlink(missing_ok=True)
            (self.folder / "raised_at").unlink(missing_ok=True)
        else:
            staged = self.folder / "fault.new"
            staged.write_text(f"{fault} {after}")
            staged.replace(path)  # the driver never reads half a file

    def raised_at(self) -> float | None:
        """When the real driver raised for the ``"driver"`` fault [s, monotonic], or None."""
        path = self.folder / "raised_at"
        return float(path.read_text()) if path.exists() else None

    def calls(self) -> list[str]:
        """The driver's lifecycle calls so far, in order."""
        path = self.folder / "calls"
        return path.read_text().split() if path.exists() else []


class FaultyDriver(bd.BotaDriver):
    """The real ``bota_driver.BotaDriver``, its lifecycle calls recorded and a fault applied as
    :class:`Injector` says: after the frame that comes when the fault is set, a frame flagged
    overrange (``"status"``), the real driver's own error once deactivated behind the
    adapter's back (``"driver"``), the last frame again and again (``"stall"``), or nothing for
    0.5 s (``"silence"``). Opened in the adapter's driver process as
    ``driver="tests.sensors.bota_dummy:FaultyDriver"``."""

    def __init__(self, config):
        super().__init__(config)
        self.folder = Path(os.environ[FAULT_DIRECTORY])
        self.frames, self.last, self.deactivated = 0, None, False

    def _record(self, name):
        with open(self.folder / "calls", "a") as calls:
            calls.write(name + "\n")
        return getattr(bd.BotaDriver, name)(self)

    def configure(self):
        return self._record("configure")

    def activate(self):
        return self._record("activate")

    def deactivate(self):
        return self._record("deactivate")

    def shutdown(self):
        return self._record("shutdown")

    def _fault(self) -> str | None:
        try:
            name, after = (self.folder / "fault").read_text().split()
        except FileNotFoundError:
            return None
        return name if self.frames > int(after) else None

    def read_frame_blocking(self):
        frame = super().read_frame_blocking()
        self.frames += 1
        fault = self._fault()
        if fault is None:
            self.last = frame
            return frame
        if fault == "driver":  # the real driver, no longer streaming, raises
            if not self.deactivated:
                self.deactivated = True
                bd.BotaDriver.deactivate(self)
            try:
                return super().read_frame_blocking()
            except Exception:
                (self.folder / "raised_at").write_text(repr(time.monotonic()))
                raise
        if fault == "silence":
            time.sleep(0.5)
            return frame
        if fault == "stall":  # frames keep coming, all the one before the fault again
            return self.last
        flags = {name: getattr(frame.status, name) for name in ("invalid", "raw")}
        flags.update(overrange=1, throttled=0)  # a saturated channel
        fields = ("force", "torque", "acceleration", "angular_rate", "temperature", "timestamp")
        return SimpleNamespace(
            **{name: getattr(frame, name) for name in fields}, status=SimpleNamespace(**flags)
        )
