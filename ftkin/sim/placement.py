"""The paper's placement experiment (METHOD.md §6), simulated on the bundled arm.

Setup. The arm holds a grasped object (known weight ``W`` [N], height ``h``
[m] below the tool point along the tool axis) with the tool pointing down
(``q_down``), ``start_gap`` above a :class:`~ftkin.sim.surfaces.Surface`. The arm
is a velocity-controlled kinematic system: ``q ← q + dq·dt`` every tick. The
simulated sensor (:class:`~ftkin.sim.sensor.SimulatedSensor`, paper-like bias,
tool weight and noise) reads, in the sensor frame, the object's weight and the
surface's normal force at the object's bottom, with their moments about the
sensor origin. The recorded ``force`` is the true compensated ``F'z`` (sensor
z, pointing down): ``+W`` in the air, ``0`` when the surface carries the
object, negative when the arm presses (the sign of the paper's figures).

Scenarios (``mode``):

* ``"position"``: the tool is lowered at ``lowering_speed`` to a target
  ``target_depth`` below the surface top, then stops; force is ignored, so the
  object hits the surface and stays pressed in (harder on a stiffer surface).
* ``"admittance"``: :class:`~ftkin.control.joint_admittance.JointAdmittance` with the
  exact compensation, on the tool z axis only (``S = diag(0,0,1,0,0,0)``) and
  desired force 0. How lowering and a zero desired force combine: the
  compensated reading still holds the object's weight, ``ΔF = W`` along the
  tool axis, so the arm *yields to the weight* and moves down at ``K2·W``;
  once the surface takes the weight, ``F'z → 0`` and the motion fades with it.
  The loop is running when the object's weight is taken (``bumpless=False``),
  so the position term also lowers the tool by ``K1·W`` at the start. The
  object is placed when ``|F'z| < 0.05 N`` and the tool has stopped; then the
  gripper could open without a jolt.
* ``"admittance-uncompensated"``: the same controller fed raw readings: the
  bias and the tool's weight look like a load the arm must hand to the
  surface, so it pushes further down, to ``N ≈ W + tool weight + F0z``.

:func:`sweep` repeats a scenario over values of ``k1`` (k13) or ``k2`` (k23).
"""

import math
from dataclasses import dataclass, field, replace
from numbers import Real

import numpy as np
import pinocchio as pin

from ..calibration.information import SensorNoise
from ..calibration.model import SensorModel
from ..control.admittance import Admittance
from ..control.compensation import Compensator
from ..control.damped_least_squares import damped_least_squares
from ..control.joint_admittance import JointAdmittance
from ..exceptions import InvalidInput
from ..kinematics.arm import Arm
from .sensor import paper_like_truth
from .surfaces import SPONGE, Surface, held_object_wrench

MODES = ("position", "admittance", "admittance-uncompensated")
"""Scenarios :func:`simulate_placement` runs."""

Q_DOWN = (0.0, 0.0, -np.pi / 6, 0.0, -np.pi / 3, 0.0)
"""Tool-pointing-down configuration of the bundled arm [rad]."""

PLACED_FORCE = 0.05
"""``|F'z|`` [N] below which the object counts as placed."""

STOPPED_SPEED = 1.0e-4
"""Tool speed [m/s] below which the arm counts as stopped (averaged over :data:`SPEED_WINDOW`)."""

SPEED_WINDOW = 0.1
"""Window [s] of the trailing average of the tool speed (sensor noise makes single ticks jitter)."""


