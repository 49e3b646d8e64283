"""Example input files from the simulated sensor: samples, logs, recordings, bags.

Every file the CLI reads can be made here from known parameters, so a tour of
the docs (and a test) starts from files whose truth is known:

* :func:`samples_table`: a samples CSV (``pose``, ``t`` with a drift, the joint
  columns [rad], ``fx..mz`` [N, N·m]) at static poses, for ``ftkin calibrate``;
* :func:`log_table`: a log of a slow motion with a known push on the tool (the
  ``true_fx..true_mz`` columns), for ``ftkin compensate``;
* :func:`recording_table`: a moving recording (``t``, joints, ``fx..mz``) along
  an excitation trajectory, the wrench from MuJoCo's inverse dynamics
  (:class:`~ftkin.sim.mujoco.recording.MujocoRecorder`), for ``ftkin calibrate --dynamic``;
* :func:`write_bag`: a ROS 2 bag (``sensor_msgs/JointState`` and
  ``geometry_msgs/WrenchStamped``) of a session that holds each pose and moves
  to the next, for ``ftkin calibrate BAG`` and ``ftkin extract``.

The readings come from :class:`SimulatedInputs`: a :class:`~ftkin.sim.sensor.SimulatedSensor`
(bias, tool gravity, noise, optional drift) seen through an optional mount
rotation ``R_M`` (URDF sensor frame → real sensor frame, ``R_BS = R_BS_urdf R_Mᵀ``)
and an optional reversed sign (the sensor reports the reaction).
"""

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..calibration.information import SensorNoise
from ..calibration.model import WRENCH_CHANNELS, SensorModel
from ..exceptions import InvalidInput, MissingDependency
from ..validation import as_batch, as_rotation_batch
from .sensor import SimulatedSensor, paper_like_truth, recording_times
from .sensor_drift import SensorDrift

PUSH = np.array([0.0, 0.0, 2.0, 0.0, 0.05, 0.0])
"""The known push of :func:`log_table`: the environment on the tool, sensor frame [N, N·m]."""


@dataclass(frozen=True)
class SimulatedInputs:
    """What the example files are simulated from.

    Attributes:
        truth: Bias, tool and base tilt (real sensor frame).
        noise: Per-reading noise of each channel.
        drift: How the bias moves after power-on at ``t = 0`` (None: it does not).
        mount_rotation: ``R_M`` ``(3, 3)``: URDF sensor frame → real sensor frame.
        sign: ``+1``, or ``-1`` for a sensor that reports the reaction.
    """

    truth: SensorModel = field(default_factory=paper_like_truth)
    noise: SensorNoise = field(default_factory=SensorNoise.paper)
    drift: SensorDrift | None = None
    mount_rotation: np.ndarray = field(default_factory=lambda: np.eye(3))
    sign: float = 1.0

    def __post_init__(self):
        if np.shape(self.mount_rotation) != (3, 3):
            raise InvalidInput(
                "mount_rotation must be a (3, 3) rotation, got shape "
                f"{np.shape(self.mount_rotation)}"
            )
        rotations, _ = as_rotation_batch(self.mount_rotation, "mount_rotation")  # refuses mirrors
        if self.sign not in (1.0, -1.0):
            raise InvalidInput(f"sign must be +1 or -1, got {self.sign!r}")
        object.__setattr__(self, "mount_rotation", rotations[0])

    @property
    def sensor(self) -> SimulatedSensor:
        """The simulated sensor (in the real sensor frame)."""
        return SimulatedSensor(self.truth, self.noise, self.drift)

    def rotations(self, arm, configurations) -> np.ndarray:
        """Real ``R_BS`` ``(N, 3, 3)`` at joint angles ``(N, nq)`` [rad]."""
        return arm.rotation_sensor_to_base(configurations) @ self.mount_rotation.T

    def readings(self, arm, configurations, rng, times=None, contact=None) -> np.ndarray:
        """Reported raw readings ``(N, 6)`` [N, N·m] at joint angles ``(N, nq)`` [rad].

        ``times`` [s] drive the drift; ``contact`` ``(6,)`` or ``(N, 6)`` is the
        environment's wrench on the tool, real sensor frame [N, N·m].
        """
        rotations = self.rotations(arm, configurations)  # the arm checks the joint angles
        return self.sign * self.sensor.read(rotations, rng, contact, times)


