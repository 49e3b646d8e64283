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
    forces, torques = poses.wrenches[:, :3], poses.wrenches[:, 3:]
    step1, *_ = np.linalg.lstsq(force_regressor(poses.rotations), forces.reshape(-1), rcond=None)
    gravity_in_base, force_offset = step1[:3], step1[3:]
    check_gravity_directions(poses.rotations, gravity_in_base)
    step2, *_ = np.linalg.lstsq(torque_regressor(forces), torques.reshape(-1), rcond=None)
    center_of_mass, auxiliary = step2[:3], step2[3:]
    torque_offset = auxiliary - cross_rows(force_offset, center_of_mass)  # M0 = b − F0 × P
    return SensorModel(force_offset, torque_offset, gravity_in_base, center_of_mass, g)
