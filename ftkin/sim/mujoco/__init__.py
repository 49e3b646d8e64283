"""Closed-loop simulation in MuJoCo (optional extra ``sim``).

:func:`build_arm_model` builds the arm, its sensor, tool, grasped object and a
table with a sponge and a book from the arm's URDF; :class:`MujocoSensor`
turns MuJoCo's ideal wrench into the raw readings of a real sensor (bias,
noise, saturation, sample rate, one-tick delay); :func:`run_closed_loop` steps
the physics with a controller (e.g. :class:`~ftkin.control.JointAdmittance`) in
the loop. ``mujoco`` is imported only when a model is built.
"""

from ..._lazy import lazy_exports

_EXPORTS = {
    "ArmSimulation": ".arm_model",
    "ClosedLoopRun": ".closed_loop",
    "GraspedObject": ".arm_model",
    "MujocoRecorder": ".recording",
    "MujocoSensor": ".mujoco_sensor",
    "ToolInertia": ".tool_inertia",
    "build_arm_model": ".arm_model",
    "run_closed_loop": ".closed_loop",
    "simulate_placement_mujoco": ".mujoco_placement",
}
"""Public name → module, loaded on first access (PEP 562)."""

__all__ = [
    "ArmSimulation",
    "ClosedLoopRun",
    "GraspedObject",
    "MujocoRecorder",
    "MujocoSensor",
    "ToolInertia",
    "build_arm_model",
    "run_closed_loop",
    "simulate_placement_mujoco",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
