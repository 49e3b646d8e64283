"""A simulated wrist sensor: raw readings from known parameters, for tests and demos.

``raw = bias + drift(t) + tool gravity + contact + noise`` in the sensor frame, with the
orientation from joint angles through an :class:`~ftkin.kinematics.arm.Arm` or given as
``R_BS``. The optional drift (:class:`SensorDrift`) needs reading times.
Hardware stays behind this interface: every test and the demo run without a robot.
"""

from dataclasses import dataclass

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.model import STANDARD_GRAVITY, SensorModel
from ..calibration.samples import Samples
from ..exceptions import InvalidInput
from ..validation import as_batch, as_float_array, as_rotation_batch
from .sensor_drift import SensorDrift


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
        truth: The parameters the readings are generated from (the bias at power-on).
        noise: Per-reading standard deviation of each channel.
        drift: How the bias moves after power-on at ``t = 0`` (None: it does not).
    """

    truth: SensorModel
    noise: SensorNoise
    drift: SensorDrift | None = None

    def bias_drift(self, times, rng: np.random.Generator) -> np.ndarray:
        """One draw of the bias change ``(N, 6)`` [N, N·m] at ``times`` [s] (zeros without
        drift).
        """
        times = as_float_array(times, "times").reshape(-1)
        return np.zeros((len(times), 6)) if self.drift is None else self.drift.offsets(times, rng)

    def read(
        self,
        rotation_sensor_to_base,
        rng: np.random.Generator,
        contact_wrench=None,
        times=None,
        bias_drift=None,
    ) -> np.ndarray:
        """Raw readings ``(N, 6)`` [N, N·m] at orientations ``(N, 3, 3)``.

        Args:
            rotation_sensor_to_base: ``R_BS`` per reading.
            rng: Random generator (seed it for reproducible tests).
            contact_wrench: ``(6,)`` or ``(N, 6)`` wrench the environment exerts
                on the tool, in the sensor frame, added to the reading.
            times: ``(N,)`` reading times [s] since power-on; with a
                :attr:`drift`, the bias drift at those times is added (one
                draw of its random walk per call).
            bias_drift: ``(N, 6)`` bias change to add instead (e.g. from
                :meth:`bias_drift`, to know the truth).
        """
        raw = self.truth.predict(rotation_sensor_to_base).reshape(-1, 6)  # checks the rotations
        if contact_wrench is not None:
            raw = raw + as_batch(contact_wrench, 6, "contact_wrench")[0]
        if bias_drift is None and times is not None and self.drift is not None:
            bias_drift = self.bias_drift(times, rng)
        if bias_drift is not None:
            offsets, _ = as_batch(bias_drift, 6, "bias_drift")
            if len(offsets) != len(raw):
                raise InvalidInput(
                    f"{len(offsets)} bias_drift rows but {len(raw)} readings; expected one each"
                )
            raw = raw + offsets
        return raw + rng.standard_normal(raw.shape) * self.noise.channel_std

    def samples(
        self,
        rotation_sensor_to_base,
        rng: np.random.Generator,
        readings_per_pose: int = 1,
        times=None,
        bias_drift=None,
    ) -> Samples:
        """Static-pose samples: ``readings_per_pose`` noisy readings at each orientation.

        ``times``: ``(N · readings_per_pose,)`` reading times [s] (see :func:`recording_times`),
        carried by the samples and driving the drift; ``bias_drift`` as in :meth:`read`.
        """
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        repeated = np.repeat(rotations, readings_per_pose, axis=0)
        pose_ids = np.repeat(np.arange(len(rotations)), readings_per_pose)
        return Samples(
            self.read(repeated, rng, times=times, bias_drift=bias_drift),
            repeated,
            pose_ids,
            times=times,
        )

    def samples_at_configurations(
        self,
        arm,
        joint_positions,
        rng: np.random.Generator,
        readings_per_pose: int = 1,
        times=None,
        bias_drift=None,
    ) -> Samples:
        """Like :meth:`samples` with orientations from joint angles ``(N, nq)`` [rad]."""
        configurations, _ = as_batch(joint_positions, arm.nq, "joint positions q")
        rotations = arm.rotation_sensor_to_base(configurations)  # FK once per pose
        read = self.samples(rotations, rng, readings_per_pose, times, bias_drift)
        repeated = np.repeat(configurations, readings_per_pose, axis=0)
        return Samples.from_joint_positions(
            arm, repeated, read.wrenches, read.pose_ids, read.rotations, times
        )


def recording_times(
    pose_count: int,
    readings_per_pose: int,
    duration: float,
    reading_interval: float = 0.001,
    start: float = 0.0,
) -> np.ndarray:
    """Reading times ``(pose_count · readings_per_pose,)`` [s] of poses spread evenly over
    ``duration`` [s].

    Pose ``i`` starts at ``start + i · duration / pose_count`` and its
    readings follow every ``reading_interval`` [s].
    """
    if pose_count < 1 or readings_per_pose < 1 or not (duration > 0 and reading_interval > 0):
        raise InvalidInput(
            "recording_times needs positive counts, duration [s] and reading_interval [s]"
        )
    pose_starts = start + np.arange(pose_count) * (duration / pose_count)
    return (pose_starts[:, None] + np.arange(readings_per_pose) * reading_interval).reshape(-1)
