"""Ground-truth wrench recordings along a prescribed motion, from MuJoCo.

MuJoCo is an engine independent of Pinocchio, so its inverse dynamics checks
ftkin's regressor and supplies the truth of the dynamic calibration tests and
``benchmarks/bench_dynamic.py``. :class:`MujocoRecorder` builds a model from a
URDF with the fixed links kept as bodies (``fusestatic = False``), optionally
replaces the inertia of the body carried by the sensor by a known load, puts
force and torque sensors on a site at the sensor frame, and for prescribed
``q, dq, ddq`` calls ``mj_inverse``: the sensors then read the wrench the
sensor body exerts on the load's subtree. ftkin's raw reading is the load on
the sensor, i.e. minus that.

This is deliberately small: the full MuJoCo model of the arm with its scene and
the closed loop is :func:`~ftkin.sim.mujoco.model.build_arm_model`; this module only records.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from ...calibration.model import STANDARD_GRAVITY
from ...exceptions import InvalidInput
from ...kinematics.arm import bundled_urdf_path
from ...kinematics.rotations import gravity_in_base_from_tilt
from ...validation import as_batch, as_positive, as_vector
from .model import add_wrench_sensor, import_mujoco
from .tool_inertia import ToolInertia


class MujocoRecorder:
    """Wrench readings of a wrist sensor from MuJoCo inverse dynamics at prescribed motions.

    Args:
        urdf: The arm's URDF (default: the bundled arm).
        joint_names: Joint names in ftkin's ``q`` order (MuJoCo's addresses are found by name).
        sensor_body: The body bolted to the sensor; its frame must be the sensor frame.
        tool: Replace ``sensor_body``'s inertia by this load (None keeps the URDF's).
        g: Acceleration of gravity [m/s²].
        base_tilt: Base tilt ``(U, V)`` [rad] (``R_WB = Rx(U) Ry(V)``): gravity in the base frame.
    """

    def __init__(
        self,
        urdf=None,
        joint_names=None,
        sensor_body: str = "gripper",
        tool: ToolInertia | None = None,
        g: float = STANDARD_GRAVITY,
        base_tilt=(0.0, 0.0),
    ):
        mujoco = import_mujoco("recording wrenches with MuJoCo (ftkin.sim.mujoco.recording)")
        self._mujoco = mujoco
        spec = mujoco.MjSpec.from_file(str(urdf if urdf is not None else bundled_urdf_path()))
        spec.compiler.fusestatic = False
        bodies = {body.name: body for body in spec.bodies}
        if sensor_body not in bodies:
            raise InvalidInput(
                f"no body {sensor_body!r} in the MuJoCo model; bodies: {', '.join(sorted(bodies))}"
            )
        body = bodies[sensor_body]
        if tool is not None:
            body.explicitinertial = True
            body.mass = tool.mass
            body.ipos = tool.center_of_mass
            body.iquat = [1.0, 0.0, 0.0, 0.0]
            inertia = tool.inertia_about_com
            body.fullinertia = [
                inertia[0, 0],
                inertia[1, 1],
                inertia[2, 2],
                inertia[0, 1],
                inertia[0, 2],
                inertia[1, 2],
            ]
        body.add_site(name="ftkin_sensor_site", pos=[0.0, 0.0, 0.0])
        add_wrench_sensor(mujoco, spec, "ftkin_sensor_site")
        self.model = spec.compile()
        self.model.opt.gravity[:] = gravity_in_base_from_tilt(
            as_positive(g, "g"), float(base_tilt[0]), float(base_tilt[1])
        )
        # Prescribed motion: no contacts (they would add forces where links overlap).
        self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        self.data = mujoco.MjData(self.model)
        self.sensor_body = sensor_body
        if joint_names is None:
            joint_names = [self.model.joint(i).name for i in range(self.model.njnt)]
        self.joint_names = list(joint_names)
        self._qpos = np.array([self.model.joint(name).qposadr[0] for name in self.joint_names])
        self._dof = np.array([self.model.joint(name).dofadr[0] for name in self.joint_names])
        self._site = self.model.site("ftkin_sensor_site").id
        self._body = self.model.body(sensor_body).id

    @property
    def nq(self) -> int:
        """Number of joints driven (ftkin's ``q`` length)."""
        return len(self.joint_names)

    def wrenches(
        self, joint_positions, joint_velocities=None, joint_accelerations=None
    ) -> np.ndarray:
        """ftkin raw readings ``(N, 6)`` [N, N·m] (load on the sensor, no bias, no noise) at ``(N,
        nq)`` ``q, dq, ddq``.

        Velocities and accelerations default to zero (static poses).
        """
        mujoco, model, data = self._mujoco, self.model, self.data
        q, _ = as_batch(joint_positions, self.nq, "joint positions q")
        dq = (
            np.zeros_like(q)
            if joint_velocities is None
            else as_batch(joint_velocities, self.nq, "dq")[0]
        )
        ddq = (
            np.zeros_like(q)
            if joint_accelerations is None
            else as_batch(joint_accelerations, self.nq, "ddq")[0]
        )
        if not (len(q) == len(dq) == len(ddq)):
            raise InvalidInput(
                f"q, dq and ddq must have the same number of rows, got {len(q)}, {len(dq)}, "
                f"{len(ddq)}"
            )
        out = np.empty((len(q), 6))
        for i in range(len(q)):
            data.qpos[self._qpos] = q[i]
            data.qvel[self._dof] = dq[i]
            data.qacc[self._dof] = ddq[i]
            mujoco.mj_inverse(model, data)
            out[i] = -data.sensordata[:6]
        return out

    def sensor_rotation(self, q) -> np.ndarray:
        """``R_BS`` ``(3, 3)`` of the sensor site at ``q`` (MuJoCo's forward kinematics)."""
        self.data.qpos[self._qpos] = as_vector(q, self.nq, "q")
        self._mujoco.mj_kinematics(self.model, self.data)
        return self.data.site_xmat[self._site].reshape(3, 3).copy()

    def true_parameters(self) -> np.ndarray:
        """θ (10,) of everything the sensor carries (``sensor_body``'s subtree), about the sensor
        origin, sensor axes.
        """
        mujoco, model, data = self._mujoco, self.model, self.data
        mujoco.mj_kinematics(model, data)
        site = pin.SE3(
            data.site_xmat[self._site].reshape(3, 3).copy(), data.site_xpos[self._site].copy()
        )
        total = pin.Inertia.Zero()
        for body in range(model.nbody):
            ancestor = body
            while ancestor not in (0, self._body):
                ancestor = model.body_parentid[ancestor]
            if ancestor != self._body or model.body_mass[body] == 0.0:
                continue
            # Body inertia: principal moments in the frame (xipos, ximat).
            principal = pin.Inertia(
                float(model.body_mass[body]), np.zeros(3), np.diag(model.body_inertia[body])
            )
            inertial_frame = pin.SE3(data.ximat[body].reshape(3, 3).copy(), data.xipos[body].copy())
            total += (site.actInv(inertial_frame)).act(principal)
        return np.asarray(total.toDynamicParameters(), dtype=float)
