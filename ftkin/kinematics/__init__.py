"""Kinematics: joint angles in, sensor orientation and Jacobians out.

Takes a URDF (or a robot name) and joint positions ``q`` [rad, m]; gives the
sensor orientation ``R_BS`` (``rotation_sensor_to_base``, sensor frame → base
frame), frame placements [m] and Jacobians, all through Pinocchio. Also the
orientation conversions (Euler angles, quaternions → ``R_BS``) and the
self-collision check used by pose planning.

Depends only on the bottom layer (:mod:`ftkin.exceptions`, :mod:`ftkin.validation`).
"""

from .._lazy import lazy_exports

_EXPORTS = {
    "Arm": ".arm",
    "ROBOTS": ".robots",
    "SensorMount": ".arm",
    "bundled_urdf_path": ".arm",
    "euler_zyx_deg_to_matrix": ".rotations",
    "load_robot": ".robots",
    "mounted_arm": ".mounting",
    "quaternion_to_matrix": ".rotations",
}
"""Public name → module, loaded on first access (PEP 562): importing one module of this stage does
not import them all.
"""

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

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS, globals())
