"""A MuJoCo model of an ftkin arm: URDF in, arm + sensor + tool + object + table out.

:func:`build_arm_model` loads the arm's URDF into an ``MjSpec`` with
``fusestatic = False`` (fixed links stay bodies, so the sensor body and the
gripper are separate), adds

* a site at the sensor frame on the *measured body* (the body bolted to the
  sensor's measuring side, ``gripper`` on the bundled arm) carrying a force and
  a torque sensor;
* a grasped object (:class:`GraspedObject`, a box hanging below the tool point);
* a table with two spring-loaded pads, a sponge and a book
  (:class:`~ftkin.sim.surfaces.Surface`: stiffness [N/m] and damping [N·s/m]
  of a vertical slide joint), the chosen one right below the object;
* one ``intvelocity`` actuator per joint: the command is a joint velocity
  [rad/s], integrated into a position target tracked by a stiff PD servo, like
  a robot's speedJ interface;
* gravity tilted by the base tilt ``(U, V)``.

Sign: MuJoCo's sensors read the wrench the parent exerts on the measured
subtree, in the site frame; ftkin's raw reading is the load *on* the sensor,
its negative: :meth:`ArmSimulation.ideal_wrench_in_sensor` returns ``-sensordata``
(torque about the site origin).

:class:`ArmSimulation` is the compiled scene with ftkin-side accessors (state,
readings, the tool's truth).
"""

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ...calibration.model import STANDARD_GRAVITY, SensorModel
from ...exceptions import InvalidInput, MissingDependency
from ...kinematics.arm import Arm
from ...kinematics.rotations import gravity_in_base_from_tilt
from ..placement import Q_DOWN
from ..surfaces import BOOK, SPONGE, Surface
from .tool_inertia import ToolInertia

PAD_MASS = 0.2
"""Mass of a surface pad [kg] (gravity-compensated: it rests at its spring's zero)."""

PAD_SPACING = 0.15
"""Distance [m] along base y between the sponge and the book on the table."""


def import_mujoco(purpose: str = "simulating in MuJoCo"):
    """The ``mujoco`` module, or :class:`~ftkin.exceptions.MissingDependency` naming the ``sim``
    extra and ``purpose``.
    """
    try:
        import mujoco
    except ImportError:
        raise MissingDependency("mujoco", "sim", purpose) from None
    return mujoco


def add_wrench_sensor(mujoco, spec, site: str) -> None:
    """MuJoCo's force and torque sensors ``ftkin_force``, ``ftkin_torque`` at the site ``site``."""
    for name, kind in (
        ("ftkin_force", mujoco.mjtSensor.mjSENS_FORCE),
        ("ftkin_torque", mujoco.mjtSensor.mjSENS_TORQUE),
    ):
        spec.add_sensor(name=name, type=kind, objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)


def subtree_inertia(model, data, site: int, root: int, without: int = -1) -> pin.Inertia:
    """Inertia of body ``root``'s subtree (less body ``without``'s) about site ``site``, site axes.

    From MuJoCo's current kinematics (each body's principal inertia at ``xipos``, ``ximat``).
    """
    site_pose = pin.SE3(data.site_xmat[site].reshape(3, 3).copy(), data.site_xpos[site].copy())
    total = pin.Inertia.Zero()
    for body in range(model.nbody):
        inside = _in_subtree(model, body, root) and not _in_subtree(model, body, without)
        if inside and model.body_mass[body] > 0.0:
            principal = pin.Inertia(
                float(model.body_mass[body]), np.zeros(3), np.diag(model.body_inertia[body])
            )
            frame = pin.SE3(data.ximat[body].reshape(3, 3).copy(), data.xipos[body].copy())
            total += site_pose.actInv(frame).act(principal)
    return total


def _in_subtree(model, body: int, root: int) -> bool:  # never for root -1
    while body > 0:
        if body == root:
            return True
        body = int(model.body_parentid[body])
    return root == 0