@dataclass(frozen=True)
class PlacementScenario:
    """One run of the experiment (SI units; the CLI converts the paper's mm).

    Attributes:
        surface: The surface (its height is set from ``start_gap``).
        mode: One of :data:`MODES`.
        k1: Position gain k13 [m/N].
        k2: Velocity gain k23 [m/(s·N)].
        object_weight: Weight of the grasped object [N].
        object_height: Object bottom below the tool point [m].
        start_gap: Object bottom above the surface at the start [m].
        lowering_speed: Position mode's speed [m/s].
        target_depth: Position mode's target below the surface top [m].
        duration: Simulated time [s]. dt: Control period [s].
        derivative_cutoff: Admittance derivative filter [Hz].
        force_deadband: Admittance deadband [N].
        noise: Sensor noise per reading. seed: Random seed.
    """

    surface: Surface = SPONGE
    mode: str = "admittance"
    k1: float = 1.0e-4
    k2: float = 1.0e-3
    object_weight: float = 2.214
    object_height: float = 0.04
    start_gap: float = 0.002
    lowering_speed: float = 0.01
    target_depth: float = 0.005
    duration: float = 5.0
    dt: float = 1.0e-3
    derivative_cutoff: float = 5.0
    force_deadband: float = 0.02
    noise: SensorNoise = field(default_factory=SensorNoise.paper)
    seed: int = 0

    def __post_init__(self):
        if self.mode not in MODES:
            raise InvalidInput(f"mode must be one of {MODES}, got {self.mode!r}")
        if not all(isinstance(k, Real) and 0 <= k < math.inf for k in (self.k1, self.k2)):
            raise InvalidInput(
                f"gains must be finite numbers >= 0, got k1={self.k1!r} m/N, k2={self.k2!r} m/(s·N)"
            )
        for name in (
            "object_weight",
            "object_height",
            "lowering_speed",
            "target_depth",
            "duration",
            "dt",
        ):
            value = getattr(self, name)
            if not (isinstance(value, Real) and 0 < value < math.inf):
                raise InvalidInput(f"{name} must be a finite number > 0, got {value!r}")
        if not (isinstance(self.start_gap, Real) and 0 <= self.start_gap < math.inf):
            raise InvalidInput(
                f"start_gap must be a finite number >= 0 [m], got {self.start_gap!r}"
            )
        if self.duration / self.dt > MAX_TICKS:
            raise InvalidInput(
                f"duration {self.duration:g} s at dt {self.dt:g} s is "
                f"{self.duration / self.dt:.3g} ticks; "
                f"at most {MAX_TICKS:,}: shorten the run or lengthen the step"
            )


MAX_TICKS = 1_000_000
"""Longest simulation, in control ticks (duration / dt): beyond it the run's arrays exhaust
memory.
"""


@dataclass(frozen=True)
class PlacementRun:
    """Time series of one run (arrays of one entry per tick).

    Attributes:
        time: [s]. displacement: Tool z from the start, base frame [m].
        velocity: Tool z velocity, base frame [m/s].
        force: True compensated ``F'z``, sensor frame (down) [N].
        measured_force: ``F'z`` as the controller saw it [N] (raw z without compensation).
        penetration: Object bottom below the surface top [m] (0 when clear).
        normal_force: Surface's force on the object [N].
        safety_stop: Whether the controller's safety stop fired.
    """

    scenario: PlacementScenario
    time: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    force: np.ndarray
    measured_force: np.ndarray
    penetration: np.ndarray
    normal_force: np.ndarray
    safety_stop: bool

    COLUMNS = (
        "t",
        "displacement",
        "velocity",
        "force",
        "measured_force",
        "penetration",
        "normal_force",
    )
    """CSV header; units s, m, m/s, N, N, m, N."""

    @property
    def peak_contact_force(self) -> float:
        """Largest surface force on the object [N]."""
        return float(self.normal_force.max())

    @property
    def final_force(self) -> float:
        """``F'z`` at the end [N]."""
        return float(self.force[-1])

    def mean_speed(self) -> np.ndarray:
        """Trailing average of the tool z velocity over :data:`SPEED_WINDOW` [m/s], per tick."""
        width = max(1, int(round(SPEED_WINDOW / self.scenario.dt)))
        total = np.concatenate(([0.0], np.cumsum(self.velocity)))
        index = np.arange(1, len(total))
        count = np.minimum(index, width)  # ticks in the window (fewer at the start)
        return (total[index] - total[index - count]) / count

    def settled_mask(self) -> np.ndarray:
        """Per tick: ``|F'z| < 0.05 N`` and the tool's mean speed below :data:`STOPPED_SPEED`."""
        return (np.abs(self.force) < PLACED_FORCE) & (np.abs(self.mean_speed()) < STOPPED_SPEED)

    @property
    def settle_time(self) -> float:
        """First time [s] from which the run stays settled to the end; ``inf`` if never."""
        mask = self.settled_mask()
        if not mask[-1]:
            return float("inf")
        unsettled = np.flatnonzero(~mask)
        return float(self.time[unsettled[-1] + 1]) if unsettled.size else float(self.time[0])

    @property
    def placed(self) -> bool:
        """Whether the run ends settled (object placed, arm stopped)."""
        return bool(np.isfinite(self.settle_time))

    def rows(self) -> np.ndarray:
        """The series as an ``(N, 7)`` array in :attr:`COLUMNS` order."""
        return np.column_stack(
            [
                self.time,
                self.displacement,
                self.velocity,
                self.force,
                self.measured_force,
                self.penetration,
                self.normal_force,
            ]
        )