def samples_table(
    inputs: SimulatedInputs,
    arm,
    configurations,
    rng: np.random.Generator,
    readings_per_pose: int = 10,
    pose_duration: float = 10.0,
) -> tuple[list[str], list[list]]:
    """Header and rows (``pose`` an int) of a samples CSV at static poses.

    Args:
        inputs: What the readings are simulated from.
        arm: The arm (joint columns named after its joints).
        configurations: ``(P, nq)`` joint angles of the poses [rad].
        rng: Random generator (seed it).
        readings_per_pose: Readings at each pose, 1 ms apart.
        pose_duration: Time from one pose to the next [s]; a ``t`` column [s]
            is written when ``inputs`` has a drift.
    """
    configurations, _ = as_batch(configurations, arm.nq, "joint positions q")
    count = len(configurations)
    repeated = np.repeat(configurations, readings_per_pose, axis=0)
    pose_ids = np.repeat(np.arange(count), readings_per_pose)
    drifts = inputs.drift is not None
    times = recording_times(count, readings_per_pose, count * pose_duration) if drifts else None
    wrenches = inputs.readings(arm, repeated, rng, times=times)
    header = ["pose", *(["t"] if drifts else []), *arm.joint_names, *WRENCH_CHANNELS]
    values = np.hstack([*([times[:, None]] if drifts else []), repeated, wrenches]).tolist()
    return header, [[int(pose), *row] for pose, row in zip(pose_ids, values)]


def _blend(start, end, fraction) -> np.ndarray:
    """Cosine blend ``(N, nq)`` from ``start`` to ``end`` (``(nq,)`` or ``(N, nq)``) at
    ``fraction`` ``(N,)``, clipped to [0, 1].
    """
    s = 0.5 - 0.5 * np.cos(np.pi * np.clip(fraction, 0.0, 1.0))
    return start + s[:, None] * (end - start)


def log_table(
    inputs: SimulatedInputs,
    arm,
    rng: np.random.Generator,
    duration: float = 5.0,
    rate: float = 200.0,
    push=PUSH,
) -> tuple[list[str], np.ndarray]:
    """Header and rows of a log: a slow move between two poses and a push in the middle.

    Columns ``t`` [s], the joints [rad], ``fx..mz`` (raw) [N, N·m] and
    ``true_fx..true_mz``: the contact wrench put in (``push`` from 40 % to 60 %
    of ``duration``, zero elsewhere), what ``ftkin compensate`` should recover.
    """
    if not (duration > 0 and rate > 0):
        raise InvalidInput(f"duration [s] and rate [Hz] must be > 0, got {duration}, {rate}")
    times = np.arange(0.0, duration, 1.0 / rate)
    start, end = arm.random_configurations(2, rng, margin=0.3)
    q = _blend(start, end, times / duration)
    inside = (times >= 0.4 * duration) & (times < 0.6 * duration)
    contact = np.where(inside[:, None], np.asarray(push, dtype=float)[None, :], 0.0)
    raw = inputs.readings(arm, q, rng, times=times, contact=contact)
    header = ["t", *arm.joint_names, *WRENCH_CHANNELS, *(f"true_{c}" for c in WRENCH_CHANNELS)]
    return header, np.hstack([times[:, None], q, raw, contact])


def recording_table(
    inputs: SimulatedInputs,
    arm,
    times,
    joint_positions,
    joint_velocities,
    joint_accelerations,
    rng: np.random.Generator,
    tool=None,
    sensor_body: str = "gripper",
) -> tuple[list[str], np.ndarray]:
    """Header and rows of a moving recording along a prescribed motion.

    The load on the sensor is MuJoCo's inverse dynamics of the arm's URDF with
    ``tool`` (a :class:`~ftkin.sim.mujoco.tool_inertia.ToolInertia`; None keeps
    the URDF's) as the body ``sensor_body`` bolted to the sensor, gravity tilted
    as ``inputs.truth``; the bias and noise of ``inputs`` are added (mount and
    sign too). Columns ``t``
    [s], the joints [rad], ``fx..mz`` [N, N·m].
    """
    from .mujoco.recording import MujocoRecorder

    times = np.asarray(times, dtype=float).reshape(-1)
    q, _ = as_batch(joint_positions, arm.nq, "joint positions q")
    if arm.urdf_path is None:
        raise InvalidInput("a MuJoCo recording needs an arm loaded from a URDF file")
    load = MujocoRecorder(
        arm.urdf_path,
        joint_names=arm.joint_names,
        sensor_body=sensor_body,
        tool=tool,
        g=inputs.truth.g,
        base_tilt=inputs.truth.base_tilt,
    ).wrenches(q, joint_velocities, joint_accelerations)
    load = (load.reshape(-1, 2, 3) @ inputs.mount_rotation.T).reshape(-1, 6)  # real sensor axes
    raw = (
        load
        + inputs.truth.bias
        + inputs.sensor.bias_drift(times, rng)  # the bias after power-on at t = 0
        + rng.standard_normal(load.shape) * inputs.noise.channel_std
    )
    return ["t", *arm.joint_names, *WRENCH_CHANNELS], np.hstack(
        [times[:, None], q, inputs.sign * raw]
    )


