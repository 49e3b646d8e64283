"""The closed-form start of the static IMU calibration.

A sphere fit of the accelerometer's means gives the bias ``b`` (and an isotropic scale), the
Kabsch rotation of the centred forces against the corrected directions gives ``R_SI`` and the
mass (a rotation like (95°, 89°, −175°) needs no initial guess), and linear least squares of
the torques gives ``M0`` and the centre of mass; :mod:`ftkin.calibration.imu_fit` refines them
jointly. A mirrored map (a negated accelerometer or wrench) is refused here.
"""

import numpy as np

from ..exceptions import SuspectConvention
from .imu_model import corrected_specific_force
from .imu_options import ImuCalibrationOptions
from .imu_samples import ImuPoseAverages
from .model import skew


def sphere_fit(accel: np.ndarray, g: float, with_scale: bool) -> tuple[np.ndarray, np.ndarray]:
    """Start for the accelerometer's bias ``b`` [m/s²] and scale ``s`` [-] from static means
    ``(P, 3)``: linear least squares of the sphere ``|a − b|² = ρ²`` (``2 a·b + k = |a|²``).

    ``s`` is the isotropic ``ρ / g − 1`` with ``with_scale`` (the joint fit then tells the axes
    apart), else zero. Too few or coplanar directions (rank below four) give zero.
    """
    if len(accel) >= 4:
        design = np.concatenate([2.0 * accel, np.ones((len(accel), 1))], axis=1)
        solution, _, rank, _ = np.linalg.lstsq(design, np.sum(accel**2, axis=1), rcond=None)
        radius_squared = solution[3] + solution[:3] @ solution[:3]
        if rank == 4 and radius_squared > 0.0:
            isotropic = np.sqrt(radius_squared) / g - 1.0 if with_scale else 0.0
            return solution[:3], np.full(3, isotropic)
    return np.zeros(3), np.zeros(3)


def kabsch_start(units: np.ndarray, forces: np.ndarray, g: float):
    """``R_SI``, ``m`` [kg], ``F0`` [N] from unit directions ``(P, 3)`` and forces ``(P, 3)``.

    ``F_i = F0 − m g R u_i``: the rotation best mapping the centred ``g u_i`` onto the centred
    ``−F_i`` (Kabsch, det = +1).

    Raises:
        SuspectConvention: the data fit a mirrored map far better (a negated accelerometer or
            wrench, or a left-handed axis).
    """
    centred_units = g * (units - units.mean(axis=0))
    centred_forces = -(forces - forces.mean(axis=0))
    cross = centred_forces.T @ centred_units  # m R Σ x xᵀ
    left, singular, right_t = np.linalg.svd(cross)
    mirrored = np.linalg.det(left @ right_t) < 0.0
    if mirrored and singular[2] > 0.1 * singular[0]:
        raise SuspectConvention(
            "the forces follow the accelerometer through a mirror, not a rotation: the "
            "accelerometer reports the acceleration (−g upward at rest) instead of the specific "
            "force, the wrench is the reaction instead of the load on the sensor, or one axis of "
            "either is reversed; negate the accelerometer (or the wrench) and calibrate again",
            explanations=[
                "an accelerometer at rest must read +g upward (specific force)",
                "a raw reading is the load on the sensor (a tool hanging below pulls it down)",
            ],
            fixes=["negate specific_force (ax, ay, az)", "negate the wrench (fx..mz)"],
        )
    rotation = left @ np.diag([1.0, 1.0, -1.0 if mirrored else 1.0]) @ right_t
    spread = float(np.sum(centred_units**2))
    mass = float(np.sum(centred_forces * (centred_units @ rotation.T))) / max(spread, 1e-300)
    force_offset = forces.mean(axis=0) + mass * g * rotation @ units.mean(axis=0)
    return rotation, mass, force_offset


def given_rotation_start(units: np.ndarray, forces: np.ndarray, g: float, rotation: np.ndarray):
    """``m`` [kg] and ``F0`` [N] at a given ``R_SI``: least squares of ``F = F0 − m g R u``."""
    directions = g * units @ rotation.T
    design = np.concatenate(
        [np.broadcast_to(np.eye(3), (len(units), 3, 3)), -directions[:, :, None]], axis=2
    ).reshape(-1, 4)
    solution = np.linalg.lstsq(design, forces.reshape(-1), rcond=None)[0]
    return float(solution[3]), solution[:3]


def torque_start(force_in_sensor: np.ndarray, torques: np.ndarray, mass: float):
    """``M0`` [N·m] and ``c`` [m] from ``M = M0 + f_S × (m c)`` (linear least squares)."""
    design = np.concatenate(
        [np.broadcast_to(np.eye(3), (len(torques), 3, 3)), skew(force_in_sensor)], axis=2
    ).reshape(-1, 6)
    solution = np.linalg.lstsq(design, torques.reshape(-1), rcond=None)[0]
    return solution[:3], solution[3:] / mass


def start(poses: ImuPoseAverages, g: float, options: ImuCalibrationOptions, scale_free):
    """The closed-form start: ``(x0 without directions, R0, directions0)``."""
    bias, scale = sphere_fit(poses.specific_force, g, bool(scale_free))
    scale = np.where(np.isin(np.arange(3), scale_free), scale, 0.0)
    corrected = corrected_specific_force(poses.specific_force, bias, scale)
    units = corrected / np.linalg.norm(corrected, axis=1)[:, None]
    forces = poses.wrenches[:, :3]
    if options.imu_rotation is None:
        rotation, mass, force_offset = kabsch_start(units, forces, g)
    else:
        rotation = options.imu_rotation
        mass, force_offset = given_rotation_start(units, forces, g, rotation)
    if not mass > 0.0:
        raise SuspectConvention(
            f"the estimated tool mass is {mass:.4g} kg (not positive): with the given imu_rotation "
            "the forces point up where the accelerometer says down; is R_SI transposed (sensor → "
            "IMU), the accelerometer negated, or the wrench the reaction?",
            fixes=["pass R_SI (IMU → sensor)", "negate the accelerometer", "negate the wrench"],
        )
    torque_offset, com = torque_start(g * units @ rotation.T, poses.wrenches[:, 3:], mass)
    x0 = np.concatenate(
        [force_offset, torque_offset, [mass], com]
        + ([np.zeros(3)] if options.imu_rotation is None else [])
        + [bias, scale[list(scale_free)]]
    )
    return x0, rotation, units
