"""A load taken into the hand, and pushes on it, in MuJoCo inverse dynamics.

:class:`MujocoLoadRecorder` is a :class:`~ftkin.sim.mujoco.recording.MujocoRecorder` whose sensor
body carries a child body ``load`` (its centre of mass at ``load_position`` in the sensor frame:
``ipos`` set to zero, TOOLING.md "A grasped load as a child body"). Its mass is set per reading,
zero before a grasp and after a release, and an external wrench (a hand's push, a surface's
reaction) can act on it: MuJoCo's ``xfrc_applied``, at the load's centre of mass, base axes. The
sensor reads the subtree below its site, so it sees the load and the pushes through MuJoCo's own
dynamics: the truth the load tracker (:mod:`ftkin.control.load_events`) is checked against.
"""

import numpy as np

from ...exceptions import InvalidInput
from ...validation import as_batch, as_vector
from .recording import MujocoRecorder


class MujocoLoadRecorder(MujocoRecorder):
    """Wrench readings with a load of varying mass and external wrenches on it.

    Args:
        load_position: The load's centre of mass in the sensor frame [m].
        load_radius: Radius [m] of the solid sphere whose inertia the load gets (``2/5 m r²``).
        **recorder: The arguments of :class:`~ftkin.sim.mujoco.recording.MujocoRecorder`.
    """

    def __init__(self, load_position=(0.0, 0.0, 0.06), load_radius: float = 0.02, **recorder):
        self.load_position = as_vector(load_position, 3, "load_position [m]")
        if not (np.isfinite(load_radius) and load_radius > 0):
            raise InvalidInput(f"load_radius must be > 0 m, got {load_radius!r}")
        self.load_radius = float(load_radius)
        super().__init__(**recorder)
        self._load = self.model.body("ftkin_load").id
        self.set_load_mass(0.0)

    def _add_sensors(self, mujoco, spec, body) -> None:
        load = body.add_body(name="ftkin_load", pos=self.load_position.tolist())
        load.ipos = [0.0, 0.0, 0.0]  # else MuJoCo puts the COM at 2 × pos
        load.explicitinertial = True
        load.mass = 1.0
        load.fullinertia = [1e-4, 1e-4, 1e-4, 0.0, 0.0, 0.0]

    def set_load_mass(self, mass: float) -> None:
        """The load's mass [kg] from now on (0: nothing held)."""
        if not (np.isfinite(mass) and mass >= 0):
            raise InvalidInput(f"load mass must be ≥ 0 kg, got {mass!r}")
        self.model.body_mass[self._load] = mass
        self.model.body_inertia[self._load] = 0.4 * mass * self.load_radius**2

    def true_load(self, q) -> tuple[float, np.ndarray]:
        """``(mass [kg], COM (3,) [m, sensor frame])`` of the load at ``q``, from MuJoCo's data."""
        self.data.qpos[self._qpos] = as_vector(q, self.nq, "q")
        self._mujoco.mj_kinematics(self.model, self.data)
        rotation = self.data.site_xmat[self._site].reshape(3, 3)
        offset = self.data.xipos[self._load] - self.data.site_xpos[self._site]
        return float(self.model.body_mass[self._load]), rotation.T @ offset

    def readings(self, joint_positions, joint_velocities, joint_accelerations, masses, applied):
        """ftkin raw readings ``(N, 6)`` [N, N·m] (no bias, no noise) along a motion.

        Args:
            joint_positions, joint_velocities, joint_accelerations: ``(N, nq)`` [rad, rad/s,
                rad/s²].
            masses: ``(N,)`` the load's mass at each reading [kg].
            applied: ``(N, 6)`` external force and torque on the load at its COM, base axes [N,
                N·m] (a push: positive is what the environment exerts).
        """
        q, _ = as_batch(joint_positions, self.nq, "q")
        dq, _ = as_batch(joint_velocities, self.nq, "dq")
        ddq, _ = as_batch(joint_accelerations, self.nq, "ddq")
        masses = np.asarray(masses, dtype=float).reshape(-1)
        applied, _ = as_batch(applied, 6, "applied wrench")
        if not (len(q) == len(dq) == len(ddq) == len(masses) == len(applied)):
            raise InvalidInput("q, dq, ddq, masses and applied need one row per reading each")
        mujoco, model, data = self._mujoco, self.model, self.data
        out = np.empty((len(q), 6))
        for i in range(len(q)):
            self.set_load_mass(masses[i])
            data.qpos[self._qpos], data.qvel[self._dof], data.qacc[self._dof] = q[i], dq[i], ddq[i]
            data.xfrc_applied[self._load] = applied[i]
            mujoco.mj_inverse(model, data)
            out[i] = -data.sensordata[:6]
        data.xfrc_applied[self._load] = 0.0
        return out