def simulate_placement(
    scenario: PlacementScenario, arm: Arm | None = None, on_tick=None
) -> PlacementRun:
    """Run one scenario; the arm defaults to the bundled one (with its tool frame).

    ``on_tick(q, contact_wrench, twist)``, if given, is called after every
    admittance tick with the controller's status (e.g. ``LiveView.publish``).
    """
    arm = Arm.default() if arm is None else arm
    if arm.tool_frame_id is None:
        raise InvalidInput("the placement simulation needs an arm with a tool frame")
    rng = np.random.default_rng(scenario.seed)
    truth = paper_like_truth()
    q = arm.check_configuration(Q_DOWN[: arm.nq]).copy()
    model, data, sensor_id, tool_id = arm.model, arm.data, arm.sensor_frame_id, arm.tool_frame_id
    _, tool_start = arm.frame_placement(q, "tool")
    rotation, _ = arm.frame_placement(q, "sensor")
    surface = scenario.surface.at_height(
        (tool_start + rotation[:, 2] * scenario.object_height)[2] - scenario.start_gap
    )
    calibration = truth if scenario.mode == "admittance" else None  # else raw readings
    controller = (
        None if scenario.mode == "position" else admittance_controller(scenario, arm, calibration)
    )
    # The sensor's no-contact reading (bias + tool gravity) is -compensate(R, 0): same model as
    # SimulatedSensor.read.
    unloaded = Compensator(truth)
    zero = np.zeros(6)
    steps = int(round(scenario.duration / scenario.dt))
    noise = rng.standard_normal((steps, 6)) * scenario.noise.channel_std
    z_target = tool_start[2] - scenario.start_gap - scenario.target_depth
    height, weight = scenario.object_height, scenario.object_weight
    out = np.zeros((steps, 7))
    penetration_before = 0.0
    for i in range(steps):
        jacobian_tool = pin.computeFrameJacobian(model, data, q, tool_id, pin.LOCAL_WORLD_ALIGNED)
        tool_point = data.oMf[tool_id].translation
        placement = pin.updateFramePlacement(model, data, sensor_id)
        rotation, sensor_origin = placement.rotation, placement.translation
        penetration = max(0.0, surface.height - (tool_point[2] + rotation[2, 2] * height))
        normal = surface.normal_force(penetration, (penetration - penetration_before) / scenario.dt)
        penetration_before = penetration
        contact = held_object_wrench(rotation, sensor_origin, tool_point, height, weight, normal)
        raw = contact - unloaded.compensate_unchecked(rotation, zero) + noise[i]
        if controller is None:
            speed = max(-scenario.lowering_speed, (z_target - tool_point[2]) / scenario.dt)
            dq = damped_least_squares(jacobian_tool, np.array([0.0, 0.0, speed, 0.0, 0.0, 0.0]))[0]
            measured = contact[2]
        else:
            dq = controller.step(q, raw, scenario.dt)
            measured = controller.last_status.contact_wrench[2]
            if on_tick is not None:
                on_tick(q, controller.last_status.contact_wrench, controller.last_status.twist)
        out[i] = (
            i * scenario.dt,
            tool_point[2] - tool_start[2],
            jacobian_tool[2] @ dq,
            contact[2],
            measured,
            penetration,
            normal,
        )
        q = q + dq * scenario.dt
    return PlacementRun(
        scenario, *out.T, safety_stop=controller is not None and controller.safety_latched
    )


def admittance_controller(
    scenario: PlacementScenario, arm: Arm, calibration: SensorModel | None
) -> JointAdmittance:
    """The experiment's controller: tool z only, desired force 0, started before the weight is
    taken.

    ``calibration`` compensates the readings; None feeds the raw readings through.
    """
    admittance = Admittance(
        scenario.k1,
        scenario.k2,
        selection=[0, 0, 1, 0, 0, 0],
        frame="tool",
        force_deadband=scenario.force_deadband,
        derivative_cutoff=scenario.derivative_cutoff,
        bumpless=False,
    )
    compensator = None if calibration is None else Compensator(calibration, arm)
    return JointAdmittance(arm, admittance, compensator, control_point="tool")


def sweep(
    scenario: PlacementScenario, gain: str, values, arm: Arm | None = None
) -> list[PlacementRun]:
    """Runs of ``scenario`` with ``gain`` (``"k1"`` [m/N] or ``"k2"`` [m/(s·N)]) set to each
    value.
    """
    if gain not in ("k1", "k2"):
        raise InvalidInput(f"gain must be 'k1' or 'k2', got {gain!r}")
    arm = Arm.default() if arm is None else arm
    return [simulate_placement(replace(scenario, **{gain: float(value)}), arm) for value in values]
