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
its negative: :meth:`ArmSimulation.ideal_wrench_in_sensor` returns ``-sensordata``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ...calibration.model import STANDARD_GRAVITY
from ...exceptions import InvalidInput, MissingDependency
from ...kinematics.arm import Arm
from ...kinematics.rotations import gravity_in_base_from_tilt
from ..surfaces import BOOK, SPONGE, Surface
from .simulation import ArmSimulation

Q_DOWN = (0.0, 0.0, -np.pi / 6, 0.0, -np.pi / 3, 0.0)
"""Tool-pointing-down configuration of the bundled arm [rad]."""

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
) -> ArmSimulation:
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
        q0: Start configuration [rad] (default :data:`Q_DOWN` for a 6-joint arm, else the zero
            configuration).
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
    q0 = _check_arguments(arm, q0, timestep, servo_bandwidth)
    spec = mujoco.MjSpec.from_file(str(arm.urdf_path))
    spec.compiler.fusestatic = False
    bodies = {body.name: body for body in spec.bodies}
    if arm.sensor_frame not in bodies:
        raise InvalidInput(
            f"the sensor frame {arm.sensor_frame!r} is not a link of {arm.urdf_path.name}; MuJoCo "
            "needs a sensor link"
        )
    measured = _measured_body(spec, bodies, arm.sensor_frame, measured_body)
    _add_sensor(mujoco, spec, bodies, measured)
    holder = bodies.get(arm.tool_frame, measured) if arm.tool_frame else measured
    if grasped_object is not None:
        _add_object(mujoco, holder, grasped_object)
    rotation, tool_point = arm.frame_placement(q0, "tool" if arm.tool_frame else "sensor")
    drop = grasped_object.height if grasped_object is not None else 0.0
    bottom = tool_point + rotation[:, 2] * drop  # of the object (or the tool point) at q0
    _add_table(mujoco, spec, surfaces, surface_under, bottom, start_gap, timestep)
    _add_servos(mujoco, spec, arm)
    spec.option.timestep = float(timestep)
    integrators = mujoco.mjtIntegrator
    spec.option.integrator = (
        getattr(integrators, "mjINT_IMPLICITFAST", None) or integrators.mjINTEGRATOR_IMPLICITFAST
    )
    spec.option.gravity = gravity_in_base_from_tilt(
        float(g), float(base_tilt[0]), float(base_tilt[1])
    )
    sim = ArmSimulation(
        mujoco,
        spec.compile(),
        arm,
        q0,
        {s.name: s for s in surfaces},
        surface_under if surfaces else None,
        (float(base_tilt[0]), float(base_tilt[1])),
        float(g),
    )
    _tune_servos(sim, 2.0 * math.pi * servo_bandwidth)
    sim.reset()  # again: the equilibrium targets depend on the servo gains
    return sim


def _check_arguments(arm: Arm, q0, timestep: float, servo_bandwidth: float) -> np.ndarray:
    """The start configuration ``q0`` [rad], after checking the arm and the numbers."""
    if arm.urdf_path is None:
        raise InvalidInput("build_arm_model needs an arm loaded from a URDF file (Arm.from_urdf)")
    if not (
        math.isfinite(timestep)
        and timestep > 0
        and math.isfinite(servo_bandwidth)
        and servo_bandwidth > 0
    ):
        raise InvalidInput(
            f"timestep [s] and servo_bandwidth [Hz] must be > 0, got {timestep!r}, "
            f"{servo_bandwidth!r}"
        )
    q0 = np.asarray(
        (Q_DOWN if arm.nq == 6 else np.zeros(arm.nq)) if q0 is None else q0, dtype=float
    )
    return arm.check_configuration(q0).copy()


def _add_sensor(mujoco, spec, bodies: dict, measured) -> None:
    """Force and torque sensors on a site at the sensor frame; the arm weightless and contact-free.

    The arm collides with nothing (only the object touches the pads) and its own links are
    gravity-compensated (the robot controller's job; its servo would sag otherwise).
    """
    for geom in spec.geoms:
        geom.contype, geom.conaffinity = 0, 0
    for name, body in bodies.items():
        if name != "world" and not _is_descendant(body, measured):
            body.gravcomp = 1.0
    site_pos, site_quat = _inverse_pose(measured)
    measured.add_site(name="ftkin_sensor", pos=site_pos, quat=site_quat)
    add_wrench_sensor(mujoco, spec, "ftkin_sensor")


