"""Kinematics: joint angles in, sensor orientation and Jacobians out.

Takes a URDF (or a robot name) and joint positions ``q`` [rad, m]; gives the
sensor orientation ``R_BS`` (``rotation_sensor_to_base``, sensor frame → base
frame), frame placements [m] and Jacobians, all through Pinocchio. Also the
orientation conversions (Euler angles, quaternions → ``R_BS``) and the
self-collision check used by pose planning.

Depends only on the bottom layer (:mod:`ftkin.exceptions`, :mod:`ftkin.validation`).
"""

from .arm import Arm, SensorMount, bundled_urdf_path
from .mounting import mounted_arm
from .robots import ROBOTS, load_robot
from .rotations import euler_zyx_deg_to_matrix, quaternion_to_matrix

__all__ = [
    "Arm",
    "ROBOTS",
    "SensorMount",
    "bundled_urdf_path",
    "euler_zyx_deg_to_matrix",
    "load_robot",
    "mounted_arm",
    "quaternion_to_matrix",
]
