"""Simulation: known truth in, readings and closed-loop runs out.

:class:`SimulatedSensor` produces raw readings [N, N·m] from known calibration
parameters at given ``R_BS`` (bias + drift + tool gravity + contact + noise;
the drift, :class:`SensorDrift`, warms up, wanders and follows temperature).
:func:`simulate_placement` runs the paper's placement experiment (METHOD.md §6)
with :class:`~ftkin.control.JointAdmittance` in the loop against a
:class:`Surface`. :mod:`ftkin.sim.paper` reproduces the paper's calibration.
:mod:`ftkin.sim.mujoco` (extra ``sim``) closes the loop in the MuJoCo physics
engine: :func:`build_arm_model`, :func:`run_closed_loop`,
:func:`simulate_placement_mujoco`.

Depends on :mod:`ftkin.control`, :mod:`ftkin.io`, :mod:`ftkin.calibration` and below.
"""

from .drift import SensorDrift
from .mujoco import MujocoRecorder, ToolInertia, build_arm_model, run_closed_loop, simulate_placement_mujoco
from .placement import PlacementRun, PlacementScenario, simulate_placement
from .sensor import SimulatedSensor, recording_times
from .surfaces import Surface

__all__ = [
    "MujocoRecorder",
    "PlacementRun",
    "PlacementScenario",
    "SensorDrift",
    "SimulatedSensor",
    "Surface",
    "ToolInertia",
    "build_arm_model",
    "recording_times",
    "run_closed_loop",
    "simulate_placement",
    "simulate_placement_mujoco",
]
