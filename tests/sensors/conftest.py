"""Fixtures of the sensor tests: the emulated Net F/T box and its ports."""

from __future__ import annotations

import pytest

from .netft_box import NetFTBox


@pytest.fixture
def box():
    """An emulated Net F/T box streaming at 1 kHz (N and N·m, 1e6 counts per unit)."""
    with NetFTBox(rate=1000.0) as emulated:
        yield emulated


@pytest.fixture
def ports(box):
    """The emulated box's ports, as :class:`~ftkin.sensors.AtiNetFT`'s keywords."""
    return {"rdt_port": box.rdt_port, "http_port": box.http_port}
