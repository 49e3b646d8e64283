"""Pose planning: an arm and limits in, calibration poses and their predicted accuracy out.

:func:`plan_poses` takes an :class:`~ftkin.kinematics.Arm` and a :class:`PlanSpec`: the
number of poses, :class:`PoseConstraints` (joint ranges [rad], floor height [m], tilt limit
[rad], self-collision) and the :class:`ExpectedCalibration` (tool weight [N], centre of mass
[m], sensor noise, mount, drift), and gives joint configurations [rad] that maximise the
Fisher information of the calibration. :func:`evaluate_poses` predicts the standard error of
every parameter for any pose set before a reading is taken.

Depends on :mod:`ftkin.calibration` (information) and :mod:`ftkin.kinematics`.
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "ExcitationPlan": ".excitation",
    "ExcitationSpec": ".excitation",
    "ExpectedCalibration": ".evaluation",
    "FourierTrajectory": ".excitation",
    "PoseConstraints": ".constraints",
    "PoseEvaluation": ".evaluation",
    "PlanSpec": ".plan",
    "PosePlan": ".plan",
    "evaluate_poses": ".evaluation",
    "plan_excitation": ".excitation",
    "plan_poses": ".plan",
}
"""Public name → module, loaded on first access (PEP 562): importing one module of this stage does
not import them all.
"""

__all__ = [
    "ExcitationPlan",
    "ExcitationSpec",
    "ExpectedCalibration",
    "FourierTrajectory",
    "PoseConstraints",
    "PlanSpec",
    "PoseEvaluation",
    "PosePlan",
    "evaluate_poses",
    "plan_excitation",
    "plan_poses",
]

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
