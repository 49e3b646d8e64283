"""Kinematics of an arm carrying a wrist F/T sensor, on Pinocchio.

:class:`Arm` turns joint angles ``q`` [rad] into the sensor orientation
``R_BS`` (``rotation_sensor_to_base``) and frame Jacobians. The base frame B is
the URDF's root (Pinocchio's world frame).
"""

import logging
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..exceptions import FrameNotFound, InvalidInput, UrdfError
from ..validation import as_batch, as_vector
from .chain import RotationChain
from .urdf_loading import (
    build_geometry,
    build_model,
    joints_beyond_frame,
    lock_joints,
    sensor_frame_hint,
)

logger = logging.getLogger(__name__)

BUNDLED_URDF_NAME = "ftkin_c4.urdf"
_BATCH_MINIMUM = 16  # batches from this size use numpy kinematics (below: Pinocchio per row)
_REFERENCE_FRAMES = {
    "local_world_aligned": pin.ReferenceFrame.LOCAL_WORLD_ALIGNED,
    "local": pin.ReferenceFrame.LOCAL,
    "world": pin.ReferenceFrame.WORLD,
}


@dataclass(frozen=True)
class SensorMount:
    """Where to add a sensor frame when the URDF has none.

    Attributes:
        parent_frame: Existing frame (link) the sensor is bolted to, e.g. ``tool0``.
        translation: Sensor origin in the parent frame [m].
        rpy: Sensor orientation in the parent frame, roll-pitch-yaw [rad]
            (``R = Rz(yaw) Ry(pitch) Rx(roll)``, the URDF convention).
    """

    parent_frame: str
    translation: Sequence[float] = (0.0, 0.0, 0.0)
    rpy: Sequence[float] = (0.0, 0.0, 0.0)

    def placement(self) -> pin.SE3:
        """Sensor placement relative to the parent frame."""
        translation = as_vector(self.translation, 3, "sensor mount translation")
        rpy = as_vector(self.rpy, 3, "sensor mount rpy")
        return pin.SE3(pin.rpy.rpyToMatrix(*rpy), translation)


def add_sensor_frame(model: pin.Model, name: str, mount: SensorMount) -> None:
    """Add frame ``name`` at ``mount`` (relative to its parent frame) to ``model``, in place.

    Raises:
        InvalidInput: ``name`` exists already.
        FrameNotFound: the parent frame is not in the model.
    """
    if model.existFrame(name):
        raise InvalidInput(
            f"frame {name!r} already exists in the model; choose another sensor frame name"
        )
    if not model.existFrame(mount.parent_frame):
        raise FrameNotFound(mount.parent_frame, [frame.name for frame in model.frames])
    parent_id = model.getFrameId(mount.parent_frame)
    parent = model.frames[parent_id]
    placement = parent.placement * mount.placement()
    model.addFrame(
        pin.Frame(name, parent.parentJoint, parent_id, placement, pin.FrameType.OP_FRAME), False
    )


def bundled_urdf_path(relative: str = BUNDLED_URDF_NAME) -> Path:
    """Path of a bundled URDF, by default the six-axis arm (modelled on the EPSON C4-A901S).

    Looks in the installed package (``ftkin/urdf/``, wheels) and then in the
    source checkout (``urdf/`` beside the ``ftkin`` folder, editable installs).

    Args:
        relative: The file's path under ``urdf/`` (e.g. ``"fr3/fr3.urdf"``).
    """
    package_dir = Path(__file__).resolve().parent.parent
    for candidate in (package_dir / "urdf" / relative, package_dir.parent / "urdf" / relative):
        if candidate.is_file():
            return candidate
    raise UrdfError(relative, ["the bundled URDF is missing from this installation"])


