"""Universal Robots e-Series arms (UR3e, UR5e, UR10e, UR16e) and the UR20 and UR30, from UR's DH
parameters: the base and flange frames the controller reports.

**Source.** The nominal Denavit–Hartenberg parameters Universal Robots publishes in "DH parameters
for calculations of kinematics and dynamics" (universal-robots.com, articles/ur/
application-installation/dh-parameters-for-calculations-of-kinematics-and-dynamics), for all six
arms. They are engineering data, typed in here (no file of UR's is copied); they agree to every
digit with the ``default_kinematics.yaml`` of UR's own ROS 2 description
(``UniversalRobots/Universal_Robots_ROS2_Description``, BSD-3-Clause), which also gives the joint
limits used here (every joint ±2π except the elbow, ±π; the velocity limits of UR's datasheets).

**Frames.** Standard DH, ``ᴮT_tool0(q) = T₁ ⋯ T₆`` with ``Tᵢ = Rz(θᵢ) Tz(dᵢ) Tx(aᵢ) Rx(αᵢ)``,
``θᵢ = qᵢ`` (UR's DH has no joint offsets), ``α = (π/2, 0, 0, π/2, −π/2, 0)`` for every arm:

* ``base``: the controller's base frame, the one RTDE's ``actual_TCP_pose`` is expressed in (ROS's
  ``base`` frame; ROS's ``base_link`` is turned by π about z from it);
* ``tool0``: the tool flange as the controller reports it with a zero TCP offset (z out of the
  flange face): ``actual_TCP_pose`` is ``ᴮT_tool0(actual_q)`` as position and rotation vector.

The flange *orientation* depends on the joint angles and the twists ``α`` only, which all UR arms
share: :func:`flange_rotation` needs no model. Each real arm is calibrated at the factory and its
controller computes ``actual_TCP_pose`` with its own calibrated parameters, which differ from these
nominal ones by about a millimetre at most; ftkin's sensor orientation ``R_BS`` comes from the
nominal model.

The model is built in Pinocchio directly (revolute joints about z, no URDF, no meshes): an
:class:`~ftkin.kinematics.arm.Arm` with the sensor frame ``ft_sensor`` at ``tool0`` (optionally
offset), registered as ``--robot ur3e|ur5e|ur10e|ur16e|ur20|ur30``. It has no collision geometry
(plan poses with ``--no-self-collision``, or record them by freedriving the arm).
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from .arm import Arm, SensorMount, add_sensor_frame

BASE_FRAME = "base"
FLANGE_FRAME = "tool0"
"""The flange frame, as the controller reports it with a zero TCP offset."""
JOINT_NAMES = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
"""UR's joint names, in ``actual_q`` order."""
TWISTS = (np.pi / 2, 0.0, 0.0, np.pi / 2, -np.pi / 2, 0.0)
"""The DH twists ``α`` [rad], the same for every UR arm."""
_POSITION_LIMITS = (2 * np.pi, 2 * np.pi, np.pi, 2 * np.pi, 2 * np.pi, 2 * np.pi)  # ± [rad]


@dataclass(frozen=True)
class UrDh:
    """One arm's DH lengths [m] (``a₁ = a₄ = a₅ = a₆ = 0``, ``d₂ = d₃ = 0``) and joint speeds.

    Attributes:
        name: The ``--robot`` name.
        d1, a2, a3, d4, d5, d6: UR's published DH parameters [m].
        max_speeds: Joint velocity limits [rad/s], shoulder pan first.
        description: One line for listings.
    """

    name: str
    d1: float
    a2: float
    a3: float
    d4: float
    d5: float
    d6: float
    max_speeds: tuple[float, ...]
    description: str

    @property
    def d(self) -> tuple[float, ...]:
        """``(d₁, …, d₆)`` [m]."""
        return (self.d1, 0.0, 0.0, self.d4, self.d5, self.d6)

    @property
    def a(self) -> tuple[float, ...]:
        """``(a₁, …, a₆)`` [m]."""
        return (0.0, self.a2, self.a3, 0.0, 0.0, 0.0)


def _degrees(*values: float) -> tuple[float, ...]:
    return tuple(float(np.deg2rad(value)) for value in values)


