"""The compiled MuJoCo scene with ftkin-side accessors (state, readings, the tool's truth).

Built by :func:`~ftkin.sim.mujoco.arm_model.build_arm_model`. MuJoCo's world frame
is the arm's base frame. Sign: MuJoCo's force/torque sensors read the wrench the
parent body exerts on the measured subtree (site frame, torque about the site
origin); ftkin's raw reading is the load on the sensor, its negative.
"""

from __future__ import annotations

import numpy as np

from ...calibration.model import SensorModel
from ...kinematics.arm import Arm
from .tool_inertia import ToolInertia


class ArmSimulation:
    """A compiled MuJoCo model of the arm and its scene, with ftkin-side accessors.

    Build it with :func:`build_arm_model`. Attributes: ``model`` (``MjModel``),
    ``data`` (``MjData``), ``arm`` (the ftkin :class:`~ftkin.kinematics.arm.Arm`),
    ``sensor_site_id``, ``force_sensor_id``, ``torque_sensor_id``,
    ``object_body_id`` (or -1), ``tool_body_id`` (the tool link's body, else the measured one),
    ``surfaces`` (name → :class:`Surface`),
    ``surface_under`` (the pad below the object), ``base_tilt`` [rad], ``g`` [m/s²].
    """

    def __init__(
        self,
        mujoco,
        model,
        arm: Arm,
        q0: np.ndarray,
        surfaces: dict,
        surface_under: str | None,
        base_tilt: tuple[float, float],
        g: float,
    ):
        self.mujoco, self.model, self.arm = mujoco, model, arm
        self.data = mujoco.MjData(model)
        name_id = lambda kind, name: mujoco.mj_name2id(model, kind, name)
        self.sensor_site_id = name_id(mujoco.mjtObj.mjOBJ_SITE, "ftkin_sensor")
        self.force_sensor_id = name_id(mujoco.mjtObj.mjOBJ_SENSOR, "ftkin_force")
        self.torque_sensor_id = name_id(mujoco.mjtObj.mjOBJ_SENSOR, "ftkin_torque")
        self._force_adr = int(model.sensor_adr[self.force_sensor_id])
        self._torque_adr = int(model.sensor_adr[self.torque_sensor_id])
        self.object_body_id = name_id(mujoco.mjtObj.mjOBJ_BODY, "ftkin_object")
        tool = name_id(mujoco.mjtObj.mjOBJ_BODY, arm.tool_frame) if arm.tool_frame else -1
        self.tool_body_id = tool if tool >= 0 else int(model.site_bodyid[self.sensor_site_id])
        self.surfaces, self.surface_under = surfaces, surface_under
        self._pad_qpos = {
            name: int(model.jnt_qposadr[name_id(mujoco.mjtObj.mjOBJ_JOINT, f"{name}_pad")])
            for name in surfaces
        }
        self._arm_qpos = np.array(
            [model.jnt_qposadr[name_id(mujoco.mjtObj.mjOBJ_JOINT, n)] for n in arm.joint_names]
        )
        self._arm_dof = np.array(
            [model.jnt_dofadr[name_id(mujoco.mjtObj.mjOBJ_JOINT, n)] for n in arm.joint_names]
        )
        self.base_tilt, self.g = base_tilt, g
        self.q0 = q0
        # contiguous addresses (the usual case) read as one slice: cheaper than fancy indexing per
        # tick
        self._q_index = _as_slice(self._arm_qpos)
        self._dq_index = _as_slice(self._arm_dof)
        adr = (self._force_adr, self._torque_adr)
        self._wrench_index = (
            slice(adr[0], adr[0] + 6)
            if adr[1] == adr[0] + 3
            else np.r_[adr[0] : adr[0] + 3, adr[1] : adr[1] + 3]
        )
        self._substeps: dict[float, int] = {}
        self._contact_force = np.zeros(6)
        self.reset()

    # --------------------------------------------------------------- state
    def reset(self, q=None) -> None:
        """Arm in static equilibrium at ``q`` [rad] (default: the build pose), pads at rest.

        Each servo's target is offset from ``q`` by the sag that balances the
        load it holds (``τ / kp``, ``τ`` from MuJoCo's inverse dynamics at rest),
        so the run starts without a transient, as a robot standing still does.
        """
        mujoco, model, data = self.mujoco, self.model, self.data
        q = self.q0 if q is None else self.arm.check_configuration(q)
        mujoco.mj_resetData(model, data)
        data.qpos[self._arm_qpos] = q
        mujoco.mj_inverse(model, data)
        data.act[:] = q + data.qfrc_inverse[self._arm_dof] / model.actuator_gainprm[: len(q), 0]
        data.ctrl[:] = 0.0
        mujoco.mj_forward(model, data)

    @property
    def q(self) -> np.ndarray:
        """Joint positions [rad] in the arm's ``q`` order (copy)."""
        return self.data.qpos[self._q_index].copy()

    @property
    def dq(self) -> np.ndarray:
        """Joint velocities [rad/s] (copy)."""
        return self.data.qvel[self._dq_index].copy()

    def step(self, dq_command, duration: float) -> None:
        """Command joint velocities [rad/s] (speedJ-like) and advance the physics by ``duration``
        [s].
        """
        self.data.ctrl[:] = dq_command
        substeps = self._substeps.get(duration)
        if substeps is None:
            substeps = self._substeps[duration] = max(
                1, int(round(duration / self.model.opt.timestep))
            )
        self.mujoco.mj_step(self.model, self.data, substeps)

    # ------------------------------------------------------------- readings
    def ideal_wrench_in_sensor(self) -> np.ndarray:
        """Load on the sensor ``(6,)`` [N, N·m], sensor frame, ftkin's sign (``-`` MuJoCo's
        sensors), no bias or noise.
        """
        return -self.data.sensordata[self._wrench_index]

    def sensor_rotation(self) -> np.ndarray:
        """``R_BS`` ``(3, 3)`` of the sensor site (base = MuJoCo world)."""
        return self.data.site_xmat[self.sensor_site_id].reshape(3, 3).copy()

    def sensor_origin(self) -> np.ndarray:
        """Sensor origin in the base frame [m]."""
        return self.data.site_xpos[self.sensor_site_id].copy()

    def surface_depth(self, name: str | None = None) -> float:
        """How far the pad ``name`` (default: the one below the object) is pressed down [m]."""
        name = self.surface_under if name is None else name
        return -float(self.data.qpos[self._pad_qpos[name]])

    def normal_force(self) -> float:
        """Total normal force [N] of the contacts between the object and the pads.

        The scene lets nothing else collide (:func:`~ftkin.sim.mujoco.build_arm_model`),
        so every contact is one of them: no walk through the contact list's
        geometry ids. Like the sensor, it is MuJoCo's value at the start of the
        last integration step.
        """
        total, force, model, data = 0.0, self._contact_force, self.model, self.data
        for i in range(data.ncon):
            self.mujoco.mj_contactForce(model, data, i, force)
            total += force[0]
        return total

    # ------------------------------------------------------------ the truth
    def tool_inertia(self) -> ToolInertia:
        """Mass, COM and inertia of the measured subtree without the object, in the sensor frame
        (from MuJoCo).
        """
        model, data = self.model, self.data
        site_body = int(model.site_bodyid[self.sensor_site_id])
        bodies = [
            b
            for b in range(model.nbody)
            if _in_subtree(model, b, site_body)
            and not (self.object_body_id >= 0 and _in_subtree(model, b, self.object_body_id))
        ]
        rotation, origin = self.sensor_rotation(), self.sensor_origin()
        masses = np.array([model.body_mass[b] for b in bodies])
        centers = np.array([rotation.T @ (data.xipos[b] - origin) for b in bodies])
        mass = float(masses.sum())
        com = masses @ centers / mass
        inertia = np.zeros((3, 3))
        for b, m, c in zip(bodies, masses, centers):
            frame = rotation.T @ data.ximat[b].reshape(3, 3)
            inertia += frame @ np.diag(model.body_inertia[b]) @ frame.T
            d = c - com
            inertia += m * (float(d @ d) * np.eye(3) - np.outer(d, d))
        return ToolInertia(mass, com, inertia)

    def tool_sensor_model(self, bias=(0.0,) * 6) -> SensorModel:
        """ftkin's :class:`SensorModel` of this tool: its mass and COM from the model, this gravity
        and tilt, ``bias`` [N, N·m].
        """
        tool = self.tool_inertia()
        bias = np.asarray(bias, dtype=float)
        return SensorModel.from_tool(
            tool.mass, tool.center_of_mass, bias[:3], bias[3:], self.base_tilt, self.g
        )


def _as_slice(indices: np.ndarray):
    """``indices`` as a slice when they run consecutively, else unchanged."""
    start = int(indices[0])
    return (
        slice(start, start + len(indices))
        if np.array_equal(indices, np.arange(start, start + len(indices)))
        else indices
    )


def _in_subtree(model, body: int, root: int) -> bool:
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return root == 0
