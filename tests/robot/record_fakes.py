"""An arm moved by someone else, for ``ftkin record``'s tests: poses held and left on a schedule
driven by the reads (each read of the sensor is the next sample of a 1 kHz stream, and the
motion advances by one sample period with it), with a sensor (and its IMU) that reads a known
tool at the orientation of the moment. A busy machine that pauses the test sees the same
sequence of readings as an idle one: the motion does not run ahead while nobody reads.

The readings are written from first principles here, not with ftkin's model: gravity
``[0, 0, −g]`` in the base; the tool's weight on the sensor ``w = −m g R_BSᵀ e_z``; the reading
``[F0 + w, M0 + c × w]``; the accelerometer reads the specific force (``+g`` up) in its own axes,
``R_SIᵀ R_BSᵀ [0, 0, g]``, with a bias; the gyro the sensor's angular velocity in its axes.
While the arm moves the reading is the static one at the orientation of the moment (no inertia):
what tells motion apart is the joint speed, the gyro and the wrench changing.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from ftkin.exceptions import RobotConnectionLost
from ftkin.sensors.sample import SensorSample

G = 9.81
TOOL = {
    "mass": 1.2,  # [kg]
    "com": np.array([0.02, -0.01, 0.09]),  # [m], sensor frame
    "bias": np.array([1.5, -0.8, 2.2, 0.05, -0.03, 0.02]),  # [N, N·m]
}
NOISE = np.array([0.02] * 3 + [0.001] * 3)  # [N, N·m] per reading
IMU_ROTATION = Rotation.from_euler("z", 90.0, degrees=True).as_matrix()  # R_SI
ACCEL_BIAS = np.array([0.05, -0.03, 0.02])  # [m/s²]
ACCEL_NOISE, GYRO_NOISE = 0.01, 0.0005  # [m/s², rad/s]
RATE = 1000.0  # [Hz] of the simulated sensor


def reading(rotation_sensor_to_base: np.ndarray) -> np.ndarray:
    """The noise-free raw wrench ``(6,)`` of :data:`TOOL` at one orientation."""
    weight = -TOOL["mass"] * G * rotation_sensor_to_base.T @ np.array([0.0, 0.0, 1.0])
    return TOOL["bias"] + np.concatenate([weight, np.cross(TOOL["com"], weight)])


def spread_rotations(count: int, seed: int = 0) -> np.ndarray:
    """``(count, 3, 3)`` sensor orientations whose gravity directions are spread over the sphere
    (a Fibonacci set, each turned about the vertical by a seeded angle)."""
    rng = np.random.default_rng(seed)
    k = np.arange(count) + 0.5
    z = 1.0 - 2.0 * k / count
    angle = np.pi * (1.0 + np.sqrt(5.0)) * k
    down = np.stack([np.sqrt(1 - z * z) * np.cos(angle), np.sqrt(1 - z * z) * np.sin(angle), z], 1)
    rotations = []
    for d in down:  # R_BSᵀ [0, 0, −1] = d: the smallest turn, then a yaw about the vertical
        turn, _ = Rotation.align_vectors([[0.0, 0.0, -1.0]], [d])
        yaw = Rotation.from_euler("z", rng.uniform(-np.pi, np.pi))
        rotations.append((yaw * turn).as_matrix())
    return np.array(rotations)


class Schedule:
    """Pose ``k`` held for ``hold`` s, then ``move`` s of motion to pose ``k + 1``; the last one
    is held for ever. ``at(t)`` gives ``(k, s)``: the segment and its fraction (0 when held).

    Its clock is the sensor's: :meth:`advance` (one read of the sensor) moves it on by one
    sample period ``1 / RATE``; the wall clock plays no part. ``start`` is the host's clock at
    construction, the origin of the samples' stamps (as ftkin's adapters stamp on the host).
    """

    def __init__(self, count: int, hold: float, move: float, order=None):
        self.order = list(range(count)) if order is None else list(order)
        self.hold, self.move = float(hold), float(move)
        self.start = time.monotonic()
        self.reads = 0  # samples produced so far

    def at(self, t: float) -> tuple[int, int, float]:
        """``(from pose, to pose, fraction [0, 1))`` at ``t`` [s] since the start."""
        period = self.hold + self.move
        k = int(t // period)
        if k >= len(self.order) - 1:
            return self.order[-1], self.order[-1], 0.0
        phase = t - k * period
        fraction = 0.0 if phase < self.hold else (phase - self.hold) / self.move
        return self.order[k], self.order[k + 1], fraction

    def advance(self) -> float:
        """One sample later: the new time since the start [s]."""
        self.reads += 1
        return self.elapsed()

    def elapsed(self) -> float:
        """Time since the start [s]: the samples produced, one sample period each."""
        return self.reads / RATE


class ScriptedArm:
    """A joint source moved on a :class:`Schedule` through joint poses (linear in joint space).

    ``lost_after``: ``joint_state`` raises :class:`RobotConnectionLost` once that many seconds
    have passed on the schedule's clock (a controller gone). The state is that of the sensor's
    last sample (the clock moves with the sensor's reads).
    """

    def __init__(self, poses, schedule: Schedule, lost_after: float | None = None):
        self.poses, self.schedule, self.lost_after = np.asarray(poses, float), schedule, lost_after

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        a, b, s = self.schedule.at(t)
        step = self.poses[b] - self.poses[a]
        return self.poses[a] + s * step, (step / self.schedule.move if s > 0.0 else 0.0 * step)

    def joint_state(self):
        t = self.schedule.elapsed()
        if self.lost_after is not None and t > self.lost_after:
            raise RobotConnectionLost("no state from the scripted arm", "scripted")
        return self.at(t)


class ScriptedSensor:
    """The sensor on a scripted motion: ``read()``; with ``imu``, ``read_sample()`` too.

    Args:
        orientation: ``f(t) -> (R_BS (3, 3), ω (3,) [rad/s, sensor frame])`` at ``t`` [s].
        schedule: The motion's schedule (its clock).
        imu: Add the accelerometer, the gyro and a temperature.
        fault_after: From this many seconds on (the schedule's clock: samples read), every read
            raises (a sensor gone).
        seed: Seed of the noise.
        noise: ``(6,)`` standard deviation of the wrench noise [N, N·m].
    """

    def __init__(self, orientation, schedule, *, imu=False, fault_after=None, seed=0, noise=NOISE):
        self.orientation, self.schedule, self.fault_after = orientation, schedule, fault_after
        self.noise = np.asarray(noise, dtype=float)
        self.rng = np.random.default_rng(seed)
        self.samples: list[SensorSample] = []  # every sample produced, for the raw log's check
        if imu:
            self.read_sample = self._read_sample

    def _sample(self) -> SensorSample:
        t = self.schedule.advance()  # each read is the stream's next sample: the motion moves on
        if self.fault_after is not None and t > self.fault_after:
            raise OSError("the scripted sensor stopped answering")
        stamp = self.schedule.start + t
        rotation, omega = self.orientation(t)
        wrench = reading(rotation) + self.noise * self.rng.standard_normal(6)
        up_in_sensor = rotation.T @ np.array([0.0, 0.0, G])
        accel = IMU_ROTATION.T @ up_in_sensor + ACCEL_BIAS
        accel = accel + ACCEL_NOISE * self.rng.standard_normal(3)
        gyro = IMU_ROTATION.T @ omega + GYRO_NOISE * self.rng.standard_normal(3)
        sample = SensorSample(stamp, wrench, accel, gyro, 25.0 + 0.001 * stamp)
        self.samples.append(sample)
        return sample

    def read(self):
        sample = self._sample()
        return sample.t, sample.wrench

    def _read_sample(self) -> SensorSample:
        return self._sample()


def rotation_path(rotations: np.ndarray, schedule: Schedule):
    """``f(t) -> (R_BS, ω)`` along ``rotations`` on ``schedule`` (slerp while moving)."""

    def orientation(t: float):
        a, b, s = schedule.at(t)
        if a == b or s == 0.0:
            return rotations[a], np.zeros(3)
        pair = Rotation.from_matrix(rotations[[a, b]])
        turn = (pair[0].inv() * pair[1]).as_rotvec()  # sensor frame, over the move
        return Slerp([0.0, 1.0], pair)([s])[0].as_matrix(), turn / schedule.move

    return orientation


def joint_path(arm, scripted: ScriptedArm):
    """``f(t) -> (R_BS, ω)`` of a scripted arm's sensor frame (ω not needed without an IMU)."""

    def orientation(t: float):
        q, _ = scripted.at(t)
        return arm.rotation_sensor_to_base(q), np.zeros(3)

    return orientation


def scripted_imu(
    poses: str = "8", hold: str = "0.4", move: str = "0.2", seed: str = "0", fault_after: str = ""
):
    """A sensor factory for the CLI (``--sensor tests.robot.record_fakes:scripted_imu``): an IMU
    sensor carried through ``poses`` spread orientations, no joint source."""
    rotations = spread_rotations(int(poses), int(seed))
    schedule = Schedule(len(rotations), float(hold), float(move))
    return ScriptedSensor(
        rotation_path(rotations, schedule),
        schedule,
        imu=True,
        fault_after=float(fault_after) if fault_after else None,
        seed=int(seed),
    )
