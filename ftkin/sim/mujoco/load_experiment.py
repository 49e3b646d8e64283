"""The paper's grasp experiment (METHOD.md eq. 23, Table 4) with the load unknown, in MuJoCo.

The arm (the bundled URDF in MuJoCo, :class:`~ftkin.sim.mujoco.load_recording.MujocoLoadRecorder`)
holds still, takes a load (its mass rising over 10 ms), holds it still, turns the wrist by 60°
about joint 5 and then about joint 4 (cosine ramps, a dwell after each), and sets it down (the mass
falling over 10 ms). The sensor adds a bias and seeded noise. ftkin sees only ``q`` and the raw
readings: a :class:`~ftkin.control.compensation.Compensator` of the tool (its mass and COM from
MuJoCo's bodies) with a :class:`~ftkin.control.load_events.LoadTracker` part (or, while the arm
moves fast, a :class:`~ftkin.control.dynamic_compensation.DynamicCompensator`).
:func:`run_load_trial` returns what it identified beside MuJoCo's truth; :func:`run_guiding` a
stretch of hand guiding with pushes and a surface contact while carrying.
"""

import math
from dataclasses import dataclass

import numpy as np

from ...calibration.information import SensorNoise
from ...calibration.model import SensorModel
from ...control.compensation import Compensator
from ...control.dynamic_compensation import DynamicCompensator
from ...control.load_events import GRASP, RELEASE, LoadEvent, LoadTracker
from ...kinematics.arm import Arm
from .load_recording import MujocoLoadRecorder

TABLE4_WEIGHTS = (1.005, 2.214, 3.180, 4.116, 5.244, 6.066)
"""Table 4's true load weights [N] (METHOD.md); masses are these over :data:`PAPER_G`."""

TABLE4_COMPUTED = (1.033, 2.291, 3.300, 4.275, 5.411, 6.294)
"""The weights the paper computed for them [N]."""

PAPER_G = 9.8
"""The paper's g [m/s²]."""

START_POSE = (0.2, -0.4, 1.6, 0.1, -0.9, 0.3)
"""The arm's pose while taking and setting down the load [rad]."""

RATE = 1000.0
"""Readings per second [Hz]."""

SENSOR_BIAS = (1.2, -0.8, 2.5, 0.05, -0.03, 0.02)
"""The simulated sensor's bias [N, N·m] (known to the calibration)."""


@dataclass(frozen=True)
class Segment:
    """A stretch of the motion: ``duration`` [s], joint change ``delta`` (nq,) [rad] along a
    cosine ramp, and the load mass [kg] at its end (ramped linearly from the one before)."""

    duration: float
    delta: tuple = (0.0,) * 6
    mass: float | None = None


def plan(segments, start=START_POSE, rate: float = RATE):
    """``(t, q, dq, ddq, mass)`` of consecutive :class:`Segment` (a cosine ramp per segment)."""
    times, q, dq, ddq, masses = [], [], [], [], []
    position, mass, clock = np.array(start, dtype=float), 0.0, 0.0
    for segment in segments:
        count = int(round(segment.duration * rate))
        tau = (np.arange(count) + 1) / count
        delta = np.asarray(segment.delta, dtype=float)
        s = (1 - np.cos(np.pi * tau)) / 2
        rate_s = np.pi / (2 * segment.duration) * np.sin(np.pi * tau)
        accel_s = (np.pi / segment.duration) ** 2 / 2 * np.cos(np.pi * tau)
        moving = np.any(delta != 0)
        q.append(position + np.outer(s, delta))
        dq.append(np.outer(rate_s, delta) if moving else np.zeros((count, 6)))
        ddq.append(np.outer(accel_s, delta) if moving else np.zeros((count, 6)))
        end = mass if segment.mass is None else segment.mass
        masses.append(mass + (end - mass) * tau)
        times.append(clock + tau * segment.duration)
        position, mass, clock = position + delta, end, clock + segment.duration
    return tuple(np.concatenate(parts) for parts in (times, q, dq, ddq, masses))


def tool_model(recorder: MujocoLoadRecorder) -> SensorModel:
    """The tool's :class:`SensorModel` from MuJoCo's bodies (load mass zero), with the bias."""
    recorder.set_load_mass(0.0)
    theta = recorder.true_parameters()
    mass, com = float(theta[0]), theta[1:4] / theta[0]
    bias = np.array(SENSOR_BIAS)
    g = float(np.linalg.norm(recorder.model.opt.gravity))
    return SensorModel.from_tool(mass, com, bias[:3], bias[3:], (0.0, 0.0), g)