@dataclass(frozen=True)
class BagSession:
    """Timing of a simulated session: hold each pose, then move to the next.

    Attributes:
        hold: Time still at each pose [s].
        move: Time moving to the next [s].
        joint_rate: Joint-state rate [Hz].
        wrench_rate: Wrench rate [Hz].
        start: Stamp of the first message [s since the epoch].
    """

    hold: float = 2.0
    move: float = 1.0
    joint_rate: float = 50.0
    wrench_rate: float = 200.0
    start: float = 1_700_000_000.0

    def positions(self, configurations: np.ndarray, times: np.ndarray) -> np.ndarray:
        """Joint angles ``(N, nq)`` [rad] at ``times`` [s since the start]."""
        period = self.hold + self.move
        index = np.clip((times // period).astype(int), 0, len(configurations) - 1)
        phase = (times - index * period - self.hold) / self.move  # <= 0 while holding
        following = np.minimum(index + 1, len(configurations) - 1)
        return _blend(configurations[index], configurations[following], phase)


def write_bag(
    path,
    inputs: SimulatedInputs,
    arm,
    configurations,
    rng: np.random.Generator,
    session: BagSession | None = None,
    wrench_topic: str = "/ft_sensor/wrench",
    joint_topic: str = "/joint_states",
) -> Path:
    """Write a rosbag2 folder (MCAP storage) of a session visiting ``configurations``.

    Joint states and wrenches have their own rates and header stamps; the
    wrench's ``frame_id`` is the arm's sensor frame. The folder must not exist.
    """
    try:
        from rosbags.rosbag2 import StoragePlugin, Writer
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise MissingDependency("rosbags", "bags", "writing a ROS 2 bag") from None
    session = session or BagSession()
    configurations, _ = as_batch(configurations, arm.nq, "joint positions q")
    path = Path(path)
    if path.exists():
        raise InvalidInput(f"{path} exists; a bag is written to a new folder")
    duration = len(configurations) * (session.hold + session.move) - session.move
    joint_times = np.arange(0.0, duration, 1.0 / session.joint_rate)
    wrench_times = np.arange(0.0, duration, 1.0 / session.wrench_rate)
    wrenches = inputs.readings(arm, session.positions(configurations, wrench_times), rng)
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    types = typestore.types
    vector = types["geometry_msgs/msg/Vector3"]
    joint_fields = (
        {
            "name": list(arm.joint_names),
            "position": q,
            "velocity": np.zeros(0),
            "effort": np.zeros(0),
        }
        for q in session.positions(configurations, joint_times)
    )
    wrench_fields = (
        {"wrench": types["geometry_msgs/msg/Wrench"](force=vector(*w[:3]), torque=vector(*w[3:]))}
        for w in wrenches
    )
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        for topic, kind, times, frame_id, messages in (
            (joint_topic, "sensor_msgs/msg/JointState", joint_times, "", joint_fields),
            (
                wrench_topic,
                "geometry_msgs/msg/WrenchStamped",
                wrench_times,
                arm.sensor_frame,
                wrench_fields,
            ),
        ):
            connection = writer.add_connection(topic, kind, typestore=typestore)
            for t, fields in zip(times, messages):
                stamp = int(round((session.start + t) * 1e9))  # [ns]
                time = types["builtin_interfaces/msg/Time"](
                    sec=stamp // 10**9, nanosec=stamp % 10**9
                )
                header = types["std_msgs/msg/Header"](stamp=time, frame_id=frame_id)
                message = types[kind](header=header, **fields)
                writer.write(connection, stamp, typestore.serialize_cdr(message, kind))
    return path
