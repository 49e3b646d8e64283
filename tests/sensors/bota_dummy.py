"""bota_driver's ``Bota_Dummy`` interface: the real driver stack without hardware (~270 Hz)."""

from __future__ import annotations

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
    import bota_driver as bd

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
