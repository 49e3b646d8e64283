"""A wrist sensor's IMU in MuJoCo: accelerometer and gyro readings beside the wrench.

:class:`MujocoImuRecorder` is a :class:`~ftkin.sim.mujoco.recording.MujocoRecorder` with
MuJoCo's own ``mjSENS_ACCELEROMETER`` and ``mjSENS_GYRO`` on a site of the sensor body, turned by
``R_SI`` and offset by ``r`` from the sensor origin. MuJoCo's accelerometer reads the specific
force (``+g`` upward at rest) in the site frame, its gyro the angular velocity in the site frame:
an engine independent of ftkin's IMU model (:mod:`ftkin.calibration.imu_model`), for the tests
and ``benchmarks/bench_imu.py``. Bias, scale and noise are the caller's to add.
"""

import numpy as np

from ...exceptions import InvalidInput
from ...kinematics.rotations import matrix_to_quaternion
from ...validation import as_batch, as_rotation_batch, as_vector
from .recording import MujocoRecorder


class MujocoImuRecorder(MujocoRecorder):
    """Wrench, specific force and angular velocity from MuJoCo inverse dynamics.

    Args:
        imu_rotation: ``R_SI`` ``(3, 3)``: the IMU's axes in the sensor frame.
        imu_position: ``r`` ``(3,)`` [m]: the IMU's origin in the sensor frame.
        **recorder: The arguments of :class:`~ftkin.sim.mujoco.recording.MujocoRecorder`
            (``urdf``, ``joint_names``, ``sensor_body``, ``tool``, ``g``, ``base_tilt``).
    """

    def __init__(self, imu_rotation=None, imu_position=(0.0, 0.0, 0.0), **recorder):
        rotation = np.eye(3) if imu_rotation is None else as_rotation_batch(imu_rotation)[0]
        if len(rotation) != 1:
            raise InvalidInput("imu_rotation must be one (3, 3) rotation")
        self.imu_rotation = rotation[0]
        self.imu_position = as_vector(imu_position, 3, "imu_position [m]")
        super().__init__(**recorder)

    def _add_sensors(self, mujoco, spec, body) -> None:
        body.add_site(
            name="ftkin_imu_site",
            pos=self.imu_position.tolist(),
            quat=matrix_to_quaternion(self.imu_rotation).tolist(),
        )
        for name, kind in (
            ("ftkin_accelerometer", mujoco.mjtSensor.mjSENS_ACCELEROMETER),
            ("ftkin_gyro", mujoco.mjtSensor.mjSENS_GYRO),
        ):
            spec.add_sensor(
                name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname="ftkin_imu_site"
            )

    def readings(self, joint_positions, joint_velocities=None, joint_accelerations=None):
        """``(wrenches (N, 6), specific_force (N, 3), angular_velocity (N, 3))`` at ``(N, nq)``
        ``q, dq, ddq``: the load on the sensor [N, N·m], the accelerometer [m/s², IMU frame] and
        the gyro [rad/s, IMU frame], ideal (no bias, no noise).
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
        out = np.empty((len(q), 12))
        for i in range(len(q)):
            data.qpos[self._qpos] = q[i]
            data.qvel[self._dof] = dq[i]
            data.qacc[self._dof] = ddq[i]
            mujoco.mj_inverse(model, data)
            out[i] = data.sensordata[:12]
        return -out[:, 0:6], out[:, 6:9].copy(), out[:, 9:12].copy()
