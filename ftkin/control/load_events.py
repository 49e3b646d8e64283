"""Grasp, release, tool change and contact, told apart from the contact wrench at control rate.

:class:`LoadTracker` takes, per tick, ``R_BS`` and the contact wrench after the tool (raw − bias −
tool gravity, sensor frame [N, N·m]) and returns the contact wrench after the tool *and* the load
it holds, identified by :mod:`ftkin.control.load_estimator`. Its state is ``empty`` or
``holding``; the events are ``grasp``, ``release``, ``tool_change`` and ``contact``.

The readings are taken in blocks of :attr:`LoadThresholds.block_time` [s]. Each block's mean is
compared with what the current model predicts (nothing when empty, the load when holding) against
``k σ_block``, per channel: ``σ_block² = σ²/n + μ²``, ``σ`` one reading's noise (the
calibration's), ``n`` the readings in the block and ``μ`` the calibration's model error (its
residual RMS; zero when unknown), ``k`` = :attr:`LoadThresholds.k_sigma`. A block within the
bound while holding is added to the load's estimate (after a joint solve, so a COM component that
turning the wrist reveals is learnt, not taken for a contact). A block beyond it starts a *step*;
the step is *settled* once :attr:`LoadThresholds.settle_blocks` consecutive blocks agree with the
one before (within ``k √(2σ²/n + μ²)``). A settled step is:

* **grasp** (empty → holding): explained by a gravity load: the force along ``g_s`` (its part
  across gravity within ``k σ_block`` per channel), pulling down (a positive mass beyond ``k``
  times its standard error), the moment perpendicular to it (``|τ·ĝ| ≤ k σ``, as ``τ = c × f``
  requires), and the gripper closed or not given;
* **tool_change** (empty → empty, the step added to the tool): such a gravity step while the
  gripper is given as *open* (no grasp happened), or, without a gripper, a mass above
  :attr:`LoadThresholds.max_load_mass` [kg] (no bound by default: never without a gripper);
* **release** (holding → empty): the contact after the tool back to zero within ``k σ_block``
  (the force back to the tool's) while the gripper is open or not given; with the gripper
  closed it is a ``contact`` (the load resting on a surface);
* **contact**: anything else (a force not along gravity, a moment not perpendicular to it, an
  upward force, a wrench inconsistent with the held load as the wrist turns), and a step that has
  not settled after :attr:`LoadThresholds.contact_time` [s] (a push that keeps changing). A
  contact is never added to the load; it ends when the readings fit the model again.

A steady push straight down along gravity with a consistent moment cannot be told from a grasp
without the gripper's state: give it when there is one. A lighter tool (an upward step) is a
contact: recalibrate after changing tools. A bias drifting beyond the bound reads as a step too
(re-zero, or track it: :class:`~ftkin.control.bias_tracker.BiasTracker`).

The tick (:meth:`LoadTracker.tick`) is a few dozen float operations; at the end of a block a
3×3 solve in floats. It never raises and never returns NaN for finite input; the events are kept
in :attr:`LoadTracker.events`, the estimate and its standard errors are computed on demand
(:meth:`LoadTracker.estimate`), outside the tick.
"""

import math
from dataclasses import dataclass, field

import numpy as np

from ..calibration.information import NOISE_RANGE, SensorNoise, at_noise_floor
from ..calibration.model import SensorModel
from ..calibration.result import CalibrationResult
from ..exceptions import InvalidInput
from ..validation import as_float_array, as_rotation_batch, as_wrench, as_wrenches
from .load_estimator import (
    LoadEstimate,
    add_still_floats,
    channel_weights,
    empty_sums,
    estimate_from,
    merge_sums,
    solve_still_floats,
)

EMPTY, HOLDING = "empty", "holding"
GRASP, RELEASE, TOOL_CHANGE, CONTACT = "grasp", "release", "tool_change", "contact"
LABELS = (EMPTY, GRASP, HOLDING, RELEASE, CONTACT, TOOL_CHANGE)
"""Every label a tick can have: a state (``empty``, ``holding``, ``contact`` while one lasts) or
the event decided at that tick."""


