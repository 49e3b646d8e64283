"""Simulation: known truth in, readings and closed-loop runs out.

:class:`SimulatedSensor` produces raw readings [N, N·m] from known calibration
parameters at given ``R_BS`` (bias + drift + tool gravity + contact + noise;
the drift, :class:`SensorDrift`, warms up, wanders and follows temperature).
:mod:`ftkin.sim.inputs` writes example input files from it (samples, logs,
recordings, bags: ``ftkin simulate samples|log|recording|bag``).
:func:`simulate_placement` runs the paper's placement experiment (METHOD.md §6)
with :class:`~ftkin.control.JointAdmittance` in the loop against a
:class:`Surface`. :mod:`ftkin.sim.paper` reproduces the paper's calibration.
:mod:`ftkin.sim.mujoco` (extra ``sim``) closes the loop in the MuJoCo physics
engine: :func:`build_arm_model`, :func:`run_closed_loop`,
:func:`simulate_placement_mujoco`.

Depends on :mod:`ftkin.control`, :mod:`ftkin.io`, :mod:`ftkin.calibration` and below.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "MujocoRecorder": ".mujoco",
    "PlacementRun": ".placement",
    "PlacementScenario": ".placement",
    "SensorDrift": ".sensor_drift",
    "SimulatedInputs": ".inputs",
    "SimulatedSensor": ".sensor",
    "Surface": ".surfaces",
    "ToolInertia": ".mujoco",
    "build_arm_model": ".mujoco",
    "recording_times": ".sensor",
    "run_closed_loop": ".mujoco",
    "simulate_placement": ".placement",
    "simulate_placement_mujoco": ".mujoco",
}
"""Public name → module, loaded on first access (PEP 562): importing one module of this stage does
not import them all.
"""

__all__ = [
    "MujocoRecorder",
    "PlacementRun",
    "PlacementScenario",
    "SensorDrift",
    "SimulatedInputs",
    "SimulatedSensor",
    "Surface",
    "ToolInertia",
    "build_arm_model",
    "recording_times",
    "run_closed_loop",
    "simulate_placement",
    "simulate_placement_mujoco",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
