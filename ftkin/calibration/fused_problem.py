"""The whitened least squares of the fused calibration (an orientation and the IMU), and what it
can determine.

Frames: B the base, U the sensor frame the orientations give (the URDF's, or the frame whose
``R_BS`` was given), S the real sensor, I the IMU. ``R_i`` (P, 3, 3) maps U to B at pose ``i``,
the mount ``R_M`` maps U to S (``R_BS = R_i R_Mᵀ``, :mod:`ftkin.calibration.mount`), ``R_SI`` maps
I to S (:mod:`ftkin.calibration.imu_model`). Per pose (readings averaged), with ``a`` the tool's
weight vector in the base frame [N] (it points down: gravity and the base tilt)::

    Gs_i = R_M R_iᵀ a                                   the weight in the real sensor frame
    F_i  = F0 + Gs_i,   M_i = M0 + P × Gs_i             (:func:`~ftkin.calibration.model.predict`)
    f_i  = −(g / |a|) Gs_i                              the specific force at rest (+g upward), S
    acc_i = (1 + s) ∘ (R_SIᵀ f_i) + b                   the accelerometer, IMU frame

over ``x = [θ, δ_M, δ_I, b, s_free]`` with ``θ = [a, F0, M0, P]`` (the FK fit's order),
``R_M = R_M0 Exp(E δ_M)`` (``E`` of the mount mode) and ``R_SI = R_I0 Exp(δ_I)`` (when estimated).
The accelerometer's magnitude is ``g`` by construction: the sphere ``|a − b| = g`` of the IMU fit
holds with the direction given by the orientation and the tilt instead of free per pose.

What each channel sees: the accelerometer sees the IMU's orientation relative to U,
``R_SIᵀ R_M``, and the gravity direction ``a / |a|`` (the base tilt); the wrench sees the real
sensor's, ``R_M``, and the weight ``a``. So ``R_M`` and ``R_SI`` are told apart by the wrench
alone when ``R_SI`` is estimated, and by the accelerometer too when ``R_SI`` is given.
:func:`check_observable` refuses a pose set that leaves a direction open, naming it.
"""

from dataclasses import dataclass, replace

import numpy as np

from .imu_model import ACCEL_BIAS_NAMES, ACCEL_SCALE_NAMES, IMU_ROTATION_NAMES
from .imu_problem import weakest_direction
from .imu_problem_base import NineChannelProblem
from .model import COMPONENT_NAMES, gravity_in_sensor, predict, skew
from .mount import MOUNT_AXES, MOUNT_NAMES, exp_so3, mount_jacobian, right_jacobian_so3
from .observability import MIN_RELATIVE_SINGULAR_VALUE

POSES_NEEDED = (
    "use static poses that turn gravity into every sensor direction: the tool tilted 30° or more "
    "about at least two different horizontal axes, and the wrist turned so gravity is seen along "
    "the sensor's x, y and z axes (a mount about an axis that keeps the same horizontal part at "
    "every pose trades against the base tilt)"
)


