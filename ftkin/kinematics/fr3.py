"""The Franka FR3 with the Franka Hand, bundled: 7 joints, the wrist sensor at the hand frame.

The URDF is franka_description's FR3 (Apache-2.0, Franka Robotics GmbH) as franky-sim ships it,
with its collision meshes (``urdf/fr3/``, see the NOTICE there). The sensor frame is
``fr3_hand``: the flange ``fr3_link8`` turned by −45° about z, where the hand (and a sensor
mounted between flange and hand) sits. The fingers are locked (:meth:`Arm.from_urdf` keeps the
joints between the base and the sensor), the tool frame is the hand's ``fr3_hand_tcp``. The arm is
the robot ``fr3`` of :data:`ftkin.kinematics.robots.ROBOTS` (``--robot fr3``), whose controller
takes a payload in the flange ``fr3_link8`` (libfranka ``F_x_Cload``), not in the hand frame.
"""

from pathlib import Path

from .arm import Arm, bundled_urdf_path

FR3_SENSOR_FRAME = "fr3_hand"
"""The sensor frame of the bundled FR3: the hand frame."""
FR3_TOOL_FRAME = "fr3_hand_tcp"
FR3_FLANGE_FRAME = "fr3_link8"
"""The FR3's flange: the frame libfranka takes the load in (``F_x_Cload``)."""


def fr3_urdf_path() -> Path:
    """Path of the bundled FR3 URDF (installed package first, then the source checkout)."""
    return bundled_urdf_path("fr3/fr3.urdf")


def fr3_arm(tool_frame: str | None = FR3_TOOL_FRAME) -> Arm:
    """The bundled FR3 as an :class:`Arm`: sensor frame ``fr3_hand``, 7 joints (fingers locked)."""
    arm = Arm.from_urdf(fr3_urdf_path(), FR3_SENSOR_FRAME, tool_frame)
    arm.robot_name = "fr3"
    return arm
