"""The body regressor of the tool in the sensor frame, and the motion it needs.

For a tool rigidly attached at the sensor frame S, moving with spatial velocity
``v = [v_lin, ω]`` and spatial acceleration ``a = [a_lin, ω̇]`` (both in S's own
axes, Pinocchio's ``LOCAL``), the wrench the sensor must exert to move it is
linear in the ten inertial parameters θ (:mod:`ftkin.calibration.log_cholesky`)::

    I a + v ×* (I v) = Y(v, a) θ            (Pinocchio's ``bodyRegressor``)

Gravity enters as an upward acceleration ``g_S = R_BSᵀ γ`` of the frame
(``γ`` = the base-frame acceleration of gravity reversed, [m/s²]). The load on
the sensor (ftkin's raw reading, without contact) is the bias minus that
wrench: ``raw = bias − Y(v, a + g_S) θ``.
"""

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput
from ..kinematics.record import KinematicsRecord
from ..validation import as_batch, as_rotation_batch, as_wrenches
from .model import cross_rows, skew
from .samples import Samples


def _inertia_map(x: np.ndarray) -> np.ndarray:
    """``(N, 3, 6)`` L(x) with ``Ī x = L(x) [xx, xy, yy, xz, yz, zz]``."""
    out = np.zeros(x.shape[:-1] + (3, 6))
    out[..., 0, 0], out[..., 0, 1], out[..., 0, 3] = x[..., 0], x[..., 1], x[..., 2]
    out[..., 1, 1], out[..., 1, 2], out[..., 1, 4] = x[..., 0], x[..., 1], x[..., 2]
    out[..., 2, 3], out[..., 2, 4], out[..., 2, 5] = x[..., 0], x[..., 1], x[..., 2]
    return out


def body_regressor(velocity, acceleration) -> np.ndarray:
    """Vectorized ``pin.bodyRegressor``: ``(N, 6)`` velocities and accelerations → ``(N, 6, 10)``.

    Args:
        velocity: Spatial velocities ``[v_lin, ω]`` in the body frame [m/s, rad/s].
        acceleration: Spatial accelerations ``[a_lin, ω̇]`` in the body frame
            (add the upward gravity acceleration to ``a_lin`` to include weight) [m/s², rad/s²].

    Returns:
        ``Y`` with ``Y θ = [force; torque about the frame origin]`` [N, N·m].
    """
    velocity, _ = as_batch(velocity, 6, "velocity")
    acceleration, _ = as_batch(acceleration, 6, "acceleration")
    omega, omega_dot = velocity[:, 3:], acceleration[:, 3:]
    alpha = acceleration[:, :3] + cross_rows(omega, velocity[:, :3])  # a_lin + ω × v_lin
    omega_skew = skew(omega)
    out = np.zeros((len(velocity), 6, 10))
    out[:, :3, 0] = alpha
    out[:, :3, 1:4] = skew(omega_dot) + omega_skew @ omega_skew
    out[:, 3:, 1:4] = -skew(alpha)
    out[:, 3:, 4:10] = _inertia_map(omega_dot) + omega_skew @ _inertia_map(omega)
    return out


def gravity_regressor(upward_gravity_in_sensor) -> np.ndarray:
    """``(N, 6, 10)`` regressor of the weight alone: :func:`body_regressor` at rest with ``a_lin =
    g_S``.
    """
    gravity, _ = as_batch(upward_gravity_in_sensor, 3, "upward gravity in sensor")
    out = np.zeros((len(gravity), 6, 10))
    out[:, :3, 0] = gravity
    out[:, 3:, 1:4] = -skew(gravity)
    return out


