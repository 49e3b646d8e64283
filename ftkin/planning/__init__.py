"""Pose planning: an arm and limits in, calibration poses and their predicted accuracy out.

:func:`plan_poses` takes an :class:`~ftkin.kinematics.Arm`, the expected tool
(weight [N], centre of mass [m]), sensor noise and :class:`PoseConstraints`
(joint ranges [rad], floor height [m], tilt limit [rad], self-collision) and
gives joint configurations [rad] that maximise the Fisher information of the
calibration. :func:`evaluate_poses` predicts the standard error of every
parameter for any pose set before a reading is taken.

Depends on :mod:`ftkin.calibration` (information) and :mod:`ftkin.kinematics`.
"""

from .constraints import PoseConstraints
from .evaluation import PoseEvaluation, evaluate_poses
from .excitation import ExcitationPlan, FourierTrajectory, plan_excitation
from .plan import PosePlan, plan_poses

__all__ = [
    "ExcitationPlan",
    "FourierTrajectory",
    "PoseConstraints",
    "PoseEvaluation",
    "PosePlan",
    "evaluate_poses",
    "plan_excitation",
    "plan_poses",
]