def refuse_fixed_sensor_frame(model: pin.Model, sensor_frame: str) -> None:
    """Raise :class:`InvalidInput` when no joint moves ``sensor_frame`` (it is fixed to the base
    link): its orientation never changes, so no calibration or compensation can use it.
    """
    if model.frames[model.getFrameId(sensor_frame)].parentJoint == 0:
        turning = [  # the last joint that is not prismatic (a gripper's fingers are)
            i
            for i, joint in enumerate(model.joints)
            if i > 0 and not re.match(r"JointModel(P[XYZ]|PrismaticUnaligned)", joint.shortname())
        ]
        last = turning[-1] if turning else model.njoints - 1
        moving = [
            frame.name
            for frame in model.frames
            if frame.parentJoint == last and frame.type == pin.FrameType.BODY
        ]
        raise InvalidInput(
            f"the sensor frame {sensor_frame!r} is fixed to the base link: no joint moves it. "
            "Name a frame on the link the sensor is bolted to"
            + (f" (frames of the last link: {', '.join(moving[:6])})" if moving else "")
        )


class Arm:
    """A serial arm with a wrist F/T sensor frame (and optionally a tool frame).

    Attributes:
        model: Pinocchio model (kinematics only).
        sensor_frame: Name of the sensor frame.
        tool_frame: Name of the tool (control point) frame, or None.
        urdf_path: The URDF the model came from.
        joint_names: Names of the configuration's joints, in ``q`` order.
    """

    def __repr__(self) -> str:
        name = self.robot_name or (self.urdf_path.name if self.urdf_path is not None else "model")
        tool = f", tool frame {self.tool_frame!r}" if self.tool_frame else ""
        return f"Arm({name}: {self.nq} joints, sensor frame {self.sensor_frame!r}{tool})"

    def __init__(
        self,
        model: pin.Model,
        sensor_frame: str,
        tool_frame: str | None = None,
        urdf_path: Path | None = None,
        package_dirs: Sequence[str] = (),
        full_model: pin.Model | None = None,
        locked_joint_ids: Sequence[int] = (),
        reference_configuration: np.ndarray | None = None,
    ):
        if model.nq != model.nv:
            kinds = sorted({joint.shortname() for joint in model.joints if joint.nq != joint.nv})
            raise InvalidInput(
                "ftkin needs one coordinate per joint (revolute or prismatic); "
                f"this model has joints of kinds {kinds} (e.g. continuous): lock them or give them "
                "limits"
            )
        self.model, self.data, self.sensor_frame = model, model.createData(), sensor_frame
        try:
            self.sensor_frame_id = self.frame_id(sensor_frame)
        except FrameNotFound as error:
            raise FrameNotFound(error.name, error.available, sensor_frame_hint(model)) from None
        self.tool_frame = tool_frame
        self.tool_frame_id = self.frame_id(tool_frame) if tool_frame is not None else None
        self.urdf_path, self.package_dirs = urdf_path, list(package_dirs)
        # what geometry() needs to reduce the URDF's geometry like the model (locked joints)
        self._full_model, self._locked_joint_ids = full_model, list(locked_joint_ids)
        self._reference_configuration = reference_configuration
        self.joint_names = [model.names[i] for i in range(1, model.njoints)]
        self.sensor_mount: SensorMount | None = None  # set by from_urdf when it added the frame
        self.robot_name: str | None = None  # set by load_robot
        self.mount_rotation: np.ndarray | None = None  # R_M, set by mounting.mounted_arm
        self._geometry: dict[str, pin.GeometryModel] = {}
        self._chain: RotationChain | None | bool = False  # False: not built yet

    # ----------------------------------------------------------------- loading
    @classmethod
    def from_urdf(
        cls,
        path,
        sensor_frame: str = "ft_sensor",
        tool_frame: str | None = None,
        *,
        sensor_mount: SensorMount | None = None,
        package_dirs: Sequence[str] = (),
        locked_joints: Mapping[str, float] | None = None,
    ) -> "Arm":
        """Load any URDF.

        Args:
            path: URDF file.
            sensor_frame: Frame of the sensor's measuring origin and axes.
            tool_frame: Optional control-point frame (e.g. the gripper tip).
            sensor_mount: Add ``sensor_frame`` at this offset from an existing
                frame (for URDFs without a sensor frame).
            package_dirs: Folders that ``package://`` mesh URIs resolve against.
            locked_joints: Joints to fix at a value [rad or m] (e.g. gripper
                fingers), removed from ``q``. None (default): the joints that do not
                move the sensor frame (a gripper's fingers) are locked at their
                neutral value (clipped to the limits) and a log line says so; ``{}``
                keeps every joint.

        Raises:
            UrdfError: the file is missing or Pinocchio refuses it (with the reason).
            FrameNotFound: a frame name is not in the model (lists the frames).
        """
        path = Path(path)
        model = build_model(path)
        if sensor_mount is not None:
            add_sensor_frame(model, sensor_frame, sensor_mount)
        if model.existFrame(sensor_frame):
            refuse_fixed_sensor_frame(model, sensor_frame)
        if locked_joints is None:
            locked_joints = joints_beyond_frame(model, sensor_frame)
            if locked_joints:
                logger.info(
                    "%s: kept the %d joints between the base and the sensor frame %r; locked %s "
                    "(locked_joints={} keeps them)",
                    path.name,
                    model.njoints - 1 - len(locked_joints),
                    sensor_frame,
                    ", ".join(f"{name} at {value:g}" for name, value in locked_joints.items()),
                )
        locked = lock_joints(model, locked_joints) if locked_joints else (model,)
        arm = cls(locked[0], sensor_frame, tool_frame, path.resolve(), package_dirs, *locked[1:])
        arm.sensor_mount = sensor_mount
        return arm

    @classmethod
    def default(cls, tool_frame: str | None = "tool") -> "Arm":
        """The bundled six-axis arm (the robot ``ftkin_c4``), sensor frame ``ft_sensor``, tool
        frame ``tool``."""
        arm = cls.from_urdf(bundled_urdf_path(), "ft_sensor", tool_frame)
        arm.robot_name = "ftkin_c4"
        return arm

    # ------------------------------------------------------------ properties
    @property
    def nq(self) -> int:
        """Number of joint coordinates."""
        return self.model.nq

    @property
    def lower_limits(self) -> np.ndarray:
        """Lower joint position limits [rad or m]."""
        return self.model.lowerPositionLimit.copy()

    @property
    def upper_limits(self) -> np.ndarray:
        """Upper joint position limits [rad or m]."""
        return self.model.upperPositionLimit.copy()

    @property
    def velocity_limits(self) -> np.ndarray:
        """Joint velocity limits [rad/s or m/s]."""
        return self.model.velocityLimit.copy()

    @property
    def frame_names(self) -> list[str]:
        """Names of all frames in the model."""
        return [frame.name for frame in self.model.frames]

    def frame_id(self, name: str) -> int:
        """Index of a frame; raises :class:`FrameNotFound` listing the frames."""
        if not isinstance(name, str) or not self.model.existFrame(name):
            raise FrameNotFound(str(name), self.frame_names)
        return self.model.getFrameId(name)

    def _resolve_frame(self, frame: str) -> int:
        if frame == "sensor":
            return self.sensor_frame_id
        if frame == "tool":
            if self.tool_frame_id is None:
                raise InvalidInput("this Arm has no tool frame: pass tool_frame= when loading it")
            return self.tool_frame_id
        return self.frame_id(frame)

    def check_configuration(self, q) -> np.ndarray:
        """A finite ``(nq,)`` joint vector or :class:`InvalidInput`."""
        return as_vector(q, self.nq, f"joint positions q (joints {', '.join(self.joint_names)})")

    # ------------------------------------------------------------ kinematics
    def sensor_rotation_unchecked(self, q: np.ndarray) -> np.ndarray:
        """``R_BS`` for a validated ``(nq,)`` float array (the control-loop path)."""
        pin.forwardKinematics(self.model, self.data, q)
        return pin.updateFramePlacement(self.model, self.data, self.sensor_frame_id).rotation

    def rotation_sensor_to_base(self, q) -> np.ndarray:
        """Sensor orientation ``R_BS`` for ``q`` ``(nq,)`` → ``(3, 3)`` or ``(N, nq)`` → ``(N, 3,
        3)``.

        Batches of revolute/prismatic chains: :class:`~ftkin.kinematics.chain.RotationChain`
        (numpy).
        """
        configurations, single = as_batch(q, self.nq, "joint positions q")
        out = self.rotations_unchecked(configurations)
        return out[0] if single else out

    def rotations_unchecked(self, configurations: np.ndarray) -> np.ndarray:
        """``R_BS`` ``(N, 3, 3)`` for validated ``(N, nq)`` float joint positions."""
        if len(configurations) >= _BATCH_MINIMUM and self._sensor_chain() is not None:
            return self._chain.rotations(configurations)
        rotations = [self.sensor_rotation_unchecked(q).copy() for q in configurations]
        return np.array(rotations).reshape(-1, 3, 3)

    def vectors_in_sensor_unchecked(
        self, configurations: np.ndarray, vector_in_base: np.ndarray
    ) -> np.ndarray:
        """``R_BS(q)ᵀ v`` ``(N, 3)``: a base-frame vector in the sensor frame, for validated ``(N,
        nq)`` angles.
        """
        if len(configurations) >= _BATCH_MINIMUM and self._sensor_chain() is not None:
            return self._chain.transposed_times(configurations, vector_in_base)
        return np.einsum("nji,j->ni", self.rotations_unchecked(configurations), vector_in_base)

    def _sensor_chain(self) -> RotationChain | None:
        if self._chain is False:  # built on first use; None: not a revolute/prismatic chain
            self._chain = RotationChain.from_model(self.model, self.sensor_frame_id)
        return self._chain

    def frame_placement(self, q, frame: str = "sensor") -> tuple[np.ndarray, np.ndarray]:
        """Rotation ``(3, 3)`` (frame to base) and position ``(3,)`` [m] of a frame in the base
        frame.

        ``frame`` is ``"sensor"``, ``"tool"`` or any frame name of the model.
        """
        frame_id = self._resolve_frame(frame)
        pin.forwardKinematics(self.model, self.data, self.check_configuration(q))
        placement = pin.updateFramePlacement(self.model, self.data, frame_id)
        return placement.rotation.copy(), placement.translation.copy()

    def jacobian(
        self, q, frame: str = "sensor", reference: str = "local_world_aligned"
    ) -> np.ndarray:
        """Frame Jacobian ``(6, nq)``: ``[v; ω] = J dq``.

        Args:
            q: Joint positions ``(nq,)`` [rad].
            frame: ``"sensor"``, ``"tool"`` or a frame name.
            reference: ``"local_world_aligned"`` (default: the frame origin's
                linear velocity and the angular velocity, both in base axes),
                ``"local"`` (both in the frame's own axes) or ``"world"``.
        """
        if reference not in _REFERENCE_FRAMES:
            raise InvalidInput(
                f"reference must be one of {sorted(_REFERENCE_FRAMES)}, got {reference!r}"
            )
        frame_id = self._resolve_frame(frame)
        return pin.computeFrameJacobian(
            self.model,
            self.data,
            self.check_configuration(q),
            frame_id,
            _REFERENCE_FRAMES[reference],
        )

    def random_configurations(
        self, count: int, rng: np.random.Generator, margin: float = 0.0
    ) -> np.ndarray:
        """Uniform random configurations within the joint limits shrunk by ``margin`` [rad]."""
        return rng.uniform(self.lower_limits + margin, self.upper_limits - margin, (count, self.nq))

    # -------------------------------------------------------------- geometry
    def geometry(self, kind: str = "collision") -> pin.GeometryModel:
        """Collision or visual geometry from the URDF (built once, cached).

        Raises:
            UrdfError: a mesh file is missing or unreadable.
        """
        if kind not in ("collision", "visual"):
            raise InvalidInput(f"kind must be 'collision' or 'visual', got {kind!r}")
        if kind not in self._geometry:
            if self.urdf_path is None:
                raise InvalidInput("this Arm was not loaded from a URDF file: no geometry")
            full = self._full_model
            geometry = build_geometry(
                self.model if full is None else full, self.urdf_path, kind, self.package_dirs
            )
            if full is not None:
                _, geometry = pin.buildReducedModel(
                    full, geometry, self._locked_joint_ids, self._reference_configuration
                )
            self._geometry[kind] = geometry
        return self._geometry[kind]
