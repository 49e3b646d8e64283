"""Bias drift of a simulated strain-gauge sensor, at realistic levels.

Three parts, added to the bias at power-on (``t = 0``) [N, N·m, sensor frame]:

* **warm-up**: ``A (1 − exp(−t/τ))``, the electronics settling after
  power-on (typically tenths of a newton over minutes);
* **random walk**: ``q · W(t)`` with ``W`` a standard Wiener process
  (rate ``q`` [N/√s, N·m/√s]);
* **temperature**: ``c (T(t) − T(0))`` with a linear coefficient ``c``
  [N/K, N·m/K] and a temperature profile ``T(t)`` [K] given at times and
  interpolated linearly (held outside).
"""

from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidInput
from ..validation import as_float_array, as_six_channels


@dataclass(frozen=True)
class SensorDrift:
    """How a simulated sensor's bias moves after power-on.

    Attributes:
        warmup: ``(6,)`` (or ``[force, torque]``) warm-up amplitude ``A`` [N, N·m].
        warmup_time_constant: ``τ`` [s].
        random_walk: ``(6,)`` (or ``[force, torque]``) rate ``q`` [N/√s, N·m/√s], ≥ 0.
        temperature_coefficient: ``(6,)`` (or ``[force, torque]``) ``c`` [N/K, N·m/K].
        temperature_times: ``(K,)`` ascending times of the temperature profile [s] (None: constant).
        temperatures: ``(K,)`` temperatures at those times [K or °C; only differences count].
    """

    warmup: np.ndarray = 0.0
    warmup_time_constant: float = 300.0
    random_walk: np.ndarray = 0.0
    temperature_coefficient: np.ndarray = 0.0
    temperature_times: np.ndarray | None = None
    temperatures: np.ndarray | None = None

    def __post_init__(self):
        for name in ("warmup", "random_walk", "temperature_coefficient"):
            object.__setattr__(self, name, as_six_channels(getattr(self, name), name))
        if np.any(self.random_walk < 0):
            raise InvalidInput(f"random_walk rates must be ≥ 0, got {self.random_walk}")
        if not (np.isfinite(self.warmup_time_constant) and self.warmup_time_constant > 0):
            raise InvalidInput(
                f"warmup_time_constant must be finite and > 0 [s], got {self.warmup_time_constant}"
            )
        if (self.temperature_times is None) != (self.temperatures is None):
            raise InvalidInput("give both temperature_times [s] and temperatures, or neither")
        if self.temperature_times is not None:
            for name in ("temperature_times", "temperatures"):
                object.__setattr__(
                    self, name, as_float_array(getattr(self, name), name).reshape(-1)
                )
            times, temperatures = self.temperature_times, self.temperatures
            if len(times) != len(temperatures) or len(times) == 0 or np.any(np.diff(times) < 0):
                raise InvalidInput("temperature_times must be ascending, one per temperature")

    @classmethod
    def typical(cls) -> "SensorDrift":
        """The benchmark's drift: warm-up ±0.5 N / ±0.01 N·m per channel with τ = 5 min, random walk
        0.002 N/√s, 4e-5 N·m/√s.
        """
        return cls(
            warmup=[0.5, -0.5, 0.5, 0.01, -0.01, 0.01],
            warmup_time_constant=300.0,
            random_walk=[0.002, 0.00004],
        )

    def deterministic(self, times) -> np.ndarray:
        """Warm-up plus temperature part ``(N, 6)`` at ``times`` [s] (no randomness)."""
        times = as_float_array(times, "times").reshape(-1)
        out = (
            self.warmup[None, :]
            * (1.0 - np.exp(-np.clip(times, 0.0, None) / self.warmup_time_constant))[:, None]
        )
        if self.temperature_times is not None:
            temperature = np.interp(times, self.temperature_times, self.temperatures)
            reference = np.interp(0.0, self.temperature_times, self.temperatures)
            out = out + self.temperature_coefficient[None, :] * (temperature - reference)[:, None]
        return out

    def offsets(self, times, rng: np.random.Generator) -> np.ndarray:
        """One draw of the bias change ``(N, 6)`` [N, N·m] at ``times`` ``(N,)`` [s ≥ 0, any
        order].
        """
        times = as_float_array(times, "times").reshape(-1)
        if np.any(times < 0) or not np.all(np.isfinite(times)):
            raise InvalidInput("drift times must be finite and ≥ 0 [s] (since power-on)")
        order = np.argsort(times, kind="stable")
        steps = np.diff(np.concatenate([[0.0], times[order]]))
        walk = np.empty((len(times), 6))
        walk[order] = (  # the walk in time order, put back in the given order
            np.cumsum(rng.standard_normal((len(times), 6)) * np.sqrt(steps)[:, None], axis=0)
            * self.random_walk
        )
        return self.deterministic(times) + walk
