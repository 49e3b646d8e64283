"""The paper's two-step linear least squares (METHOD.md §3), ``method="linear"``.

Step 1 fits gravity in the base frame ``a`` and the force bias ``F0`` from the
force channels; step 2 fits the centre of mass ``P`` and the auxiliary
``b = M0 + F0 × P`` from the torque channels with the measured forces as
regressors, then recovers ``M0 = b - F0 × P``. It reproduces the paper's
printed numbers exactly; :mod:`ftkin.calibration.ml` improves on it.
"""

import numpy as np

from .model import STANDARD_GRAVITY, SensorModel, cross_rows
from .observability import (
    check_gravity_directions,
    check_orientations,
    check_pose_count,
    force_regressor,
    torque_regressor,
)
from .samples import PoseAverages


def fit_linear(poses: PoseAverages, g: float = STANDARD_GRAVITY) -> SensorModel:
    """Two-step least squares on per-pose mean readings.

    Raises:
        UnobservableParameters: fewer than three poses, orientations that
            cannot separate gravity from bias, or gravity along one sensor
            direction only.
    """
    check_pose_count(len(poses))
    check_orientations(poses.rotations)
    theta = two_step(poses.rotations, poses.wrenches)
    check_gravity_directions(poses.rotations, theta[0:3])
    return SensorModel(theta[3:6], theta[6:9], theta[0:3], theta[9:12], g)


def two_step(rotations: np.ndarray, wrenches: np.ndarray) -> np.ndarray:
    """``θ = [a, F0, M0, P]`` (12,) of :func:`fit_linear` without its checks (poses it would
    refuse get numpy's minimum-norm answer): ``rotations`` ``(N, 3, 3)`` ``R_BS``, ``wrenches``
    ``(N, 6)`` per-pose means [N, N·m].
    """
    forces, torques = wrenches[:, :3], wrenches[:, 3:]
    step1, *_ = np.linalg.lstsq(force_regressor(rotations), forces.reshape(-1), rcond=None)
    gravity_in_base, force_offset = step1[:3], step1[3:]
    step2, *_ = np.linalg.lstsq(torque_regressor(forces), torques.reshape(-1), rcond=None)
    center_of_mass, auxiliary = step2[:3], step2[3:]
    torque_offset = auxiliary - cross_rows(force_offset, center_of_mass)  # M0 = b − F0 × P
    return np.concatenate([gravity_in_base, force_offset, torque_offset, center_of_mass])
