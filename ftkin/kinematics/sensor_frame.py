"""Where the sensor sits when the URDF has no sensor frame: :class:`SensorMount`.

A sensor bolted to an existing link (``tool0``, a flange) at a fixed offset
becomes a Pinocchio frame on that link's joint (:func:`add_sensor_frame`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import pinocchio as pin

from ..exceptions import FrameNotFound, InvalidInput
from ..validation import as_vector


@dataclass(frozen=True)
class SensorMount:
    """Where to add a sensor frame when the URDF has none.

    Attributes:
        parent_frame: Existing frame (link) the sensor is bolted to, e.g. ``tool0``.
        translation: Sensor origin in the parent frame [m].
        rpy: Sensor orientation in the parent frame, roll-pitch-yaw [rad]
            (``R = Rz(yaw) Ry(pitch) Rx(roll)``, the URDF convention).
    """

    parent_frame: str
    translation: Sequence[float] = (0.0, 0.0, 0.0)
    rpy: Sequence[float] = (0.0, 0.0, 0.0)

    def placement(self) -> pin.SE3:
        """Sensor placement relative to the parent frame."""
        translation = as_vector(self.translation, 3, "sensor mount translation")
        rpy = as_vector(self.rpy, 3, "sensor mount rpy")
        return pin.SE3(pin.rpy.rpyToMatrix(*rpy), translation)


def add_sensor_frame(model: pin.Model, name: str, mount: SensorMount) -> None:
    """Add frame ``name`` at ``mount`` (relative to its parent frame) to ``model``, in place.

    Raises:
        InvalidInput: ``name`` exists already.
        FrameNotFound: the parent frame is not in the model.
    """
    if model.existFrame(name):
        raise InvalidInput(
            f"frame {name!r} already exists in the model; choose another sensor frame name"
        )
    if not model.existFrame(mount.parent_frame):
        raise FrameNotFound(mount.parent_frame, [frame.name for frame in model.frames])
    parent_id = model.getFrameId(mount.parent_frame)
    parent = model.frames[parent_id]
    placement = parent.placement * mount.placement()
    model.addFrame(
        pin.Frame(name, parent.parentJoint, parent_id, placement, pin.FrameType.OP_FRAME), False
    )