@dataclass(frozen=True)
class GraspedObject:
    """A box held by the tool, hanging along the tool frame's z axis.

    Attributes:
        mass: [kg] (default: the paper's 2.214 N object).
        height: Box height [m]; its bottom is this far below the tool point.
        half_width: Half of its square footprint [m].
    """

    mass: float = 2.214 / STANDARD_GRAVITY
    height: float = 0.04
    half_width: float = 0.02

    def __post_init__(self):
        for name in ("mass", "height", "half_width"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise InvalidInput(
                    f"GraspedObject.{name} must be a finite number > 0, got {value!r}"
                )

    @property
    def weight(self) -> float:
        """Weight under standard gravity [N]."""
        return self.mass * STANDARD_GRAVITY


def build_arm_model(
    arm: Arm | None = None,
    *,
    measured_body: str | None = None,
    grasped_object: GraspedObject | None = None,
    surfaces: tuple[Surface, ...] = (SPONGE, BOOK),
    surface_under: str | None = "sponge",
    q0=None,
    start_gap: float = 0.002,
    base_tilt=(0.0, 0.0),
    g: float = STANDARD_GRAVITY,
    timestep: float = 5e-4,
    servo_bandwidth: float = 60.0,
) -> "ArmSimulation":
    """Build the MuJoCo scene of ``arm`` (default: the bundled arm with its ``tool`` frame).

    Args:
        arm: An ftkin arm loaded from a URDF (``arm.urdf_path``); its sensor frame must be a link.
        measured_body: The body whose subtree the sensor measures. Default: the only child link
            of the sensor link.
        grasped_object: The held object (None: nothing held). Attached to the tool frame's link
            (sensor link's child if no tool).
        surfaces: Pads on the table, spaced :data:`PAD_SPACING` along base y.
        surface_under: Name of the pad placed ``start_gap`` [m] below the object (or the tool
            point) at ``q0``; None: no table.
        q0: Start configuration [rad] (default :data:`~ftkin.sim.placement.Q_DOWN` for a 6-joint
            arm, else the zero configuration).
        start_gap: Air gap at the start [m].
        base_tilt: ``(U, V)`` [rad]: gravity in the base frame is ``g`` along
            ``[cosU sinV, -sinU, -cosU cosV]``.
        g: Gravity [m/s²].
        timestep: MuJoCo's integration step [s].
        servo_bandwidth: Natural frequency of each joint's position servo [Hz] (critically damped).

    Raises:
        InvalidInput: the arm has no URDF, its sensor frame is not a link, or the measured body
            is ambiguous.
        MissingDependency: ``mujoco`` is not installed (the ``sim`` extra).
    """
    mujoco = import_mujoco()
    arm = Arm.default() if arm is None else arm
    if arm.urdf_path is None:
        raise InvalidInput("build_arm_model needs an arm loaded from a URDF file (Arm.from_urdf)")
    if not (0 < timestep < math.inf and 0 < servo_bandwidth < math.inf):
        raise InvalidInput(
            f"timestep [s] and servo_bandwidth [Hz] must be > 0, got {timestep!r}, "
            f"{servo_bandwidth!r}"
        )
    default = Q_DOWN if arm.nq == 6 else np.zeros(arm.nq)
    q0 = arm.check_configuration(default if q0 is None else q0).copy()
    spec = mujoco.MjSpec.from_file(str(arm.urdf_path))
    spec.compiler.fusestatic = False
    bodies = {body.name: body for body in spec.bodies}
    measured = _measured_body(bodies, arm, measured_body)
    _add_sensor(mujoco, spec, bodies, measured)
    if grasped_object is not None:  # on the tool link (the measured body without a tool)
        holder = bodies.get(arm.tool_frame, measured) if arm.tool_frame else measured
        holder.add_body(name="ftkin_object", pos=[0.0, 0.0, grasped_object.height / 2]).add_geom(
            name="ftkin_object",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[grasped_object.half_width] * 2 + [grasped_object.height / 2],
            mass=grasped_object.mass,
            contype=1,
            conaffinity=0,
            rgba=[0.2, 0.5, 0.9, 1],
        )
    rotation, tool_point = arm.frame_placement(q0, "tool" if arm.tool_frame else "sensor")
    drop = grasped_object.height if grasped_object is not None else 0.0
    bottom = tool_point + rotation[:, 2] * drop  # of the object (or the tool point) at q0
    _add_table(mujoco, spec, surfaces, surface_under, bottom, start_gap, timestep)
    _add_servos(mujoco, spec, arm)
    spec.option.timestep = float(timestep)
    spec.option.integrator = (
        getattr(mujoco.mjtIntegrator, "mjINT_IMPLICITFAST", None)
        or mujoco.mjtIntegrator.mjINTEGRATOR_IMPLICITFAST
    )
    tilt = (float(base_tilt[0]), float(base_tilt[1]))
    spec.option.gravity = gravity_in_base_from_tilt(float(g), *tilt)
    sim = ArmSimulation(
        mujoco,
        spec.compile(),
        arm,
        q0,
        {surface.name: surface for surface in surfaces},
        surface_under if surfaces else None,
        tilt,
        float(g),
    )
    _tune_servos(sim, 2.0 * math.pi * servo_bandwidth)
    sim.reset()  # again: the equilibrium targets depend on the servo gains
    return sim


def _measured_body(bodies: dict, arm: Arm, name: str | None):
    """The body whose subtree the sensor measures: ``name``, else the sensor link's only child."""
    sensor = arm.sensor_frame
    if sensor not in bodies:
        raise InvalidInput(
            f"the sensor frame {sensor!r} is not a link of {arm.urdf_path.name}; MuJoCo "
            "needs a sensor link"
        )
    children = [
        body for body in bodies.values() if body.parent is not None and body.parent.name == sensor
    ]
    if name is None:
        if len(children) != 1:
            raise InvalidInput(
                f"the sensor link {sensor!r} has {len(children)} child links; name the measured "
                "one (measured_body=...)"
            )
        return children[0]
    if name not in bodies:
        raise InvalidInput(f"measured_body {name!r} is not a link; links: {sorted(bodies)}")
    if bodies[name] not in children:
        raise InvalidInput(
            f"measured_body {name!r} must be a child link of the sensor link {sensor!r}"
        )
    return bodies[name]


def _add_sensor(mujoco, spec, bodies: dict, measured) -> None:
    """Force and torque sensors on a site at the sensor frame; the arm weightless and contact-free.

    The arm collides with nothing (only the object touches the pads) and its own links are
    gravity-compensated (the robot controller's job; its servo would sag otherwise). The site
    sits at the measured body's parent frame (the sensor link's origin): its inverse pose.
    """
    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 0, 0
    for name, body in bodies.items():
        if name != "world" and not _is_descendant(body, measured):
            body.gravcomp = 1.0
    site_pos, site_quat = np.zeros(3), np.zeros(4)
    quat = np.asarray(measured.quat, dtype=float)
    mujoco.mju_negPose(
        site_pos, site_quat, np.asarray(measured.pos, dtype=float), quat / np.linalg.norm(quat)
    )
    measured.add_site(name="ftkin_sensor", pos=site_pos, quat=site_quat)
    add_wrench_sensor(mujoco, spec, "ftkin_sensor")


def _is_descendant(body, root) -> bool:
    while body is not None and body.name != "world":
        if body.name == root.name:
            return True
        body = body.parent
    return False


def _add_table(mujoco, spec, surfaces, surface_under, bottom: np.ndarray, start_gap, timestep):
    """The pads, ``surface_under`` ``start_gap`` [m] below ``bottom`` [m], on a table.

    Each pad (:data:`PAD_MASS`) rides a vertical slide joint whose spring and damper are the
    surface's ``k`` and ``c``; its contact is stiff.
    """
    names = [surface.name for surface in surfaces]
    if surface_under is not None and surface_under not in names:
        raise InvalidInput(f"surface_under must be one of {names} or None, got {surface_under!r}")
    top, thickness = bottom[2] - float(start_gap), 0.01
    under = names.index(surface_under) if surface_under is not None else 0
    for index, surface in enumerate(surfaces):
        x, y = bottom[:2] + np.array([0.0, PAD_SPACING * (index - under)])
        pad = spec.worldbody.add_body(name=f"{surface.name}_pad", pos=[x, y, top - thickness])
        pad.gravcomp = 1.0
        joint = pad.add_joint(
            name=f"{surface.name}_pad", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1]
        )
        for field, value in (("stiffness", surface.stiffness), ("damping", surface.damping)):
            current = getattr(joint, field)  # newer MuJoCo: an array, set its first entry
            first = np.r_[value, np.zeros(np.size(current) - 1)]
            setattr(joint, field, float(value) if np.ndim(current) == 0 else first)
        pad.add_geom(
            name=f"{surface.name}_pad",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.06, 0.06, thickness],
            mass=PAD_MASS,
            contype=0,
            conaffinity=1,
            solref=[2.0 * timestep, 1.0],
            solimp=[0.99, 0.99, 0.001, 0.5, 2.0],
            rgba=[0.9, 0.9, 0.3, 1] if surface.name == "sponge" else [0.5, 0.2, 0.2, 1],
        )
    if surfaces:
        spec.worldbody.add_geom(
            name="table",
            type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.3, 0.4, 0.01],
            pos=[bottom[0], bottom[1], top - 0.03],
            contype=0,
            conaffinity=0,
            rgba=[0.6, 0.45, 0.3, 1],
        )


