"""Run a controller in the loop with MuJoCo: read, decide, command, integrate.

Each control tick of :func:`run_closed_loop`:

1. MuJoCo's ideal wrench (ftkin's sign) becomes a raw reading through the
   :class:`~ftkin.sim.mujoco.mujoco_sensor.MujocoSensor` (bias, noise, saturation,
   sample rate, one-tick delay);
2. the controller turns the measured joint positions and the reading into
   joint velocities (``controller.step(q, raw, dt)``, e.g.
   :class:`~ftkin.control.JointAdmittance`);
3. the velocities go to the speedJ-like servos and MuJoCo integrates ``dt``.

Typical rates: 125 Hz (a UR's classic interface), 500 Hz (a typical driver),
1 kHz (a Franka). The run is recorded as :class:`ClosedLoopRun`: the placement
CSV's columns plus joint states and the ideal wrench.
"""

import math
from dataclasses import dataclass

import numpy as np

from ...calibration.model import SensorModel
from ...exceptions import InvalidInput
from ..placement import PlacementRun
from .arm_model import ArmSimulation
from .mujoco_sensor import MujocoSensor

PLACEMENT_COLUMNS = PlacementRun.COLUMNS
"""The placement CSV's columns (s, m, m/s, N, N, m, N), as
:attr:`~ftkin.sim.placement.PlacementRun.COLUMNS`.
"""

WRENCH_COLUMNS = tuple(f"ideal_{c}" for c in ("fx", "fy", "fz", "mx", "my", "mz"))
"""Ideal load on the sensor [N, N·m], sensor frame, ftkin's sign."""


@dataclass(frozen=True)
class ClosedLoopRun:
    """What a closed-loop run recorded, one row per control tick.

    Attributes:
        columns: Column names: :data:`PLACEMENT_COLUMNS` (``force`` is the true compensated
            ``F'z``: the ideal wrench minus the tool's modelled weight; ``measured_force`` the
            controller's compensated ``F'z`` from its ``last_status``, or the raw ``fz`` for a
            controller without one), then ``q1..qn`` [rad],
            ``dq1..dqn`` [rad/s] (measured), ``cmd1..cmdn`` [rad/s] (commanded),
            :data:`WRENCH_COLUMNS` and ``held`` (1 when the controller held the arm).
        table: ``(ticks, len(columns))``.
        dt: Control period [s].
        events: ``(time [s], message)`` each time the controller's event or fault changed.
        first_hold: Time [s] of the first held tick, ``inf`` if none.
    """

    columns: tuple[str, ...]
    table: np.ndarray
    dt: float
    events: tuple[tuple[float, str], ...]
    first_hold: float

    def column(self, name: str) -> np.ndarray:
        """One column by name."""
        if name not in self.columns:
            raise InvalidInput(f"no column {name!r}; columns: {self.columns}")
        return self.table[:, self.columns.index(name)]

    def placement_rows(self) -> np.ndarray:
        """The ``(ticks, 7)`` placement columns (:data:`PLACEMENT_COLUMNS`)."""
        return self.table[:, : len(PLACEMENT_COLUMNS)]


def run_closed_loop(
    sim: ArmSimulation,
    controller,
    duration: float,
    dt: float,
    *,
    sensor: MujocoSensor | None = None,
    tool_model: SensorModel | None = None,
    reset: bool = True,
) -> ClosedLoopRun:
    """Step MuJoCo with ``controller`` in the loop for ``duration`` [s] at period ``dt`` [s].

    Args:
        sim: The scene (:func:`~ftkin.sim.mujoco.build_arm_model`).
        controller: Anything with ``step(q, raw_wrench, dt) -> dq`` [rad/s] (and optionally
            ``last_status`` like :class:`~ftkin.control.JointAdmittance`).
        duration: Simulated time [s].
        dt: Control period [s] (e.g. 1/125, 1/500, 1/1000); a multiple of the MuJoCo timestep.
        sensor: Sensor model; default: noiseless, unbiased, one-tick delay.
        tool_model: The tool's true weight for the ``force`` column,
            ``F'z = ideal fz − (R_BSᵀ a)_z`` (default: :meth:`ArmSimulation.tool_sensor_model`,
            from the model's tool inertia; its bias is ignored).
        reset: Start from ``sim``'s build pose at rest (else continue from the current state).
    """
    if not (0 < duration < math.inf and 0 < dt < math.inf):
        raise InvalidInput(f"duration and dt must be finite and > 0 [s], got {duration!r}, {dt!r}")
    substeps = dt / sim.model.opt.timestep
    if abs(substeps - round(substeps)) > 1e-6 or round(substeps) < 1:
        raise InvalidInput(
            f"dt = {dt} s must be a multiple of MuJoCo's timestep {sim.model.opt.timestep} s"
        )
    if getattr(controller, "step", None) is None:
        raise InvalidInput(
            "controller must have a step(q, raw_wrench, dt) method, got "
            f"{type(controller).__name__}"
        )
    if reset:
        sim.reset()
    sensor = MujocoSensor() if sensor is None else sensor
    sensor.reset()
    tool_model = sim.tool_sensor_model() if tool_model is None else tool_model
    ax, ay, az = np.asarray(tool_model.gravity_in_base, dtype=float).tolist()
    nq, dt, data = sim.arm.nq, float(dt), sim.data
    columns = (
        PLACEMENT_COLUMNS
        + tuple(f"{kind}{i + 1}" for kind in ("q", "dq", "cmd") for i in range(nq))
        + WRENCH_COLUMNS
        + ("held",)
    )
    table = np.zeros((int(round(duration / dt)), len(columns)))
    events, last_event, first_hold = [], "", math.inf
    z_start = z_before = float(data.xpos[sim.tool_body_id][2])
    for i, row in enumerate(table):
        ideal = sim.ideal_wrench_in_sensor()
        q = sim.q
        raw = sensor.read(ideal, dt)
        dq = controller.step(q, raw, dt)
        status = getattr(controller, "last_status", None)
        # The row: time, tool height and speed, true and measured F'z, the surface, q, dq, ...
        row[4] = raw[2] if status is None else status.contact_wrench[2]
        if status is not None:
            event = status.event or ("" if status.fault == "none" else str(status.fault))
            if event != last_event:
                events.append((i * dt, str(event)))
                last_event = event
            if status.held:
                row[-1] = 1.0
                first_hold = min(first_hold, i * dt)
        z = data.xpos[sim.tool_body_id][2]
        row[0], row[1], row[2] = i * dt, z - z_start, (z - z_before) / dt
        # R_BS's third column: the sensor z axis in the base
        r02, r12, r22 = data.site_xmat[sim.sensor_site_id][2::3].tolist()
        row[3] = ideal[2] - (r02 * ax + r12 * ay + r22 * az)
        if sim.surface_under is not None:
            row[5], row[6] = sim.surface_depth(), sim.normal_force()
        row[7 : 7 + nq], row[7 + nq : 7 + 2 * nq] = q, data.qvel[sim._arm_dof]
        row[7 + 2 * nq : 7 + 3 * nq], row[7 + 3 * nq : 13 + 3 * nq] = dq, ideal
        z_before = z
        sim.step(dq, dt)
    return ClosedLoopRun(columns, table, dt, tuple(events), first_hold)