@dataclass(frozen=True)
class FusedStaticProblem(NineChannelProblem):
    """The whitened least squares of the fused static calibration (inspectable on its own; its
    whitening and residuals are :class:`~ftkin.calibration.imu_problem_base.NineChannelProblem`'s).

    Attributes:
        rotations: ``(P, 3, 3)`` orientations ``R_i`` of the sensor frame U (URDF) in the base.
        accel: ``(P, 3)`` mean accelerometer reading per pose [m/s², IMU frame].
        wrenches: ``(P, 6)`` mean raw wrench per pose [N, N·m].
        counts: ``(P,)`` readings per pose.
        noise: ``(9,)`` per-reading noise ``[accel (3) m/s², force (3) N, torque (3) N·m]``.
        g: Magnitude of gravity [m/s²].
        mount0: ``R_M0`` ``(3, 3)`` (``R_M = R_M0 Exp(E δ_M)``).
        imu_rotation0: ``R_I0`` ``(3, 3)`` (``R_SI = R_I0 Exp(δ_I)``; fixed when not free).
        mount_mode: ``"none"``, ``"yaw"`` or ``"full"``
            (:data:`~ftkin.calibration.mount.MOUNT_NAMES`).
        imu_rotation_free: Whether ``δ_I`` is estimated.
        scale_free: Which accelerometer scale components are estimated.
        accel_count_factor: Independent accelerometer readings per reading
            (:attr:`~ftkin.calibration.imu_samples.ImuSamples.accel_count_factor`).
    """

    rotations: np.ndarray
    accel: np.ndarray
    wrenches: np.ndarray
    counts: np.ndarray
    noise: np.ndarray
    g: float
    mount0: np.ndarray
    imu_rotation0: np.ndarray
    mount_mode: str = "none"
    imu_rotation_free: bool = True
    scale_free: tuple[int, ...] = ()
    accel_count_factor: float = 1.0

    @property
    def names(self) -> tuple[str, ...]:
        """The parameters' names, in the order of ``x``."""
        return (
            COMPONENT_NAMES
            + MOUNT_NAMES[self.mount_mode]
            + (IMU_ROTATION_NAMES if self.imu_rotation_free else ())
            + ACCEL_BIAS_NAMES
            + tuple(ACCEL_SCALE_NAMES[k] for k in self.scale_free)
        )

    @property
    def global_count(self) -> int:
        """All parameters are global (no per-pose nuisance: the orientation gives the direction)."""
        return len(self.names)

    @property
    def mount_count(self) -> int:
        return len(MOUNT_NAMES[self.mount_mode])

    def unpack(self, x: np.ndarray) -> dict:
        """The parameters of ``x`` by name: ``theta, mount_delta, imu_delta, b, s``."""
        i = 12 + self.mount_count
        imu_delta = np.zeros(3)
        if self.imu_rotation_free:
            imu_delta, i = x[i : i + 3], i + 3
        bias, i = x[i : i + 3], i + 3
        scale = np.zeros(3)
        scale[list(self.scale_free)] = x[i : i + len(self.scale_free)]
        return {
            "theta": x[:12],
            "mount_delta": x[12 : 12 + self.mount_count],
            "imu_delta": imu_delta,
            "b": bias,
            "s": scale,
        }

    def mount(self, x: np.ndarray) -> np.ndarray:
        """``R_M`` at ``x`` (U → real sensor frame)."""
        return self.mount0 @ exp_so3(MOUNT_AXES[self.mount_mode] @ self.unpack(x)["mount_delta"])

    def imu_rotation(self, x: np.ndarray) -> np.ndarray:
        """``R_SI`` at ``x`` (IMU → real sensor frame)."""
        return self.imu_rotation0 @ exp_so3(self.unpack(x)["imu_delta"])

    def specific_force_in_imu(self, x: np.ndarray) -> np.ndarray:
        """``(P, 3)`` ``R_SIᵀ f_i``: the model's specific force at rest, IMU frame [m/s²]."""
        theta = self.unpack(x)["theta"]
        weight = gravity_in_sensor(self.rotations, theta[0:3]) @ self.mount(x).T  # Gs = R_M Rᵀ a
        return -(self.g / np.linalg.norm(theta[0:3])) * weight @ self.imu_rotation(x)

    def predict(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9)`` predicted ``[acc, F, M]`` per pose."""
        p = self.unpack(x)
        wrench = predict(self.rotations @ self.mount(x).T, p["theta"])
        accel = (1.0 + p["s"]) * self.specific_force_in_imu(x) + p["b"]
        return np.concatenate([accel, wrench], axis=1)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``(P, 9, n)`` derivative of :meth:`predict` with respect to ``x`` (tested against
        finite differences)."""
        p = self.unpack(x)
        theta, k = p["theta"], self.mount_count
        gravity = theta[0:3]
        norm = float(np.linalg.norm(gravity))
        mount, imu_rotation = self.mount(x), self.imu_rotation(x)
        jac = np.zeros((len(self.rotations), 9, self.parameter_count))
        jac[:, 3:9, : 12 + k] = mount_jacobian(
            self.rotations, gravity, theta[9:12], self.mount_mode, mount, p["mount_delta"]
        )
        # f = −(g/|a|) R_M Rᵀ a: ∂f/∂a = −(g/|a|) R_M Rᵀ (I − â âᵀ), ∂f/∂δ_M = −(g/|a|) ∂Gs/∂δ_M
        unit = gravity / norm
        d_force = np.zeros((len(self.rotations), 3, 3 + k))
        d_force[:, :, 0:3] = jac[:, 3:6, 0:3] @ (np.eye(3) - np.outer(unit, unit))
        d_force[:, :, 3:] = jac[:, 3:6, 12 : 12 + k]
        d_force *= -self.g / norm
        gain = (1.0 + p["s"])[:, None]  # ∂acc = diag(1 + s) R_SIᵀ ∂f
        d_accel = gain * (imu_rotation.T @ d_force)
        jac[:, 0:3, 0:3] = d_accel[:, :, 0:3]
        jac[:, 0:3, 12 : 12 + k] = d_accel[:, :, 3:]
        i = 12 + k
        in_imu = self.specific_force_in_imu(x)
        if self.imu_rotation_free:  # R_SIᵀ f = Exp(−δ) v: ∂/∂δ = Exp(−δ) [v]× J_r(−δ)
            delta = p["imu_delta"]
            v = -(self.g / norm) * gravity_in_sensor(self.rotations, gravity) @ mount.T
            v = v @ self.imu_rotation0
            turn = exp_so3(-delta)
            jac[:, 0:3, i : i + 3] = gain * (turn @ skew(v) @ right_jacobian_so3(-delta))
            i += 3
        jac[:, 0:3, i : i + 3] = np.eye(3)  # ∂acc/∂b
        i += 3
        for axis in self.scale_free:
            jac[:, axis, i] = in_imu[:, axis]
            i += 1
        return jac

    def recentred(self, x: np.ndarray) -> "tuple[FusedStaticProblem, np.ndarray]":
        """The same problem with ``R_M0``, ``R_I0`` moved to ``x`` (``δ_M = δ_I = 0``)."""
        problem = replace(self, mount0=self.mount(x), imu_rotation0=self.imu_rotation(x))
        out = np.array(x, dtype=float)
        out[12 : 12 + self.mount_count] = 0.0
        if self.imu_rotation_free:
            out[12 + self.mount_count : 15 + self.mount_count] = 0.0
        return problem, out


def check_observable(problem: FusedStaticProblem, x: np.ndarray) -> None:
    """Refuse a pose set that leaves a parameter open (see the module docstring).

    Raises:
        UnobservableParameters: naming the parameters of the weakest direction (a mount angle
            with the tilt and offsets it trades against, the IMU's rotation with the mount, ...).
    """
    directions = weakest_direction(problem, x)
    relative, involved = directions.relative, directions.names
    if relative >= MIN_RELATIVE_SINGULAR_VALUE:
        return
    both = any(n.startswith("mount") for n in involved) and any(
        n.startswith("imu_rotation") for n in involved
    )
    raise directions.error(
        f"{POSES_NEEDED}"
        + (
            "; the mount trades against the IMU's rotation: with R_SI estimated only the wrench "
            "tells them apart (in Python, calibrate(..., imu_rotation=R_SI) holds a known "
            "rotation of the IMU in the sensor; the command line takes none: add poses)"
            if both
            else ""
        )
        + f" (smallest relative singular value {relative:.1e}, need at least "
        f"{MIN_RELATIVE_SINGULAR_VALUE:.0e})",
    )