def _add_servos(mujoco, spec, arm: Arm) -> None:
    """One speedJ-like ``intvelocity`` actuator per joint, within the URDF's speed limits."""
    for name, limit in zip(arm.joint_names, arm.velocity_limits):
        joint = spec.joint(name)
        actuator = spec.add_actuator(
            name=f"{name}_speed", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        actuator.set_to_intvelocity(kp=1.0, kv=0.0)
        actuator.ctrllimited, actuator.ctrlrange = 1, [-limit, limit]
        actuator.actlimited, actuator.actrange = 1, list(joint.range)
        joint.armature = 0.05


def _tune_servos(sim: "ArmSimulation", omega: float) -> None:
    """Critically damped position servos: ``kp = ω² M_ii``, ``kv = 2 ω M_ii`` with the joint-space
    inertia at ``q0``.
    """
    mujoco, model, data = sim.mujoco, sim.model, sim.data
    full = np.zeros((model.nv, model.nv))
    if hasattr(data, "qM"):
        mujoco.mj_fullM(model, full, data.qM)
    else:  # MuJoCo 4
        mujoco.mj_fullM(model, data, full)
    inertia = np.diag(full)[sim._arm_dof]  # actuator i drives arm joint i
    model.actuator_gainprm[: len(inertia), 0] = omega * omega * inertia
    model.actuator_biasprm[: len(inertia), 1] = -omega * omega * inertia
    model.actuator_biasprm[: len(inertia), 2] = -2.0 * omega * inertia


class ArmSimulation:
    """A compiled MuJoCo model of the arm and its scene, with ftkin-side accessors.

    Build it with :func:`build_arm_model`. Attributes: ``model`` (``MjModel``),
    ``data`` (``MjData``), ``arm`` (the ftkin :class:`~ftkin.kinematics.arm.Arm`),
    ``sensor_site_id``, ``force_sensor_id``, ``torque_sensor_id``,
    ``object_body_id`` (or -1), ``tool_body_id`` (the tool link's body, else the measured one),
    ``surfaces`` (name → :class:`Surface`),
    ``surface_under`` (the pad below the object), ``base_tilt`` [rad], ``g`` [m/s²].
    MuJoCo's world frame is the arm's base frame; the sign of the readings is the module's.
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
        self.mujoco, self.model, self.arm, self.q0 = mujoco, model, arm, q0
        self.data = mujoco.MjData(model)
        self.surfaces, self.surface_under = surfaces, surface_under
        self.base_tilt, self.g = base_tilt, g
        self.sensor_site_id = model.site("ftkin_sensor").id
        self.force_sensor_id = model.sensor("ftkin_force").id
        self.torque_sensor_id = model.sensor("ftkin_torque").id
        body_id = lambda name: mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, name)  # -1: none
        self.object_body_id = body_id("ftkin_object")
        tool = body_id(arm.tool_frame) if arm.tool_frame else -1
        self.tool_body_id = tool if tool >= 0 else int(model.site_bodyid[self.sensor_site_id])
        self._pad_qpos = {name: int(model.joint(f"{name}_pad").qposadr[0]) for name in surfaces}
        # contiguous addresses (the usual case) as one slice: cheaper than fancy indexing per tick
        self._arm_qpos = _as_slice([model.joint(n).qposadr[0] for n in arm.joint_names])
        self._arm_dof = _as_slice([model.joint(n).dofadr[0] for n in arm.joint_names])
        force, torque = (
            int(model.sensor_adr[i]) for i in (self.force_sensor_id, self.torque_sensor_id)
        )
        self._wrench_index = _as_slice([*range(force, force + 3), *range(torque, torque + 3)])
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
        return self.data.qpos[self._arm_qpos].copy()

    @property
    def dq(self) -> np.ndarray:
        """Joint velocities [rad/s] (copy)."""
        return self.data.qvel[self._arm_dof].copy()

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
        return -float(self.data.qpos[self._pad_qpos[self.surface_under if name is None else name]])

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
        site = self.sensor_site_id
        root = int(self.model.site_bodyid[site])  # the measured body
        inertia = subtree_inertia(self.model, self.data, site, root, without=self.object_body_id)
        return ToolInertia(inertia.mass, inertia.lever, inertia.inertia)

    def tool_sensor_model(self, bias=(0.0,) * 6) -> SensorModel:
        """ftkin's :class:`SensorModel` of this tool: its mass and COM from the model, this gravity
        and tilt, ``bias`` [N, N·m].
        """
        tool = self.tool_inertia()
        bias = np.asarray(bias, dtype=float)
        return SensorModel.from_tool(
            tool.mass, tool.center_of_mass, bias[:3], bias[3:], self.base_tilt, self.g
        )


def _as_slice(indices):
    """``indices`` as a slice when they run consecutively, else as an index array."""
    indices = np.asarray(indices, dtype=int)
    start = int(indices[0])
    consecutive = np.array_equal(indices, np.arange(start, start + len(indices)))
    return slice(start, start + len(indices)) if consecutive else indices
