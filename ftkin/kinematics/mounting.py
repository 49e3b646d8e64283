"""Fold the sensor's real mount into an arm's sensor frame.

A calibration that estimated the mount ``R_M`` (URDF sensor frame → real
sensor frame; the real orientation is ``R_BS = R_BS_urdf · R_Mᵀ``) is applied
at run time by changing the placement of the arm's sensor frame, not by an
extra rotation per tick: :func:`mounted_arm` returns a copy of the arm whose
sensor frame is rotated by ``R_Mᵀ`` relative to the URDF's (origin kept), so
forward kinematics, Jacobians and the control loop see the real sensor with
no added work.
"""

import copy

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from .arm import Arm


def mounted_arm(arm: Arm, mount_rotation) -> Arm:
    """A copy of ``arm`` whose sensor frame is the real sensor's (``R_BS = R_BS_urdf · R_Mᵀ``).

    Args:
        arm: The arm as its URDF describes it (not already mounted).
        mount_rotation: ``R_M`` ``(3, 3)``, URDF sensor frame → real sensor frame.

    Returns:
        ``arm`` itself when ``R_M`` is the identity, else a new :class:`Arm`
        (its own Pinocchio model and data; geometry shared) with
        ``mount_rotation`` set.

    Raises:
        InvalidInput: ``R_M`` is not a rotation, or ``arm`` already carries another mount.
    """
    rotation = np.asarray(mount_rotation, dtype=float)
    if (
        rotation.shape != (3, 3)
        or not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-6)
        or np.linalg.det(rotation) <= 0
    ):
        raise InvalidInput(
            f"mount_rotation must be a (3, 3) rotation matrix, got {rotation.tolist()}"
        )
    if arm.mount_rotation is not None:
        if np.allclose(arm.mount_rotation, rotation, atol=1e-12):
            return arm
        raise InvalidInput(
            "this Arm already carries another sensor mount; start from the arm its URDF describes"
        )
    if np.array_equal(rotation, np.eye(3)):
        return arm
    mounted = copy.copy(arm)
    model = pin.Model(arm.model)
    frame = model.frames[arm.sensor_frame_id]
    frame.placement = frame.placement * pin.SE3(rotation.T.copy(), np.zeros(3))
    model.frames[arm.sensor_frame_id] = frame
    mounted.model, mounted.data = model, model.createData()
    mounted._geometry = dict(arm._geometry)
    mounted._chain = False  # the arm's batch chain ends at the URDF sensor frame: rebuilt
    mounted.mount_rotation = rotation.copy()
    return mounted
