"""Closed-loop simulation in MuJoCo (optional extra ``sim``).

:func:`build_arm_model` builds the arm, its sensor, tool, grasped object and a
table with a sponge and a book from the arm's URDF; :class:`MujocoSensor`
turns MuJoCo's ideal wrench into the raw readings of a real sensor (bias,
noise, saturation, sample rate, one-tick delay); :func:`run_closed_loop` steps
the physics with a controller (e.g. :class:`~ftkin.control.JointAdmittance`) in
the loop. ``mujoco`` is imported only when a model is built.
"""

from .arm_model import ArmSimulation, GraspedObject, build_arm_model
from .closed_loop import ClosedLoopRun, run_closed_loop
from .mujoco_placement import simulate_placement_mujoco
from .mujoco_sensor import MujocoSensor
from .recording import MujocoRecorder
from .tool_inertia import ToolInertia

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