@dataclass(frozen=True)
class MotionSamples:
    """Raw readings along a motion, with the sensor frame's orientation, velocity and acceleration.

    Attributes:
        wrenches: ``(N, 6)`` raw readings, sensor frame [N, N·m].
        rotations: ``(N, 3, 3)`` ``R_BS`` (sensor → base).
        velocities: ``(N, 6)`` sensor-frame spatial velocity ``[v, ω]`` in sensor axes [m/s, rad/s].
        accelerations: ``(N, 6)`` spatial acceleration ``[a, ω̇]`` in sensor axes, gravity excluded
        [m/s², rad/s²].
        times: ``(N,)`` stamps [s], or None.
        urdf, sensor_frame: Provenance when built from joint angles.
        kinematics: The arm's record (:class:`~ftkin.kinematics.record.KinematicsRecord`) when
            built from joint angles, recorded by the calibration.
    """

    wrenches: np.ndarray
    rotations: np.ndarray
    velocities: np.ndarray
    accelerations: np.ndarray
    times: np.ndarray | None = None
    urdf: str | None = None
    sensor_frame: str | None = None
    kinematics: KinematicsRecord | None = None

    def __post_init__(self):
        arrays = {
            "wrenches": as_wrenches(self.wrenches, "wrenches")[0],
            "rotations": as_rotation_batch(self.rotations)[0],
            "velocities": as_batch(self.velocities, 6, "velocities")[0],
            "accelerations": as_batch(self.accelerations, 6, "accelerations")[0],
        }
        count, rotations, velocities, accelerations = map(len, arrays.values())
        if not (rotations == velocities == accelerations == count):
            raise InvalidInput(
                "motion samples need one rotation, velocity and acceleration per wrench: got "
                f"{count} wrenches, {rotations} rotations, {velocities} velocities, "
                f"{accelerations} accelerations"
            )
        for name, value in arrays.items():
            value = np.array(value)
            value.setflags(write=False)
            object.__setattr__(self, name, value)
        if self.times is not None:
            times, _ = as_batch(np.asarray(self.times, dtype=float)[:, None], 1, "times")
            if len(times) != count:
                raise InvalidInput(f"{len(times)} times for {count} wrenches; expected one each")
            object.__setattr__(self, "times", times[:, 0].copy())

    def __len__(self) -> int:
        return len(self.wrenches)

    @classmethod
    def from_static(cls, samples: Samples) -> "MotionSamples":
        """Static readings as a motion at rest (velocity and acceleration zero)."""
        zeros = np.zeros((len(samples), 6))
        return cls(
            samples.wrenches,
            samples.rotations,
            zeros,
            zeros,
            None,
            samples.urdf,
            samples.sensor_frame,
            samples.kinematics,
        )

    @classmethod
    def from_joint_trajectory(
        cls, arm, joint_positions, joint_velocities, joint_accelerations, wrenches, times=None
    ) -> "MotionSamples":
        """Forward kinematics (Pinocchio) of ``q, dq, ddq`` ``(N, nq)`` [rad, rad/s, rad/s²] at the
        arm's sensor frame.
        """
        q, _ = as_batch(joint_positions, arm.nq, "joint positions q")
        dq, _ = as_batch(joint_velocities, arm.nq, "joint velocities dq")
        ddq, _ = as_batch(joint_accelerations, arm.nq, "joint accelerations ddq")
        if not (len(q) == len(dq) == len(ddq)):
            raise InvalidInput(
                f"q, dq and ddq must have the same number of rows, got {len(q)}, {len(dq)}, "
                f"{len(ddq)}"
            )
        rotations, velocities, accelerations = sensor_motion(arm, q, dq, ddq)
        urdf = str(arm.urdf_path) if arm.urdf_path is not None else None
        record = KinematicsRecord.from_arm(arm)
        return cls(
            wrenches, rotations, velocities, accelerations, times, urdf, arm.sensor_frame, record
        )

    def regressor(self) -> np.ndarray:
        """``(N, 6, 10)`` inertial part ``Y(v, a)`` (gravity excluded)."""
        return body_regressor(self.velocities, self.accelerations)


def sensor_motion(arm, q: np.ndarray, dq: np.ndarray, ddq: np.ndarray):
    """``R_BS`` ``(N, 3, 3)``, LOCAL velocity and acceleration ``(N, 6)`` of the sensor frame for
    validated arrays.
    """
    model, data, frame, local = arm.model, arm.model.createData(), arm.sensor_frame_id, pin.LOCAL
    rotations, (velocities, accelerations) = np.empty((len(q), 3, 3)), np.empty((2, len(q), 6))
    for i in range(len(q)):
        pin.forwardKinematics(model, data, q[i], dq[i], ddq[i])
        rotations[i] = pin.updateFramePlacement(model, data, frame).rotation
        velocities[i] = pin.getFrameVelocity(model, data, frame, local).vector
        accelerations[i] = pin.getFrameAcceleration(model, data, frame, local).vector
    return rotations, velocities, accelerations