UR_DH: dict[str, UrDh] = {
    arm.name: arm
    for arm in (
        UrDh("ur3e", 0.15185, -0.24355, -0.2132, 0.13105, 0.08535, 0.0921,
             _degrees(180, 180, 180, 360, 360, 360), "Universal Robots UR3e"),
        UrDh("ur5e", 0.1625, -0.425, -0.3922, 0.1333, 0.0997, 0.0996,
             _degrees(180, 180, 180, 180, 180, 180), "Universal Robots UR5e"),
        UrDh("ur10e", 0.1807, -0.6127, -0.57155, 0.17415, 0.11985, 0.11655,
             _degrees(120, 120, 180, 180, 180, 180), "Universal Robots UR10e"),
        UrDh("ur16e", 0.1807, -0.4784, -0.36, 0.17415, 0.11985, 0.11655,
             _degrees(120, 120, 180, 180, 180, 180), "Universal Robots UR16e"),
        UrDh("ur20", 0.2363, -0.862, -0.7287, 0.201, 0.1593, 0.1543,
             _degrees(120, 120, 150, 210, 210, 210), "Universal Robots UR20"),
        UrDh("ur30", 0.2363, -0.637, -0.5037, 0.201, 0.1593, 0.1543,
             _degrees(120, 120, 150, 210, 210, 210), "Universal Robots UR30"),
    )
}  # fmt: skip
"""UR's published DH parameters by ``--robot`` name."""


def _dh_placement(d: float, a: float, alpha: float) -> pin.SE3:
    """``Tz(d) Tx(a) Rx(α)``: the constant part of one DH transform."""
    return pin.SE3(pin.utils.rotate("x", alpha), np.array([a * 1.0, 0.0, d * 1.0]))


def dh_model(dh: UrDh) -> pin.Model:
    """The Pinocchio model of one arm: six joints about z, frames ``base`` and ``tool0``."""
    model = pin.Model()
    model.name = dh.name
    model.addFrame(pin.Frame(BASE_FRAME, 0, 0, pin.SE3.Identity(), pin.FrameType.OP_FRAME), False)
    parent, placement = 0, pin.SE3.Identity()
    for index, name in enumerate(JOINT_NAMES):
        limit = _POSITION_LIMITS[index]
        joint = model.addJoint(
            parent,
            pin.JointModelRZ(),
            placement,
            name,
            np.array([1e3]),
            np.array([dh.max_speeds[index]]),
            np.array([-limit]),
            np.array([limit]),
        )
        model.appendBodyToJoint(joint, pin.Inertia.Zero(), pin.SE3.Identity())
        model.addJointFrame(joint)
        placement = _dh_placement(dh.d[index], dh.a[index], TWISTS[index])
        parent = joint
    model.addFrame(
        pin.Frame(
            FLANGE_FRAME, parent, model.getFrameId(JOINT_NAMES[-1]), placement,
            pin.FrameType.OP_FRAME,
        ),
        False,
    )  # fmt: skip
    return model


def ur_arm(
    name: str, sensor_mount: SensorMount | None = None, tool_frame: str | None = None
) -> Arm:
    """An e-Series (or UR20/UR30) :class:`~ftkin.kinematics.arm.Arm`, sensor frame ``ft_sensor``.

    Args:
        name: A key of :data:`UR_DH` (``ur5e``, ...).
        sensor_mount: Where the sensor frame is on ``tool0`` (default: at the flange, its axes).
        tool_frame: A tool frame of the model, or None.

    Raises:
        InvalidInput: unknown name.
    """
    if name not in UR_DH:
        raise InvalidInput(f"unknown UR arm {name!r}; known: {', '.join(UR_DH)}")
    model = dh_model(UR_DH[name])
    mount = sensor_mount if sensor_mount is not None else SensorMount(FLANGE_FRAME)
    add_sensor_frame(model, "ft_sensor", mount)
    arm = Arm(model, "ft_sensor", tool_frame)
    arm.sensor_mount = mount
    return arm


def flange_rotation(q) -> np.ndarray:
    """``ᴮR_tool0`` ``(3, 3)`` of any UR arm at ``q`` ``(6,)`` [rad] (the DH lengths do not rotate:
    ``R = ∏ Rz(qᵢ) Rx(αᵢ)``; computed on one model, cached).

    Raises:
        InvalidInput: ``q`` is not 6 finite angles.
    """
    q = np.asarray(q, dtype=float)
    if q.shape != (6,) or not np.all(np.isfinite(q)):
        raise InvalidInput(f"expected 6 finite joint angles [rad], got {np.shape(q)}")
    model, data, frame = _rotation_model()
    pin.forwardKinematics(model, data, q)
    return pin.updateFramePlacement(model, data, frame).rotation.copy()


@functools.lru_cache(maxsize=1)
def _rotation_model() -> tuple[pin.Model, pin.Data, int]:
    model = dh_model(UR_DH["ur5e"])
    return model, model.createData(), model.getFrameId(FLANGE_FRAME)
