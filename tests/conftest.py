"""Shared fixtures: the bundled arm (loaded once) and seeded random generators."""

from __future__ import annotations

import numpy as np
import pytest

from ftkin import Arm
from ftkin.simulation import paper_like_truth


@pytest.fixture(scope="session")
def arm() -> Arm:
    """The bundled six-axis arm with sensor frame ft_sensor and tool frame tool."""
    return Arm.default()


@pytest.fixture
def rng() -> np.random.Generator:
    """A fresh generator with a fixed seed for each test."""
    return np.random.default_rng(12345)


@pytest.fixture(scope="session")
def truth():
    """Simulation truth close to the paper's setup (3.15 N tool, COM 47 mm on z, small tilt)."""
    return paper_like_truth()
