"""Catch an admittance loop that has gone unstable: repeated large reversals of the contact force.

An unstable loop on a stiff contact (K1 above
:func:`~ftkin.control.stability.max_stable_k1`) chatters: the contact force
jumps up and down every few ticks, growing until the velocity saturates or the
tool bounces off the surface. That never trips a force limit if the peaks stay
below it. :class:`OscillationDetector` watches the scalar contact signal
``s = |F'| + |M'| / lever`` [N] (sensor frame; both norms are computed on the
control path anyway) and its tick-to-tick step ``δ = s[n] − s[n−1]``:

* a *reversal* is a step against the previous one (``δ[n]·δ[n−1] < 0``)
  that ends a swing (the sum of the steps since the last reversal) larger
  than ``force_step`` [N] (sensor noise reverses the step every other tick,
  but its swings are small: the default 0.3 N is ten times the increments of
  the paper's 0.02 N noise);
* reversals are counted with exponential forgetting over ``window`` [s], and so is the
  step *energy* ``mean(δ²)``;
* the loop oscillates when at least ``reversals`` counted reversals and an
  energy of at least ``(force_step / 2)²`` coincide.

So an oscillation of at least ``reversals / (2·window)`` Hz (30 Hz with the
defaults) is caught within about a window once its swings exceed
``force_step``; a single impact, a push by hand, noise or the short ring-down
after a jolt (a handful of reversals) is not. Cost: a
dozen float operations per tick, no array.
"""

import math
from dataclasses import dataclass

from ..exceptions import InvalidInput


@dataclass(frozen=True)
class OscillationLimits:
    """Thresholds of the :class:`OscillationDetector`.

    Attributes:
        force_step: Smallest step of the contact signal that counts as a reversal [N].
        reversals: Counted reversals (within about ``window``) that mean an oscillation.
        window: Memory of the counts [s] (exponential forgetting).
        lever: Length [m] turning the torque norm into a force in the signal.
    """

    force_step: float = 0.3
    reversals: float = 12.0
    window: float = 0.2
    lever: float = 0.1

    def __post_init__(self):
        if (
            not all(
                isinstance(v, (int, float)) and math.isfinite(v) and v > 0
                for v in (self.force_step, self.reversals, self.window, self.lever)
            )
            or self.reversals < 2
        ):
            raise InvalidInput(
                "OscillationLimits needs force_step [N], window [s], lever [m] > 0 and reversals "
                f">= 2, got {self}"
            )


class OscillationDetector:
    """Per-tick detection with constant memory (see the module docstring)."""

    __slots__ = (
        "limits",
        "count",
        "energy",
        "_previous",
        "_step",
        "_swing",
        "_dt",
        "_decay",
        "_threshold",
        "_energy_floor",
        "_inverse_lever",
        "_window",
        "_reversals",
    )

    def __init__(self, limits: OscillationLimits | None = None):
        self.limits = OscillationLimits() if limits is None else limits
        if not isinstance(self.limits, OscillationLimits):
            raise InvalidInput(
                "oscillation limits must be an ftkin OscillationLimits or None, got "
                f"{type(limits).__name__}"
            )
        self._threshold, self._window, self._reversals = (
            float(self.limits.force_step),
            self.limits.window,
            self.limits.reversals,
        )
        self._energy_floor = 0.25 * self._threshold * self._threshold
        self._inverse_lever = 1.0 / float(self.limits.lever)
        self.reset()

    def reset(self) -> None:
        """Forget the signal, the counts and the energy."""
        self.count, self.energy = 0.0, 0.0
        self._previous, self._step, self._swing = math.nan, 0.0, 0.0
        self._dt, self._decay = math.nan, 0.0

    def update(self, force: float, torque: float, dt: float) -> bool:
        """Feed one tick's contact force and torque norms [N, N·m] and ``dt`` [s]; True while
        oscillating.
        """
        signal = force + torque * self._inverse_lever
        step = signal - self._previous
        self._previous = signal
        if step != step:  # first tick after a reset
            return False
        if dt != self._dt:
            self._dt, self._decay = dt, math.exp(-dt / self._window)
        decay = self._decay
        count = self.count * decay
        if step * self._step < 0.0:  # a reversal: count the swing it ends if that was large
            if abs(self._swing) > self._threshold:
                count += 1.0
            self._swing = step
        else:
            self._swing += step
        self.count, self._step = count, step
        self.energy = energy = self.energy * decay + (1.0 - decay) * step * step
        return count >= self._reversals and energy >= self._energy_floor


DEFAULT_OSCILLATION_LIMITS = OscillationLimits()
"""The thresholds :class:`~ftkin.control.JointAdmittance` uses unless told otherwise."""
