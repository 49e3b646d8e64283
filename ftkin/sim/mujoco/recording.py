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
the closed loop is :func:`~ftkin.sim.mujoco.arm_model.build_arm_model`; this module only records.
"""

import numpy as np

from ...calibration.model import STANDARD_GRAVITY, check_gravity
from ...exceptions import InvalidInput
from ...kinematics.arm import bundled_urdf_path
from ...kinematics.rotations import gravity_in_base_from_tilt
from ...validation import as_batch, as_vector
from .arm_model import add_wrench_sensor, import_mujoco, subtree_inertia
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
        self._mujoco = mujoco = import_mujoco(
            "recording wrenches with MuJoCo (ftkin.sim.mujoco.recording)"
        )
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
            # MuJoCo's order: Ixx, Iyy, Izz, Ixy, Ixz, Iyz
            body.fullinertia = tool.inertia_about_com[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]]
        body.add_site(name="ftkin_sensor_site", pos=[0.0, 0.0, 0.0])
        add_wrench_sensor(mujoco, spec, "ftkin_sensor_site")
        self._add_sensors(mujoco, spec, body)  # a subclass's own sensors (the IMU's)
        self.model = spec.compile()
        self.model.opt.gravity[:] = gravity_in_base_from_tilt(
            check_gravity(g), float(base_tilt[0]), float(base_tilt[1])
        )
        # Prescribed motion: no contacts (they would add forces where links overlap).
        self.model.opt.disableflags |= mujoco.mjtDisableBit.mjDSBL_CONTACT
        self.data = mujoco.MjData(self.model)
        self.sensor_body = sensor_body
        self.joint_names = list(
            [self.model.joint(i).name for i in range(self.model.njnt)]
            if joint_names is None
            else joint_names
        )
        self._qpos = np.array([self.model.joint(name).qposadr[0] for name in self.joint_names])
        self._dof = np.array([self.model.joint(name).dofadr[0] for name in self.joint_names])
        self._site = self.model.site("ftkin_sensor_site").id
        self._body = self.model.body(sensor_body).id

    def _add_sensors(self, mujoco, spec, body) -> None:
        """Add sensors to ``body`` of ``spec`` before it compiles (none here; see
        :mod:`ftkin.sim.mujoco.imu_recording`)."""

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
        dq, ddq = (
            np.zeros_like(q) if value is None else as_batch(value, self.nq, name)[0]
            for value, name in ((joint_velocities, "dq"), (joint_accelerations, "ddq"))
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
        self._mujoco.mj_kinematics(self.model, self.data)
        carried = subtree_inertia(self.model, self.data, self._site, self._body)
        return np.asarray(carried.toDynamicParameters(), dtype=float)