def _add_table(mujoco, spec, surfaces, surface_under, bottom: np.ndarray, start_gap, timestep):
    """The pads, ``surface_under`` ``start_gap`` [m] below ``bottom`` [m], on a table."""
    names = [surface.name for surface in surfaces]
    if surface_under is not None and surface_under not in names:
        raise InvalidInput(f"surface_under must be one of {names} or None, got {surface_under!r}")
    top = bottom[2] - float(start_gap)
    under = names.index(surface_under) if surface_under is not None else 0
    for index, surface in enumerate(surfaces):
        centre = bottom[:2] + np.array([0.0, PAD_SPACING * (index - under)])
        _add_pad(mujoco, spec, surface, centre, top, timestep)
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
    for name in arm.joint_names:
        joint = spec.joint(name)
        limit = arm.velocity_limits[arm.joint_names.index(name)]
        actuator = spec.add_actuator(
            name=f"{name}_speed", target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT
        )
        actuator.set_to_intvelocity(kp=1.0, kv=0.0)
        actuator.ctrllimited, actuator.ctrlrange = 1, [-limit, limit]
        actuator.actlimited, actuator.actrange = 1, list(joint.range)
        joint.armature = 0.05


def _measured_body(spec, bodies: dict, sensor: str, name: str | None):
    if name is not None:
        if name not in bodies:
            raise InvalidInput(f"measured_body {name!r} is not a link; links: {sorted(bodies)}")
        if bodies[name].parent is None or bodies[name].parent.name != sensor:
            raise InvalidInput(
                f"measured_body {name!r} must be a child link of the sensor link {sensor!r}"
            )
        return bodies[name]
    children = [
        body for body in bodies.values() if body.parent is not None and body.parent.name == sensor
    ]
    if len(children) != 1:
        raise InvalidInput(
            f"the sensor link {sensor!r} has {len(children)} child links; name the measured one "
            "(measured_body=...)"
        )
    return children[0]


def _is_descendant(body, root) -> bool:
    while body is not None and body.name != "world":
        if body.name == root.name:
            return True
        body = body.parent
    return False


def _inverse_pose(body) -> tuple[list, list]:
    """Pose of a body's parent frame in the body's frame (where the sensor link's origin sits)."""
    w, x, y, z = (float(v) for v in body.quat)
    norm = math.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / norm, x / norm, y / norm, z / norm
    rotation = np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )
    return (-(rotation.T @ np.asarray(body.pos, dtype=float))).tolist(), [w, -x, -y, -z]


def _add_object(mujoco, holder, obj: GraspedObject) -> None:
    body = holder.add_body(name="ftkin_object", pos=[0.0, 0.0, obj.height / 2])
    body.add_geom(
        name="ftkin_object",
        type=mujoco.mjtGeom.mjGEOM_BOX,
        size=[obj.half_width, obj.half_width, obj.height / 2],
        mass=obj.mass,
        contype=1,
        conaffinity=0,
        rgba=[0.2, 0.5, 0.9, 1],
    )


def _add_pad(mujoco, spec, surface: Surface, centre, top: float, timestep: float) -> None:
    """A pad on a vertical slide joint: its spring and damper are the surface's ``k`` and ``c``; the
    contact is stiff.
    """
    thickness = 0.01
    body = spec.worldbody.add_body(
        name=f"{surface.name}_pad", pos=[centre[0], centre[1], top - thickness]
    )
    body.gravcomp = 1.0
    joint = body.add_joint(
        name=f"{surface.name}_pad", type=mujoco.mjtJoint.mjJNT_SLIDE, axis=[0, 0, 1]
    )
    _set_first(joint, "stiffness", surface.stiffness)
    _set_first(joint, "damping", surface.damping)
    body.add_geom(
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


def _set_first(obj, name: str, value: float) -> None:
    """Set a scalar attribute, or the first entry where newer MuJoCo made it an array."""
    current = getattr(obj, name)
    if np.ndim(current) == 0:
        setattr(obj, name, float(value))
    else:
        array = np.zeros(np.shape(current))
        array[0] = value
        setattr(obj, name, array)


def _tune_servos(sim: ArmSimulation, omega: float) -> None:
    """Critically damped position servos: ``kp = ω² M_ii``, ``kv = 2 ω M_ii`` with the joint-space
    inertia at ``q0``.
    """
    mujoco, model, data = sim.mujoco, sim.model, sim.data
    full = np.zeros((model.nv, model.nv))
    if hasattr(data, "qM"):
        mujoco.mj_fullM(model, full, data.qM)
    else:  # MuJoCo 4
        mujoco.mj_fullM(model, data, full)
    for actuator, dof in enumerate(sim._arm_dof):
        inertia = full[dof, dof]
        model.actuator_gainprm[actuator, 0] = omega * omega * inertia
        model.actuator_biasprm[actuator, 1] = -omega * omega * inertia
        model.actuator_biasprm[actuator, 2] = -2.0 * omega * inertia
