"""The paper's placement experiment (METHOD.md §6) in MuJoCo.

The same :class:`~ftkin.sim.placement.PlacementScenario` as the simple engine,
run in a physics engine instead: the arm's servos, the tool's and the object's
inertia, a spring-loaded sponge or book pad and a sensor with bias, noise and a
one-tick delay (:class:`~ftkin.sim.mujoco.mujoco_sensor.MujocoSensor`, the paper-like
bias of :func:`~ftkin.sim.sensor.paper_like_truth`, gravity tilted by its base tilt).

* ``"position"``: :class:`PositionLowering` lowers the tool at the scenario's speed to
  ``target_depth`` below the surface top and holds it there (force ignored);
* ``"admittance"``: :func:`~ftkin.sim.placement.admittance_controller` with the
  exact compensation (the tool's inertia from the model, the sensor's true bias);
* ``"admittance-uncompensated"``: the same controller on raw readings.

:func:`simulate_placement_mujoco` returns a :class:`~ftkin.sim.placement.PlacementRun`
(so the plots, CSV and settle criteria are shared) and the full :class:`ClosedLoopRun`.
"""

import numpy as np
import pinocchio as pin

from ...calibration.model import STANDARD_GRAVITY
from ...control.damped_least_squares import damped_least_squares
from ...kinematics.arm import Arm
from ..placement import PlacementRun, PlacementScenario, admittance_controller
from ..sensor import paper_like_truth
from ..surfaces import SURFACES
from .arm_model import ArmSimulation, GraspedObject, build_arm_model
from .closed_loop import ClosedLoopRun, run_closed_loop
from .mujoco_sensor import MujocoSensor


class PositionLowering:
    """Position control: lower the tool point at ``speed`` [m/s] to base height ``z_target`` [m],
    ignoring force.

    The commanded height ``z_cmd`` starts at the tool's height on the first step and moves
    at ``speed`` until it reaches ``z_target`` (a trajectory, as a robot's position mode
    runs it: no feedback from the measured height, whose servo lag would make a
    ``1/dt`` feedback gain ring). ``step(q, raw, dt)`` maps ``[0, 0, dz_cmd/dt, 0, 0, 0]``
    at the tool point through the tool Jacobian at the measured ``q`` (damped least squares).
    """

    def __init__(self, arm: Arm, z_target: float, speed: float):
        self.arm, self.z_target, self.speed = arm, float(z_target), float(speed)
        self.z_command: float | None = None

    def step(self, q, raw_wrench, dt: float) -> np.ndarray:
        arm = self.arm
        jacobian = pin.computeFrameJacobian(
            arm.model, arm.data, q, arm.tool_frame_id, pin.LOCAL_WORLD_ALIGNED
        )
        if self.z_command is None:
            self.z_command = float(arm.data.oMf[arm.tool_frame_id].translation[2])
        speed = max(-self.speed, (self.z_target - self.z_command) / dt)
        self.z_command += speed * dt
        return damped_least_squares(jacobian, np.array([0.0, 0.0, speed, 0.0, 0.0, 0.0]))[0]


def placement_scene(scenario: PlacementScenario, arm: Arm | None = None) -> ArmSimulation:
    """The MuJoCo scene of a scenario: its object, its surface below (the other surfaces beside
    it), the paper-like base tilt.
    """
    others = [
        surface for name, surface in sorted(SURFACES.items()) if name != scenario.surface.name
    ]
    return build_arm_model(
        arm,
        grasped_object=GraspedObject(
            mass=scenario.object_weight / STANDARD_GRAVITY, height=scenario.object_height
        ),
        surface_under=scenario.surface.name,
        surfaces=(scenario.surface, *others),
        start_gap=scenario.start_gap,
        base_tilt=paper_like_truth().base_tilt,
    )


def simulate_placement_mujoco(
    scenario: PlacementScenario,
    arm: Arm | None = None,
    *,
    sim: ArmSimulation | None = None,
    sample_rate: float | None = None,
    delay_ticks: int = 1,
    controller=None,
) -> tuple[PlacementRun, ClosedLoopRun]:
    """Run one scenario in MuJoCo at the scenario's ``dt``.

    Args:
        scenario: What to run (surface, mode, gains, object, timing, noise, seed).
        arm: Kinematics for the controller (default: the bundled arm with its tool frame).
        sim: A scene built by :func:`placement_scene` to reuse (its surface must be the scenario's).
        sample_rate: Sensor sample rate [Hz] (None: one sample per tick).
        delay_ticks: Sensor delay in control ticks.
        controller: Override the scenario's controller (anything with ``step(q, raw, dt)``).
    """
    arm = Arm.default() if arm is None else arm
    sim = placement_scene(scenario, arm) if sim is None else sim
    bias = paper_like_truth().bias
    sensor = MujocoSensor(
        bias, scenario.noise, sample_rate=sample_rate, delay_ticks=delay_ticks, seed=scenario.seed
    )
    if controller is None and scenario.mode == "position":
        z_start = arm.frame_placement(sim.q0, "tool")[1][2]
        z_target = z_start - scenario.start_gap - scenario.target_depth
        controller = PositionLowering(arm, z_target, scenario.lowering_speed)
    elif controller is None:
        calibration = sim.tool_sensor_model(bias) if scenario.mode == "admittance" else None
        controller = admittance_controller(scenario, arm, calibration)
    run = run_closed_loop(sim, controller, scenario.duration, scenario.dt, sensor=sensor)
    safety = bool(getattr(controller, "safety_latched", False))
    return PlacementRun(scenario, *run.placement_rows().T.copy(), safety_stop=safety), run
