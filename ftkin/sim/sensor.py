"""A simulated wrist sensor: raw readings from known parameters, for tests and demos.

``raw = bias + tool gravity + contact + noise`` in the sensor frame, with the
orientation from joint angles through an :class:`~ftkin.kinematics.arm.Arm` or given as
``R_BS``. Hardware stays behind this interface: every test and the demo run
without a robot.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.model import STANDARD_GRAVITY, SensorModel
from ..calibration.samples import Samples
from ..validation import as_batch, as_rotation_batch


def paper_like_truth(g: float = STANDARD_GRAVITY) -> SensorModel:
    """Parameters close to the paper's setup (METHOD.md §6), as a simulation truth.

    Bias ``F0 = [-0.86, 1.10, 0.20]`` N, ``M0 = [-0.0002, -0.0605, 0.0254]`` N·m,
    a 0.3215 kg tool with its COM 47 mm along the sensor z axis, and a base
    tilted by U = -0.204°, V = -0.129°.
    """
    return SensorModel.from_tool(
        tool_mass=3.153 / 9.8,
        center_of_mass=[0.0001, -0.0003, 0.047],
        force_offset=[-0.8613, 1.1015, 0.1976],
        torque_offset=[-0.0002, -0.0605, 0.0254],
        base_tilt=np.deg2rad([-0.204, -0.129]),
        g=g,
    )


@dataclass(frozen=True)
class SimulatedSensor:
    """A six-axis sensor with known bias, tool and Gaussian noise.

    Attributes:
        truth: The parameters the readings are generated from.
        noise: Per-reading standard deviation of each channel.
    """

    truth: SensorModel
    noise: SensorNoise

    def read(self, rotation_sensor_to_base, rng: np.random.Generator, contact_wrench=None) -> np.ndarray:
        """Raw readings ``(N, 6)`` [N, N·m] at orientations ``(N, 3, 3)``.

        Args:
            rotation_sensor_to_base: ``R_BS`` per reading.
            rng: Random generator (seed it for reproducible tests).
            contact_wrench: ``(6,)`` or ``(N, 6)`` wrench the environment exerts
                on the tool, in the sensor frame, added to the reading.
        """
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        raw = self.truth.predict(rotations).reshape(-1, 6)
        if contact_wrench is not None:
            contact, _ = as_batch(contact_wrench, 6, "contact_wrench")
            raw = raw + contact
        return raw + rng.standard_normal(raw.shape) * self.noise.channel_std

    def samples(self, rotation_sensor_to_base, rng: np.random.Generator, readings_per_pose: int = 1) -> Samples:
        """Static-pose samples: ``readings_per_pose`` noisy readings at each orientation."""
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        repeated = np.repeat(rotations, readings_per_pose, axis=0)
        pose_ids = np.repeat(np.arange(len(rotations)), readings_per_pose)
        return Samples(self.read(repeated, rng), repeated, pose_ids)

    def samples_at_configurations(self, arm, joint_positions, rng: np.random.Generator, readings_per_pose: int = 1) -> Samples:
        """Like :meth:`samples` with orientations from joint angles ``(N, nq)`` [rad]."""
        configurations, _ = as_batch(joint_positions, arm.nq, "joint positions q")
        rotations = np.repeat(arm.rotation_sensor_to_base(configurations), readings_per_pose, axis=0)  # FK once per pose
        pose_ids = np.repeat(np.arange(len(configurations)), readings_per_pose)
        repeated = np.repeat(configurations, readings_per_pose, axis=0)
        return Samples.from_joint_positions(arm, repeated, self.read(rotations, rng), pose_ids, rotations)
