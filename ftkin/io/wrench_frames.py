"""Which frame a recorded wrench is expressed in (``WrenchStamped.header.frame_id``).

ftkin calibrates raw readings in the sensor frame. Some drivers publish the
wrench in another frame: UR's TCP force (``/force_torque_sensor_broadcaster``,
``getActualTCPForce``) is in the **base** frame. :func:`wrenches_in_sensor_frame`
checks the ``frame_id`` against the arm's sensor frame, converts a base-frame
wrench when the user says so (``wrench_frame="base"``, CLI ``--wrench-frame
base``: ``F_S = R_BSᵀ F_B``, ``M_S = R_BSᵀ M_B``, the torque kept about the
same point, the sensor origin), and otherwise names a mismatch as the likely
problem.
"""

import logging

import numpy as np

from ..exceptions import InvalidInput
from ..kinematics.rotations import wrenches_base_to_sensor

logger = logging.getLogger(__name__)

WRENCH_FRAMES = ("sensor", "base")
"""Frames a recorded wrench can be declared in."""

BASE_FRAME_NAMES = ("world", "universe", "base", "base_link", "base_link_inertia")
"""``frame_id`` values taken for the robot base (besides the URDF's root link)."""


def base_frame_names(arm) -> set[str]:
    """Names that denote the arm's base: :data:`BASE_FRAME_NAMES` and the frames fixed to the
    root.
    """
    return {
        *BASE_FRAME_NAMES,
        *(frame.name for frame in arm.model.frames if frame.parentJoint == 0),
    }


def wrenches_in_sensor_frame(
    wrenches: np.ndarray,
    rotations: np.ndarray,
    frame_id: str,
    arm,
    wrench_frame: str = "sensor",
    source: str = "",
) -> np.ndarray:
    """The recorded wrenches ``(N, 6)`` [N, N·m] in the sensor frame.

    Args:
        wrenches: As recorded.
        rotations: ``(N, 3, 3)`` ``R_BS`` of each reading (URDF sensor frame).
        frame_id: The messages' ``header.frame_id`` ("" when unset).
        arm: The arm (its sensor frame and base frame names).
        wrench_frame: ``"sensor"`` (default: taken as they are) or ``"base"`` (rotated into the
            sensor frame).
        source: Where they came from, for the messages.

    Raises:
        InvalidInput: unknown ``wrench_frame``.
    """
    if wrench_frame not in WRENCH_FRAMES:
        raise InvalidInput(
            f"wrench_frame must be one of {', '.join(WRENCH_FRAMES)}, got {wrench_frame!r}"
        )
    if wrench_frame == "base":
        if frame_id and frame_id not in base_frame_names(arm):
            logger.warning(
                "%s: converting wrenches from the base frame although their frame_id is %r",
                source,
                frame_id,
            )
        return wrenches_base_to_sensor(rotations, wrenches)
    if frame_id and frame_id != arm.sensor_frame:
        if frame_id in base_frame_names(arm):
            logger.warning(
                "%s: the wrenches are published in the base frame %r (as a UR TCP force is), not "
                "in the sensor frame "
                "%r: this is the likely problem if the calibration fits badly; convert them with "
                "--wrench-frame base "
                "(wrench_frame='base')",
                source,
                frame_id,
                arm.sensor_frame,
            )
        else:
            logger.warning(
                "%s: the wrench frame_id %r is not the arm's sensor frame %r: if the readings are "
                "expressed in that "
                "frame, this is the likely problem (choose the matching --sensor-frame, or "
                "estimate the mount with "
                "--estimate-mount full)",
                source,
                frame_id,
                arm.sensor_frame,
            )
    return wrenches