@dataclass(frozen=True)
class LoadThresholds:
    """How :class:`LoadTracker` decides (see :mod:`ftkin.control.load_events`).

    Attributes:
        k_sigma: Bounds are ``k_sigma`` standard deviations of the block's mean.
        block_time: Length of a block [s].
        settle_blocks: Consecutive agreeing blocks that settle a step.
        contact_time: A step not settled after this long is a contact [s].
        max_load_mass: Without a gripper, a gravity step heavier than this is a tool change [kg]
            (None: no bound).
    """

    k_sigma: float = 5.0
    block_time: float = 0.005
    settle_blocks: int = 3
    contact_time: float = 0.05
    max_load_mass: float | None = None

    def __post_init__(self):
        for name in ("k_sigma", "block_time", "contact_time"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InvalidInput(f"LoadThresholds.{name} must be a number > 0, got {value!r}")
        if not (isinstance(self.settle_blocks, int) and self.settle_blocks >= 1):
            raise InvalidInput(
                f"LoadThresholds.settle_blocks must be an integer ≥ 1, got {self.settle_blocks!r}"
            )
        mass = self.max_load_mass
        if mass is not None and not (
            isinstance(mass, (int, float)) and math.isfinite(mass) and mass > 0
        ):
            raise InvalidInput(f"LoadThresholds.max_load_mass must be None or > 0 kg, got {mass!r}")


@dataclass(frozen=True)
class LoadEvent:
    """One decision of :class:`LoadTracker`, with its evidence.

    Attributes:
        kind: ``grasp``, ``release``, ``tool_change`` or ``contact``.
        time: When it was decided [s].
        onset: When the step began (the start of its first block off the model) [s].
        mass: The step's mass along gravity ``f·ĝ / |g|`` [kg] (negative: an upward force).
        force_step: ``(3,)`` the step's force in the sensor frame [N] (last block's mean).
        moment_step: ``(3,)`` its moment about the sensor origin [N·m].
        across_gravity: The force across gravity in block standard deviations (largest channel).
        moment_along_force: ``|τ·ĝ|`` in standard deviations (0 for a gravity load).
        gripper: The gripper's state given at the decision (True closed, False open, None).
        reason: What decided it, in words.
    """

    kind: str
    time: float
    onset: float
    mass: float
    force_step: np.ndarray
    moment_step: np.ndarray
    across_gravity: float
    moment_along_force: float
    gripper: bool | None
    reason: str

    def __post_init__(self):
        for name in ("force_step", "moment_step"):
            value = np.array(getattr(self, name), dtype=float)
            value.setflags(write=False)
            object.__setattr__(self, name, value)


@dataclass
class _Step:
    """A step in progress (blocks off the model)."""

    onset: float = 0.0
    steady: int = 0
    sums: list = field(default_factory=empty_sums)


class LoadTracker:
    """Identify the load in the hand and tell grasps, releases, tool changes and contacts apart.

    Args:
        noise: One reading's noise per channel [N, N·m] (the calibration's).
        gravity_in_base: Gravity's acceleration ``γ`` (3,) in the base frame [m/s²] (down).
        model_std: ``(6,)`` the model's error floor ``μ`` [N, N·m] (the calibration's residual
            RMS; default zeros).
        thresholds: :class:`LoadThresholds`.
        period: The tick's period [s] when :meth:`tick` is given no time (the
            :class:`~ftkin.control.compensation.Compensator` path).

    Attributes:
        gripper: The gripper's state (True closed, False open, None unknown); a tick's ``gripper``
            argument sets it, and a caller may set it between ticks.
        label: The last tick's label (one of :data:`LABELS`).
        events: The :class:`LoadEvent` decided so far.
        version: Increases whenever the load's estimate changes (to refresh a display).
        moving: Set by the caller when the arm moves enough for the load's own inertia to show
            (:class:`~ftkin.control.dynamic_compensation.DynamicCompensator` sets it each tick):
            a block with a moving tick is checked against the load but not added to its estimate,
            which only readings held still make.
    """

    def __init__(
        self,
        noise: SensorNoise,
        gravity_in_base=(0.0, 0.0, -9.80665),
        *,
        model_std=None,
        thresholds: LoadThresholds | None = None,
        period: float = 0.001,
    ):
        self.weights = channel_weights(noise)
        self.noise = noise
        gravity = as_float_array(gravity_in_base, "gravity_in_base [m/s²]")
        if gravity.shape != (3,) or not np.all(np.isfinite(gravity)) or not np.any(gravity):
            raise InvalidInput(f"gravity_in_base must be a finite nonzero (3,), got {gravity}")
        self.gravity_in_base = tuple(gravity.tolist())
        floor = np.zeros(6) if model_std is None else as_wrench(model_std, "model_std [N, N·m]")
        if np.any(floor < 0):
            raise InvalidInput(f"model_std must be ≥ 0, got {floor}")
        self.model_std = tuple(floor.tolist())
        self.thresholds = LoadThresholds() if thresholds is None else thresholds
        if not isinstance(self.thresholds, LoadThresholds):
            raise InvalidInput(
                f"thresholds must be an ftkin LoadThresholds, got {type(thresholds).__name__}"
            )
        if not (isinstance(period, (int, float)) and math.isfinite(period) and period > 0):
            raise InvalidInput(f"period must be a number of seconds > 0, got {period!r}")
        self.period = float(period)
        self._variances = tuple(1.0 / w for w in self.weights)
        self.reset()

    @classmethod
    def for_calibration(
        cls, calibration, noise: SensorNoise | None = None, readings=None, **options
    ):
        """A tracker with a calibration's gravity and noise.

        The noise is ``noise`` if given, else the calibration's (``diagnostics.noise`` of a
        maximum-likelihood fit, the ``channel_std`` of a dynamic one), else, when ``readings``
        ``(N, 6)`` of a recording (3 or more) are given, estimated from them
        (:func:`noise_from_readings`), else the calibration's per-pose residual RMS times
        ``√(readings per pose)`` (the per-pose readings were means: model error counts as
        noise). The model floor is the residual RMS unless the noise came from it.

        Raises:
            InvalidInput: not a calibration, or no noise given and none in the calibration (no
                diagnostics, no residuals above rounding): pass ``noise=SensorNoise(force_std,
                torque_std)``.
        """
        if not isinstance(calibration, SensorModel):
            raise InvalidInput(
                f"calibration must be an ftkin SensorModel, got {type(calibration).__name__}"
            )
        calibration = CalibrationResult.from_model(calibration)
        a = np.asarray(calibration.gravity_in_base, dtype=float)
        gravity = a / np.linalg.norm(a) * calibration.g
        residuals = np.asarray(calibration.residuals)
        rms = np.sqrt(np.mean(residuals**2, axis=0)) if len(residuals) else None
        floor = rms
        if noise is None:
            from ..calibration.dynamic import DynamicCalibrationResult  # on first use (its fit)

            dynamic = isinstance(calibration, DynamicCalibrationResult)
            if calibration.diagnostics is not None:
                noise = calibration.diagnostics.noise
            elif dynamic and calibration.channel_std is not None:
                noise = SensorNoise(calibration.channel_std[:3], calibration.channel_std[3:])
            elif readings is not None and len(readings) >= 3:
                noise = noise_from_readings(readings)
            elif rms is not None and not at_noise_floor(rms, calibration.pose_wrenches):
                per_pose = max(calibration.sample_count / max(len(residuals), 1), 1.0)
                noise, floor = SensorNoise(rms[:3] * per_pose**0.5, rms[3:] * per_pose**0.5), None
            else:
                raise InvalidInput(
                    "this calibration records no noise (no diagnostics, no residuals): give the "
                    "sensor's noise per reading, noise=SensorNoise(force_std [N], torque_std "
                    "[N·m]) (ftkin compensate: --noise-force N --noise-torque NM)"
                )
        return cls(noise, gravity, model_std=floor, **options)

    def reset(self) -> None:
        """Back to ``empty`` with no load, no tool offset, no events."""
        self.gripper: bool | None = None
        self.label = EMPTY
        self.events: list[LoadEvent] = []
        self.version = 0
        self.moving = False
        self._block_moving = False
        self._state = EMPTY
        self._in_contact = False
        self._time = -self.period
        self._load = (0.0, 0.0, 0.0, 0.0)  # [m, m c] of the load
        self._offset = (0.0, 0.0, 0.0, 0.0)  # [m, m c] added to the tool by tool changes
        self._load_sums = empty_sums()
        self._block = empty_sums()
        self._block_means = [0.0] * 9  # Σ y (6), Σ g_s (3)
        self._block_start: float | None = None
        self._previous: tuple | None = None  # the last block's means
        self._step: _Step | None = None

    @property
    def state(self) -> str:
        """``empty`` or ``holding``."""
        return self._state

    @property
    def load_parameters(self) -> np.ndarray:
        """``(4,)`` ``[m, m c]`` [kg, kg·m] of the load subtracted now (zeros when empty)."""
        return np.array(self._load)

    @property
    def tool_offset(self) -> np.ndarray:
        """``(4,)`` ``[m, m c]`` [kg, kg·m] that tool changes added to the calibrated tool."""
        return np.array(self._offset)

    # ---------------------------------------------------------------- the tick
    def tick(self, rotation_rows, contact, time=None, gripper=None) -> tuple[float, ...]:
        """One reading: ``R_BS.tolist()`` and the contact after the tool (six floats [N, N·m]) →
        the contact after the tool and the load (six floats).

        Args:
            time: This reading's time [s] (default: the last one plus :attr:`period`).
            gripper: The gripper's state now (True closed, False open), if known.

        A non-finite reading is passed through and not used.
        """
        (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = rotation_rows
        ax, ay, az = self.gravity_in_base
        gx = r00 * ax + r10 * ay + r20 * az  # g_s = R_BSᵀ γ
        gy = r01 * ax + r11 * ay + r21 * az
        gz = r02 * ax + r12 * ay + r22 * az
        c0, c1, c2, c3, c4, c5 = contact
        if not math.isfinite(c0 + c1 + c2 + c3 + c4 + c5 + gx + gy + gz):
            return tuple(contact)
        t = self._time + self.period if time is None else time
        if gripper is not None:
            self.gripper = gripper
        mo, ox, oy, oz = self._offset
        y0, y1, y2 = c0 - mo * gx, c1 - mo * gy, c2 - mo * gz
        y3 = c3 - (oy * gz - oz * gy)  # τ = (m c) × g_s
        y4 = c4 - (oz * gx - ox * gz)
        y5 = c5 - (ox * gy - oy * gx)
        ml, lx, ly, lz = self._load
        out = (
            y0 - ml * gx,
            y1 - ml * gy,
            y2 - ml * gz,
            y3 - (ly * gz - lz * gy),
            y4 - (lz * gx - lx * gz),
            y5 - (lx * gy - ly * gx),
        )
        if self._block_start is None:
            self._block_start = t
        if self.moving:
            self._block_moving = True
        add_still_floats(self._block, self.weights, (gx, gy, gz), (y0, y1, y2, y3, y4, y5))
        m = self._block_means
        m[0] += y0
        m[1] += y1
        m[2] += y2
        m[3] += y3
        m[4] += y4
        m[5] += y5
        m[6] += gx
        m[7] += gy
        m[8] += gz
        self.label = CONTACT if self._in_contact else self._state
        self._time = t
        if t - self._block_start >= self.thresholds.block_time - 1e-12:
            self._end_block(t)
        return out

    def compensate(self, rotation_sensor_to_base, contact_wrench, time=None, gripper=None):
        """:meth:`tick` with checked inputs: ``R_BS`` ``(3, 3)`` and ``(6,)`` [N, N·m] → ``(6,)``.

        Raises:
            InvalidInput: not a rotation, not six finite numbers, a time that is not a finite
                number of seconds, or a gripper state that is not True, False or None.
        """
        rotations, _ = as_rotation_batch(rotation_sensor_to_base)
        if len(rotations) != 1:
            raise InvalidInput("compensate takes one (3, 3) rotation R_BS")
        wrench = as_wrench(contact_wrench, "contact_wrench [N, N·m]")
        if time is not None and not (
            isinstance(time, (int, float, np.floating)) and math.isfinite(time)
        ):
            raise InvalidInput(f"time must be a finite number of seconds, got {time!r}")
        if gripper is not None and not isinstance(gripper, (bool, np.bool_)):
            raise InvalidInput(
                f"gripper must be True (closed), False (open) or None, got {gripper!r}"
            )
        gripper = None if gripper is None else bool(gripper)
        time = None if time is None else float(time)
        return np.array(self.tick(rotations[0].tolist(), wrench.tolist(), time, gripper))

    # ------------------------------------------------------------- the blocks
    def _end_block(self, t: float) -> None:
        block, m, start, moving = (
            self._block,
            self._block_means,
            self._block_start,
            self._block_moving,
        )
        self._block_moving = False
        n = block[0]
        means = tuple(value / n for value in m)
        self._block, self._block_means, self._block_start = empty_sums(), [0.0] * 9, None
        k = self.thresholds.k_sigma
        floor = self.model_std
        bounds = tuple(k * math.sqrt(v / n + f * f) for v, f in zip(self._variances, floor))
        y, g = means[:6], means[6:]
        previous, self._previous = self._previous, means
        if self._state == HOLDING:
            trial = list(self._load_sums)
            merge_sums(trial, block)
            theta = solve_still_floats(trial)
            if _within(_residual(y, g, theta), bounds):
                if not moving:  # the estimate is made of readings held still
                    self._load_sums, self._load = trial, theta
                    self.version += 1
                self._back_on_model()
                return
        elif _within(y, bounds):
            self._back_on_model()
            return
        step = self._step
        if step is None:
            step = self._step = _Step(onset=start)
        steady = previous is not None and all(
            abs(a - b) <= k * math.sqrt(2.0 * v / n + f * f)
            for a, b, v, f in zip(y, previous[:6], self._variances, floor)
        )
        if steady:
            step.steady += 1
            merge_sums(step.sums, block)
        else:
            step.steady, step.sums = 0, list(block)
        if step.steady >= self.thresholds.settle_blocks:
            self._decide(t, step, y, g, bounds)
        elif not self._in_contact and t - step.onset >= self.thresholds.contact_time:
            self._event(CONTACT, t, step, y, g, bounds, "the step kept changing")
            self._in_contact = True

    def _back_on_model(self) -> None:
        self._step = None
        self._in_contact = False

    def _decide(self, t, step, y, g, bounds) -> None:
        """Classify a settled step (see the module's rules)."""
        gripper, limit = self.gripper, self.thresholds.max_load_mass
        if self._state == EMPTY:
            mass, across, along, explained = _gravity_test(y, g, bounds, self.thresholds.k_sigma)
            if explained:
                heavy = gripper is None and limit is not None and mass > limit
                if gripper is False or heavy:
                    why = "the gripper is open" if gripper is False else f"mass > {limit:g} kg"
                    theta = solve_still_floats(step.sums)
                    self._offset = tuple(a + b for a, b in zip(self._offset, theta))
                    self.version += 1
                    self._event(TOOL_CHANGE, t, step, y, g, bounds, f"a gravity step while {why}")
                else:
                    self._load_sums = list(step.sums)
                    self._load = solve_still_floats(self._load_sums)
                    self._state = HOLDING
                    self.version += 1
                    held = "the gripper closed" if gripper else "no gripper state given"
                    self._event(GRASP, t, step, y, g, bounds, f"a gravity step, {held}")
                self._back_on_model()
                self._previous = None
                return
            if not self._in_contact:
                k = self.thresholds.k_sigma
                upward = across <= k and along <= k and mass < 0
                reason = "an upward force (a negative mass)" if upward else "not a gravity load"
                self._event(CONTACT, t, step, y, g, bounds, reason)
                self._in_contact = True
            return
        if _within(y, bounds):  # holding, and the force is back to the tool's
            if gripper is True:
                if not self._in_contact:
                    self._event(
                        CONTACT,
                        t,
                        step,
                        y,
                        g,
                        bounds,
                        "the load rests on a surface, gripper closed",
                    )
                    self._in_contact = True
                return
            released = f"back to the tool's, {'gripper open' if gripper is False else 'no gripper'}"
            self._event(RELEASE, t, step, y, g, bounds, released)
            self._state, self._load, self._load_sums = EMPTY, (0.0, 0.0, 0.0, 0.0), empty_sums()
            self.version += 1
            self._back_on_model()
            self._previous = None
            return
        if not self._in_contact:
            self._event(CONTACT, t, step, y, g, bounds, "not explained by the held load")
            self._in_contact = True

    def _event(self, kind, t, step, y, g, bounds, reason) -> None:
        mass, across, along, _ = _gravity_test(y, g, bounds, self.thresholds.k_sigma)
        self.events.append(
            LoadEvent(kind, t, step.onset, mass, y[:3], y[3:], across, along, self.gripper, reason)
        )
        self.label = kind

    # ------------------------------------------------------------ on demand
    def estimate(self) -> LoadEstimate | None:
        """The held load's :class:`~ftkin.control.load_estimator.LoadEstimate` (None when empty).

        Not for the tick: a solve with standard errors (an eigendecomposition).
        """
        return estimate_from(self._load_sums) if self._state == HOLDING else None


def noise_from_readings(readings) -> SensorNoise:
    """One reading's noise per channel estimated from a recording ``(N, 6)`` [N, N·m].

    From consecutive differences, robustly: ``σ = 1.4826 · MAD(Δw) / √2`` per channel (white noise
    doubles its variance in a difference; the median ignores the few steps of grasps and
    contacts; a motion slow beside the reading rate adds little). A channel that does not change
    gets the floor of :data:`~ftkin.calibration.information.NOISE_RANGE`.

    Raises:
        InvalidInput: fewer than 3 readings, or readings not finite.
    """
    wrenches, _ = as_wrenches(readings, "readings")
    if len(wrenches) < 3:
        raise InvalidInput(
            f"estimating the noise needs at least 3 readings, got {len(wrenches)}: give it "
            "(ftkin compensate: --noise-force N --noise-torque NM)"
        )
    differences = np.diff(wrenches, axis=0)
    spread = np.median(np.abs(differences - np.median(differences, axis=0)), axis=0)
    sigma = np.maximum(1.4826 * spread / math.sqrt(2.0), NOISE_RANGE[0])
    return SensorNoise(sigma[:3], sigma[3:])


def _residual(y, g, theta) -> tuple[float, ...]:
    """``y − [m g, (m c) × g]`` of six floats, ``g`` (3), ``θ = [m, m c]``."""
    m, x, yy, z = theta
    gx, gy, gz = g
    return (
        y[0] - m * gx,
        y[1] - m * gy,
        y[2] - m * gz,
        y[3] - (yy * gz - z * gy),
        y[4] - (z * gx - x * gz),
        y[5] - (x * gy - yy * gx),
    )


def _within(values, bounds) -> bool:
    return all(abs(v) <= b for v, b in zip(values, bounds))


def _gravity_test(y, g, bounds, k):
    """``(mass [kg], across [σ], along [σ], explained)`` of a step ``y`` (six floats) at ``g``.

    ``across``: the largest channel of the force across gravity in block standard deviations;
    ``along``: ``|τ·ĝ|`` in standard deviations; explained: both within ``k`` and a positive mass
    beyond ``k`` standard errors.
    """
    gx, gy, gz = g
    g2 = gx * gx + gy * gy + gz * gz
    mass = (y[0] * gx + y[1] * gy + y[2] * gz) / g2
    sigma = tuple(b / k for b in bounds)
    across = max(abs(y[i] - mass * g[i]) / sigma[i] for i in range(3))
    norm = math.sqrt(g2)
    unit = (gx / norm, gy / norm, gz / norm)
    moment_sigma = math.sqrt(sum((u * s) ** 2 for u, s in zip(unit, sigma[3:])))
    along = abs(sum(u * v for u, v in zip(unit, y[3:]))) / moment_sigma
    force_sigma = math.sqrt(sum((u * s) ** 2 for u, s in zip(unit, sigma[:3])))
    explained = across <= k and along <= k and mass * norm > k * force_sigma
    return mass, across, along, explained
