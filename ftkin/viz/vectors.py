"""The vectors drawn at one pose, in the base frame (pure numpy).

At a static pose without contact, the measured force minus the sensor bias
equals the tool weight the calibration predicts; the compensated contact force
is what is left. Drawn in the base frame B, anchored at the sensor origin:

* ``measured``: ``R_BS (F - F0)`` [N], the raw force with the bias removed;
* ``gravity``: ``R_BS Gs = a`` [N], the predicted tool weight;
* ``contact``: ``R_BS F'`` [N], ``F' = F - F0 - Gs`` (the compensated force, from the
  model's :meth:`~ftkin.calibration.model.SensorModel.predict`);
* ``center_of_mass``: ``p_S + R_BS P`` [m], the tool's centre of mass;
* ``base_gravity``: the unit direction of ``a`` (the estimated base tilt).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..calibration.model import SensorModel
from ..exceptions import InvalidInput
from ..validation import as_rotation_batch, as_vector


@dataclass(frozen=True)
class PoseVectors:
    """Everything drawn for one pose (base frame B).

    Attributes:
        rotation_sensor_to_base: ``R_BS`` ``(3, 3)``.
        sensor_origin: Sensor origin in the base frame [m].
        measured_force: ``R_BS (F - F0)`` [N].
        gravity_force: Predicted tool weight ``a`` [N].
        contact_force: ``R_BS F'`` [N], the compensated contact force.
        contact_wrench: ``F'`` and ``M'`` in the sensor frame [N, N·m].
        center_of_mass: Tool centre of mass in the base frame [m].
        gravity_direction: Unit vector along ``a`` (base frame).
    """

    rotation_sensor_to_base: np.ndarray
    sensor_origin: np.ndarray
    measured_force: np.ndarray
    gravity_force: np.ndarray
    contact_force: np.ndarray
    contact_wrench: np.ndarray
    center_of_mass: np.ndarray
    gravity_direction: np.ndarray


def pose_vectors(
    calibration: SensorModel, rotation_sensor_to_base, sensor_origin, raw_wrench
) -> PoseVectors:
    """Compute the drawn vectors of one pose.

    Args:
        calibration: The calibration to check (bias, tool weight, COM).
        rotation_sensor_to_base: ``R_BS`` ``(3, 3)`` at this pose.
        sensor_origin: Sensor origin in the base frame [m] (zero without an arm).
        raw_wrench: Raw reading ``[fx, fy, fz, mx, my, mz]`` [N, N·m] of the real sensor
            (its reading signs applied: :func:`~ftkin.calibration.conventions.as_real_sensor`).
    """
    rotations, _ = as_rotation_batch(rotation_sensor_to_base)
    if len(rotations) != 1:
        raise InvalidInput("pose_vectors takes one (3, 3) rotation, got a batch")
    rotation = rotations[0]
    origin = as_vector(sensor_origin, 3, "sensor origin")
    raw = as_vector(raw_wrench, 6, "raw wrench [fx, fy, fz, mx, my, mz]")
    contact = raw - calibration.predict(rotation)  # F' = F − F0 − Gs, M' = M − M0 − P × Gs
    gravity = np.array(calibration.gravity_in_base, dtype=float)
    weight = np.linalg.norm(gravity)
    direction = gravity / weight if weight > 0 else np.array([0.0, 0.0, -1.0])
    return PoseVectors(
        rotation_sensor_to_base=rotation,
        sensor_origin=origin,
        measured_force=rotation @ (raw[:3] - calibration.force_offset),
        gravity_force=gravity,
        contact_force=rotation @ contact[:3],
        contact_wrench=contact,
        center_of_mass=origin + rotation @ calibration.center_of_mass,
        gravity_direction=direction,
    )