@dataclass(frozen=True)
class LoadTrial:
    """One load taken, identified, turned and set down.

    Attributes:
        true_mass: MuJoCo's load mass [kg]; ``true_com`` its COM (3,) [m, sensor frame].
        mass_held: Identified mass 1 s after the grasp ended, held still [kg] (``mass_held_std``).
        com_held: COM then (3,) [m] (NaN: undetermined along gravity).
        mass: Identified mass after the wrist turns [kg]; ``com`` (3,) [m], ``com_std`` (3,) [m].
        grasp_delay, release_delay: From the end of the mass step to the event [s] (inf: none).
        events: Every :class:`LoadEvent`.
    """

    true_mass: float
    true_com: np.ndarray
    mass_held: float
    mass_held_std: float
    com_held: np.ndarray
    mass: float
    com: np.ndarray
    com_std: np.ndarray
    grasp_delay: float
    release_delay: float
    events: tuple[LoadEvent, ...]


def _noisy(readings, noise: SensorNoise, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return readings + np.asarray(SENSOR_BIAS) + rng.normal(size=readings.shape) * noise.channel_std


def _first(events, kind: str, after: float) -> float:
    return next((event.time - after for event in events if event.kind == kind), math.inf)


def run_load_trial(
    weight: float,
    load_position=(0.01, -0.008, 0.07),
    *,
    noise: SensorNoise | None = None,
    seed: int = 0,
    recorder: MujocoLoadRecorder | None = None,
    arm: Arm | None = None,
) -> LoadTrial:
    """Take a load of ``weight`` [N] (mass ``weight / 9.8``) at ``load_position`` (sensor frame
    [m]), identify it held still, turn the wrist 60° about joints 5 and 4, set it down.
    """
    noise = SensorNoise.paper() if noise is None else noise
    recorder = MujocoLoadRecorder(load_position) if recorder is None else recorder
    arm = Arm.default() if arm is None else arm
    mass = weight / PAPER_G
    turn = math.radians(60.0)
    segments = (
        Segment(0.3),
        Segment(0.01, mass=mass),  # the grasp: the load lifted in 10 ms
        Segment(1.09),
        Segment(1.0, (0, 0, 0, 0, turn, 0)),
        Segment(0.3),
        Segment(1.0, (0, 0, 0, turn, 0, 0)),
        Segment(0.3),
        Segment(1.0, (0, 0, 0, -turn, -turn, 0)),
        Segment(0.3),
        Segment(0.01, mass=0.0),  # set down
        Segment(0.3),
    )
    t, q, dq, ddq, masses = plan(segments)
    recorder.set_load_mass(mass)
    true_mass, true_com = recorder.true_load(q[0])
    raw = _noisy(recorder.readings(q, dq, ddq, masses, np.zeros((len(t), 6))), noise, seed)
    tracker = LoadTracker(noise, recorder.model.opt.gravity, period=1.0 / RATE)
    compensator = DynamicCompensator(
        tool_model(recorder), arm, inertial_parameters=_tool_theta(recorder), load=tracker
    )
    grasped, released = 0.31, 5.31  # the ends of the mass steps [s]
    estimates = {}
    for i in range(len(t)):
        compensator.contact_moving_floats(q[i], dq[i], ddq[i], raw[i])
        for name, at in (("held", grasped + 1.0), ("turned", 4.0)):
            if name not in estimates and t[i] >= at - 1e-9:
                estimates[name] = tracker.estimate()
    held, turned = (_values(estimates.get(name)) for name in ("held", "turned"))
    events = tuple(tracker.events)
    return LoadTrial(
        true_mass,
        true_com,
        held[0],
        held[1],
        held[2],
        turned[0],
        turned[2],
        turned[3],
        _first(events, GRASP, grasped),
        _first(events, RELEASE, released),
        events,
    )


def _values(estimate):
    """``(mass, mass_std, com, com_std)`` of an estimate, NaN and inf for None."""
    if estimate is None:
        return math.nan, math.inf, np.full(3, np.nan), np.full(3, np.inf)
    return estimate.mass, estimate.mass_std, estimate.com_in_sensor, estimate.com_std


def _tool_theta(recorder: MujocoLoadRecorder) -> np.ndarray:
    recorder.set_load_mass(0.0)
    return recorder.true_parameters()


@dataclass(frozen=True)
class GuidingRun:
    """A stretch of hand guiding with pushes, a grasp, a surface contact while carrying, a
    release.

    Attributes:
        times: ``(N,)`` [s]; ``labels`` each tick's label; ``events`` every event.
        pushes: ``((start, end), ...)`` the pushes' windows [s]; ``surface`` the surface
            contact's window [s].
        grasped, released: The ends of the mass steps [s].
        true_mass: The load's mass [kg]; ``mass_after`` the identified mass before the release.
    """

    times: np.ndarray
    labels: tuple[str, ...]
    events: tuple[LoadEvent, ...]
    pushes: tuple
    surface: tuple
    grasped: float
    released: float
    true_mass: float
    mass_after: float


def _window(times, start, duration, ramp=None):
    """``(N,)`` envelope: ``sin²`` over ``duration`` from ``start``, or with ``ramp`` [s] a
    trapezoid."""
    tau = (times - start) / duration
    inside = (tau >= 0) & (tau <= 1)
    if ramp is None:
        return np.where(inside, np.sin(np.pi * np.clip(tau, 0, 1)) ** 2, 0.0)
    rise = np.clip((times - start) / ramp, 0, 1) * np.clip((start + duration - times) / ramp, 0, 1)
    return np.where(inside, rise, 0.0)


def run_guiding(
    weight: float = 3.180,
    push: float = 20.0,
    *,
    noise: SensorNoise | None = None,
    seed: int = 0,
    recorder: MujocoLoadRecorder | None = None,
    arm: Arm | None = None,
) -> GuidingRun:
    """Hand guiding (the arm moved by segments) with pushes up to ``push`` [N] on the tool, empty
    and carrying a load of ``weight`` [N]; the load set on a surface that takes 70 % of its weight
    for 0.5 s; then released.
    """
    noise = SensorNoise.paper() if noise is None else noise
    recorder = MujocoLoadRecorder((0.01, -0.008, 0.07)) if recorder is None else recorder
    arm = Arm.default() if arm is None else arm
    rng = np.random.default_rng(seed)
    mass = weight / PAPER_G

    def moves(count):
        return [
            Segment(0.7, tuple(rng.uniform(-0.15, 0.15, 3).tolist() + [0.0] * 3))
            for _ in range(count)
        ]

    segments = (
        [Segment(0.3)]
        + moves(3)
        + [Segment(0.2), Segment(0.01, mass=mass), Segment(1.0)]
        + moves(4)
        + [Segment(1.0), Segment(0.3), Segment(0.01, mass=0.0), Segment(0.3)]
    )
    t, q, dq, ddq, masses = plan(segments)
    grasped = 0.3 + 2.1 + 0.2 + 0.01
    carrying = grasped + 1.0
    pushes = (
        (0.5, 0.6),
        (1.4, 0.6),
        (carrying + 0.3, 0.6),
        (carrying + 1.3, 0.6),
        (carrying + 2.2, 0.5),
    )
    applied = np.zeros((len(t), 6))
    for start, duration in pushes:
        direction = rng.normal(size=3)
        direction /= np.linalg.norm(direction)
        applied[:, :3] += np.outer(_window(t, start, duration), push * direction)
    surface = (carrying + 2.8 + 0.1, 0.6)
    up = -np.asarray(recorder.model.opt.gravity, dtype=float)
    up /= np.linalg.norm(up)
    support = 0.7 * mass * PAPER_G * up + np.array([0.3, -0.2, 0.0])
    applied[:, :3] += np.outer(_window(t, *surface, ramp=0.05), support)
    released = t[-1] - 0.3
    recorder.set_load_mass(mass)
    true_mass = recorder.true_load(q[0])[0]
    raw = _noisy(recorder.readings(q, dq, ddq, masses, applied), noise, seed)
    tracker = LoadTracker(noise, recorder.model.opt.gravity, period=1.0 / RATE)
    compensator = DynamicCompensator(
        tool_model(recorder), arm, inertial_parameters=_tool_theta(recorder), load=tracker
    )
    labels, mass_after = [], math.nan
    for i in range(len(t)):
        compensator.contact_moving_floats(q[i], dq[i], ddq[i], raw[i])
        labels.append(tracker.label)
        if t[i] < released - 0.01 and tracker.state == "holding":
            mass_after = float(tracker.load_parameters[0])
    windows = tuple((start, start + duration) for start, duration in pushes)
    return GuidingRun(
        t,
        tuple(labels),
        tuple(tracker.events),
        windows,
        (surface[0], surface[0] + surface[1]),
        grasped,
        released,
        true_mass,
        mass_after,
    )


@dataclass(frozen=True)
class IdentifiedPlacement:
    """The placement experiment with the object's weight identified instead of known.

    Attributes:
        run: The :class:`~ftkin.sim.placement.PlacementRun` (admittance on the tool's z, the
            object's weight driving it down onto the surface).
        true_mass: The object's mass in MuJoCo [kg].
        identified_mass: The tracker's mass before the object touched the surface [kg].
        placed_time: The first time [s] from which the surface carries the identified load: the
            force along gravity after the tool (the load's weight ``m̂ g`` while it hangs) stays
            within ±0.05 N of the empty tool's (a 20 ms trailing mean) to the end; inf if never.
        events: Every :class:`LoadEvent` (the gripper given as closed throughout).
    """

    run: object
    true_mass: float
    identified_mass: float
    placed_time: float
    events: tuple[LoadEvent, ...]


class _Watched:
    """A controller whose every tick also feeds a load tracker the contact after the tool."""

    def __init__(self, controller, compensator, tracker, gravity_in_base):
        self.controller, self.compensator, self.tracker = controller, compensator, tracker
        self.down = np.asarray(gravity_in_base) / np.linalg.norm(gravity_in_base)
        self.mass_before_contact = math.nan
        self.along = []  # per tick: the force along gravity after the tool [N] (the load's weight)

    def step(self, q, raw_wrench, dt: float):
        rotation = self.compensator.arm.rotation_sensor_to_base(np.asarray(q)[None])[0]
        contact = self.compensator.compensate_rotation(rotation, raw_wrench)
        self.tracker.tick(rotation.tolist(), contact.tolist())
        if self.tracker.state == "holding" and all(e.kind == GRASP for e in self.tracker.events):
            self.mass_before_contact = float(self.tracker.load_parameters[0])
        self.along.append(float(contact[:3] @ (rotation.T @ self.down)))
        return self.controller.step(q, raw_wrench, dt)


def run_placement(weight: float = 2.214, surface=None, *, seed: int = 0, arm: Arm | None = None):
    """The paper's placement (admittance, desired force 0, the object's weight driving the tool
    down) with a :class:`LoadTracker` beside the controller (the gripper closed): it identifies
    the held object, and "placed" is decided from the identified weight (see
    :class:`IdentifiedPlacement`).
    """
    from ..placement import PLACED_FORCE, PlacementScenario, admittance_controller
    from ..sensor import paper_like_truth
    from ..surfaces import SPONGE
    from .mujoco_placement import placement_scene, simulate_placement_mujoco

    arm = Arm.default() if arm is None else arm
    scenario = PlacementScenario(
        surface=SPONGE if surface is None else surface, object_weight=weight, seed=seed
    )
    sim = placement_scene(scenario, arm)
    tool = sim.tool_sensor_model(paper_like_truth().bias)
    gravity = tool.gravity_in_base / np.linalg.norm(tool.gravity_in_base) * tool.g
    tracker = LoadTracker(scenario.noise, gravity, period=scenario.dt)
    tracker.gripper = True
    watched = _Watched(
        admittance_controller(scenario, arm, tool), Compensator(tool, arm), tracker, gravity
    )
    run, _ = simulate_placement_mujoco(scenario, arm, sim=sim, controller=watched)
    window = max(1, int(round(0.02 / scenario.dt)))  # a 20 ms trailing mean against the noise
    along = np.convolve(watched.along, np.ones(window) / window)[: len(watched.along)]
    carried = np.abs(along) <= PLACED_FORCE
    unplaced = np.flatnonzero(~carried)
    placed = (
        math.inf
        if not carried[-1]
        else float(run.time[min(unplaced[-1] + 1, len(run.time) - 1)])
        if unplaced.size
        else 0.0
    )
    true_mass = float(sim.model.body_mass[sim.object_body_id])
    return IdentifiedPlacement(
        run, true_mass, watched.mass_before_contact, placed, tuple(tracker.events)
    )
