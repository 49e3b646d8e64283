"""Shared fixtures: the bundled arm (loaded once) and seeded random generators."""

from __future__ import annotations

import signal

import numpy as np
import pytest

from ftkin import Arm, SensorModel
from ftkin.sim.sensor import paper_like_truth

# A command started in the background of a non-interactive shell (`make test &`, a CI step run
# that way) inherits SIGINT ignored, and so does every process it starts: the Ctrl-C tests (a
# session interrupted, `ftkin ... ` exiting 130) would then test nothing but the shell. The suite
# restores Python's own handler, so its child processes start with Ctrl-C as a user has it.
if signal.getsignal(signal.SIGINT) == signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


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


@pytest.fixture(scope="module")
def tool() -> SensorModel:
    """A 15 N tool, COM a few cm off the sensor axis, biases, a small base tilt (the estimator
    benchmark's).
    """
    return SensorModel.from_tool(
        15.0 / 9.80665,
        [0.03, -0.02, 0.08],
        [2.0, -1.5, 3.0],
        [0.10, -0.05, 0.02],
        base_tilt=np.deg2rad([0.3, -0.2]),
    )


@pytest.fixture(scope="module")
def rotations(arm) -> np.ndarray:
    """Twelve sensor orientations ``(12, 3, 3)`` of random joint configurations of the bundled
    arm.
    """
    rng = np.random.default_rng(7)
    return arm.rotation_sensor_to_base(arm.random_configurations(12, rng, margin=0.3))
