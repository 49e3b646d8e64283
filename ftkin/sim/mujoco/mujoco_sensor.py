"""A real sensor's imperfections on MuJoCo's ideal wrench.

MuJoCo gives the exact load on the sensor (:meth:`ArmSimulation.ideal_wrench_in_sensor`,
already in ftkin's sign: ``-`` MuJoCo's force/torque sensors). :class:`MujocoSensor`
makes it a raw reading the way :class:`~ftkin.sim.sensor.SimulatedSensor` does:

``raw = clip(ideal + bias + noise, ±range)``, sampled at ``sample_rate`` [Hz]
(zero-order hold between samples) and delivered ``delay_ticks`` control ticks
late (default one: the controller acts on the previous tick's sample, as a
driver that reads the sensor while the robot executes the last command).

The tool's weight is *not* added: MuJoCo's physics already puts it in the
ideal wrench (with the inertial forces of the motion).
"""

import math
from collections import deque

import numpy as np

from ...calibration.information import SensorNoise
from ...exceptions import InvalidInput
from ...validation import as_vector
from ..sensor import SimulatedSensor


class MujocoSensor:
    """Bias, noise, saturation, sample rate and delay applied to ideal wrenches.

    Args:
        bias: ``[F0, M0]`` (6,) [N, N·m], sensor frame.
        noise: Per-sample noise (None: noiseless).
        force_range: Saturation per force channel [N].
        torque_range: Saturation per torque channel [N·m].
        sample_rate: Samples per second [Hz]; None: one fresh sample every control tick.
        delay_ticks: Control ticks between sampling and delivery (>= 0).
        seed: Seed of the noise generator.
    """

    def __init__(
        self,
        bias=(0.0,) * 6,
        noise: SensorNoise | None = None,
        *,
        force_range: float = 250.0,
        torque_range: float = 6.0,
        sample_rate: float | None = None,
        delay_ticks: int = 1,
        seed: int = 0,
    ):
        self.bias = as_vector(bias, 6, "bias")
        self.noise = noise
        if not (force_range > 0 and torque_range > 0):
            raise InvalidInput(
                f"force_range [N] and torque_range [N·m] must be > 0, got {force_range!r}, "
                f"{torque_range!r}"
            )
        if sample_rate is not None and not (math.isfinite(sample_rate) and sample_rate > 0):
            raise InvalidInput(
                f"sample_rate must be a finite number of Hz > 0 or None, got {sample_rate!r}"
            )
        if not (isinstance(delay_ticks, int) and delay_ticks >= 0):
            raise InvalidInput(f"delay_ticks must be an integer >= 0, got {delay_ticks!r}")
        self.range = np.array([force_range] * 3 + [torque_range] * 3, dtype=float)
        self.sample_rate, self.delay_ticks, self.seed = sample_rate, delay_ticks, seed
        self._std = np.zeros(6) if noise is None else noise.channel_std
        self._negative_range = -self.range
        self.reset()

    @classmethod
    def from_simulated(cls, sensor: SimulatedSensor, **options) -> "MujocoSensor":
        """The bias and noise of a :class:`SimulatedSensor` (its tool gravity is left to the
        physics).
        """
        return cls(sensor.truth.bias, sensor.noise, **options)

    def reset(self) -> None:
        """Restart time, the noise stream and the delay line."""
        self._rng = np.random.default_rng(self.seed)
        self._noise, self._noise_row = np.empty((0, 6)), 0
        self._time, self._next_sample = 0.0, 0.0
        self._sample: np.ndarray | None = None
        self._line: deque = deque()

    def read(self, ideal_wrench, dt: float) -> np.ndarray:
        """The raw reading ``(6,)`` [N, N·m] the controller gets this tick.

        Args:
            ideal_wrench: Load on the sensor now ``(6,)`` [N, N·m], sensor frame, ftkin's sign.
            dt: Control period [s] (advances the sensor's clock).
        """
        if (
            self._sample is None
            or self.sample_rate is None
            or self._time >= self._next_sample - 1e-12
        ):
            if self._noise_row == len(self._noise):  # noise drawn in blocks of 1024 samples
                self._noise, self._noise_row = self._rng.standard_normal((1024, 6)) * self._std, 0
            sample = ideal_wrench + self.bias
            sample += self._noise[self._noise_row]
            self._noise_row += 1
            # saturation (ufuncs: np.clip's wrapper costs more)
            self._sample = np.maximum(
                np.minimum(sample, self.range, out=sample), self._negative_range, out=sample
            )
            if self.sample_rate is not None:
                self._next_sample += 1.0 / self.sample_rate
        self._time += dt
        self._line.append(self._sample)
        return self._line.popleft() if len(self._line) > self.delay_ticks else self._line[0]
