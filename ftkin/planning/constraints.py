"""Which joint configurations a calibration pose may use.

:class:`PoseConstraints` holds the user's limits; :class:`FeasibilityChecker`
applies them to configurations, cheapest test first:

1. joint limits shrunk by ``margin`` [rad], intersected with optional
   per-joint ranges (e.g. for cable dress) taken as given;
2. floor: the sensor origin and the tool origin (when the arm has a tool
   frame) at least ``floor_height`` [m] above the base frame's origin (base z);
3. tilt: the tool axis (z axis of the tool frame, else of the sensor frame)
   within ``max_tilt`` [rad] of pointing straight down (base −z);
4. no self-collision: the links (their meshes' convex hulls) at least ``clearance`` [m]
   apart (:class:`~ftkin.kinematics.collision.SelfCollision`).

:func:`check_tilt_observability` and :func:`check_information` refuse, before
any optimization, constraint sets under which no pose set could determine
every parameter, naming the parameters.
"""

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from ..calibration.model import COMPONENT_NAMES
from ..calibration.mount import MOUNT_NAMES
from ..exceptions import InvalidInput, UnobservableParameters
from ..kinematics.collision import DEFAULT_CLEARANCE, SelfCollision
from ..kinematics.rotations import euler_zyx_to_matrix
from ..options import float_text, number, option
from ..validation import as_in_range, as_real, set_checked

_MOUNT_MODE_BY_SIZE = {12: "none", 13: "yaw", 15: "full"}

DEFAULT_MARGIN = 0.05
"""Default distance kept from every joint limit [rad] (about 3°)."""
_TILT_DEGREES = number(0.0, 180.0)
DEFAULT_FLOOR_HEIGHT = 0.1
"""Default floor of planned poses and of a robot session [m, base z]: the base plane plus a
10 cm margin (a tool's length below the sensor is not in the model)."""


def joint_range_text(text: str) -> tuple[str, float, float]:
    """A joint range written ``NAME:LO:HI`` [rad] (the command line's ``--joint-range``), as
    ``(name, lower, upper)``; a text that is not one raises :class:`argparse.ArgumentTypeError`
    naming what is expected (radians: values beyond 2π are taken for degrees)."""
    import argparse

    parts = text.rsplit(":", 2)
    try:
        if len(parts) != 3 or not parts[0]:
            raise ValueError
        low, high = float_text(parts[1]), float_text(parts[2])
    except ValueError:
        old = " (JOINT LOW HIGH, three words, is the old spelling)" if ":" not in text else ""
        raise argparse.ArgumentTypeError(
            f"expected NAME:LO:HI with LO, HI in radians (e.g. joint1:-0.5:0.5), got {text!r}{old}"
        ) from None
    if not (math.isfinite(low) and math.isfinite(high)):
        raise argparse.ArgumentTypeError(f"expected finite LO and HI [rad], got {text!r}")
    if max(abs(low), abs(high)) > 2.0 * math.pi:
        raise argparse.ArgumentTypeError(
            f"{text!r}: LO and HI are beyond 2π: ranges are in radians (these look like degrees)"
        )
    if low > high:
        raise argparse.ArgumentTypeError(f"{text!r}: LO must not exceed HI")
    return parts[0], low, high


@dataclass(frozen=True)
class PoseConstraints:
    """Limits on calibration poses.

    Attributes:
        margin: Distance kept from the URDF joint limits [rad].
        floor_height: Lowest allowed height of the sensor and tool origins
            in the base frame [m] (default :data:`DEFAULT_FLOOR_HEIGHT`, 0.1 m, as ``ftkin
            plan``), or None (no floor: an arm on a wall or a ceiling).
        max_tilt: Largest angle between the tool axis and straight down
            [rad], or None.
        joint_ranges: ``((joint name, lower, upper), ...)`` extra ranges [rad].
        self_collision: Whether to reject self-colliding configurations.
        clearance: Smallest distance kept between the arm's own links (their collision meshes'
            convex hulls) [m]: a robot's own collision model (and a simulator's) is not the
            URDF's meshes, so poses that only just miss in the URDF touch on the robot.
    """

    margin: float = option(
        DEFAULT_MARGIN,
        "distance kept from the joint limits",
        unit="rad",
        metavar="RAD",
        parse=number(0.0, 2.0 * np.pi),
    )
    floor_height: float | None = option(
        DEFAULT_FLOOR_HEIGHT,
        "sensor and tool origins stay above this height in the base frame (default: a floor at "
        "base z = 0 with a 10 cm margin; None, --no-floor: no floor)",
        unit="m",
        metavar="M",
        parse=number(-100.0, 100.0),
    )
    max_tilt: float | None = option(
        None,
        "largest angle of the tool axis from pointing straight down (the field: radians)",
        unit="deg",
        flag="--max-tilt-deg",
        metavar="DEG",
        parse=lambda text: math.radians(_TILT_DEGREES(text)),
    )
    joint_ranges: tuple = option(
        (),
        "extra range for one joint, NAME:LO:HI; repeat for several joints",
        unit="rad",
        flag="--joint-range",
        metavar="NAME:LO:HI",
        parse=joint_range_text,
        action="append",
        cli_default=[],
    )
    self_collision: bool = option(
        True,
        "do not check self-collision",
        flag="--no-self-collision",
        action="store_false",
    )
    clearance: float = option(
        DEFAULT_CLEARANCE,
        "smallest distance kept between the arm's own links (convex hulls of the URDF's "
        "collision meshes)",
        unit="m",
        metavar="M",
        parse=number(0.0, 1.0),
    )

    def __post_init__(self):
        set_checked(
            self,
            margin=as_in_range(self.margin, "margin", 0.0, 2.0 * np.pi, "rad"),
            floor_height=_optional(self.floor_height, "floor_height", 100.0, "m"),
            max_tilt=_optional(self.max_tilt, "max_tilt", np.pi, "rad", low=0.0),
            joint_ranges=_joint_ranges(self.joint_ranges),
            clearance=as_in_range(self.clearance, "clearance", 0.0, 1.0, "m"),
        )
        if not isinstance(self.self_collision, bool | np.bool_):
            raise InvalidInput(f"self_collision must be True or False, got {self.self_collision!r}")

    def describe(self) -> str:
        """One line naming every active constraint (for reports and errors)."""
        parts = [f"joint limits with a {self.margin:g} rad margin"]
        parts += [
            f"{name} in [{lower:g}, {upper:g}] rad" for name, lower, upper in self.joint_ranges
        ]
        if self.floor_height is not None:
            parts.append(f"sensor and tool above {self.floor_height:g} m (base z)")
        if self.max_tilt is not None:
            parts.append(f"tool axis within {np.rad2deg(self.max_tilt):g}° of straight down")
        parts.append(
            f"no self-collision (links at least {self.clearance:g} m apart)"
            if self.self_collision
            else "self-collision not checked"
        )
        return "; ".join(parts)


def _optional(value, name: str, bound: float, unit: str, low: float | None = None):
    """None, or a finite float within ``[low, bound]`` (``low`` default ``-bound``)."""
    return (
        None
        if value is None
        else as_in_range(value, name, -bound if low is None else low, bound, unit)
    )


def _joint_ranges(value) -> tuple[tuple[str, float, float], ...]:
    """``((name, lower, upper), ...)`` [rad] from such entries or ``{name: (lower, upper)}``."""
    try:
        entries = (
            [(name, *bounds) for name, bounds in value.items()]
            if isinstance(value, Mapping)
            else list(() if value is None else value)
        )
    except TypeError:
        raise InvalidInput(
            "joint_ranges must be ((name, lower, upper), ...) or {name: (lower, upper)} [rad], "
            f"got {value!r}"
        ) from None
    cleaned = []
    for entry in entries:
        try:
            name, lower, upper = entry
        except (TypeError, ValueError):
            name = None
        if not isinstance(name, str):
            raise InvalidInput(
                f"a joint range must be (joint name, lower, upper) [rad], got {entry!r}"
            )
        lower, upper = (as_real(bound, f"the joint range of {name!r}") for bound in (lower, upper))
        if not (np.isfinite(lower) and np.isfinite(upper) and lower < upper):
            raise InvalidInput(
                f"joint range for {name!r} must be finite with lower < upper [rad], got "
                f"({lower}, {upper})"
            )
        cleaned.append((name, lower, upper))
    return tuple(cleaned)


class FeasibilityChecker:
    """Apply :class:`PoseConstraints` to configurations of an arm.

    Attributes:
        lower, upper: Effective joint bounds ``(nq,)`` [rad].
        rejected: Count of configurations rejected per constraint.
    """

    def __init__(self, arm, constraints: PoseConstraints):
        self.arm, self.constraints, self.data = arm, constraints, arm.model.createData()
        lower, upper = arm.lower_limits + constraints.margin, arm.upper_limits - constraints.margin
        for name, low, high in constraints.joint_ranges:
            if name not in arm.joint_names:
                raise InvalidInput(
                    f"joint range for unknown joint {name!r}; joints: {', '.join(arm.joint_names)}"
                )
            index = arm.joint_names.index(name)
            lower[index], upper[index] = max(lower[index], low), min(upper[index], high)
        empty = [arm.joint_names[i] for i in np.flatnonzero(lower >= upper)]
        if empty:
            raise InvalidInput(
                f"no joint values left for {', '.join(empty)} between the URDF limits shrunk by "
                "the "
                f"{constraints.margin:g} rad margin and the given joint ranges"
            )
        self.lower, self.upper = lower, upper
        tool = [] if arm.tool_frame_id is None else [arm.tool_frame_id]
        self.axis_frame_id = (tool or [arm.sensor_frame_id])[0]
        self.height_frame_ids = [arm.sensor_frame_id, *tool]
        self.collision = (
            SelfCollision(arm, clearance=constraints.clearance)
            if constraints.self_collision
            else None
        )
        self.rejected = {"floor": 0, "tilt": 0, "self-collision": 0}

    def sample(self, count: int, rng: np.random.Generator) -> np.ndarray:
        """Uniform random configurations ``(count, nq)`` within the effective bounds [rad]."""
        return rng.uniform(self.lower, self.upper, size=(count, len(self.lower)))

    def within_bounds(self, q: np.ndarray) -> bool:
        """True when ``q`` lies within the effective joint bounds."""
        return bool(np.all(q >= self.lower) and np.all(q <= self.upper))

    def check(self, q: np.ndarray, collision: bool = True) -> np.ndarray | None:
        """``R_BS`` ``(3, 3)`` of a bounded configuration ``q`` if it meets the other constraints,
        else None.

        ``collision=False`` leaves out the self-collision test (the costly one:
        callers that may discard the pose anyway run :meth:`in_collision` last).
        """
        model, data, limits = self.arm.model, self.data, self.constraints
        pin.forwardKinematics(model, data, q)
        if limits.floor_height is not None and any(
            pin.updateFramePlacement(model, data, frame_id).translation[2] < limits.floor_height
            for frame_id in self.height_frame_ids
        ):
            self.rejected["floor"] += 1
            return None
        if limits.max_tilt is not None:
            axis_z = pin.updateFramePlacement(model, data, self.axis_frame_id).rotation[2, 2]
            if np.arccos(np.clip(-axis_z, -1.0, 1.0)) > limits.max_tilt:
                self.rejected["tilt"] += 1
                return None
        rotation = pin.updateFramePlacement(model, data, self.arm.sensor_frame_id).rotation.copy()
        if collision and self.in_collision(q):
            return None
        return rotation

    def in_collision(self, q: np.ndarray) -> bool:
        """True (and counted as a rejection) when ``q`` is self-colliding; False without a collision
        check.
        """
        if self.collision is not None and self.collision.in_collision(q):
            self.rejected["self-collision"] += 1
            return True
        return False

    def tool_to_sensor_rotation(self) -> np.ndarray:
        """Fixed rotation from the tilt-axis frame to the sensor frame, ``R_TS`` ``(3, 3)``."""
        model, data = self.arm.model, self.data
        pin.forwardKinematics(model, data, np.clip(np.zeros(self.arm.nq), self.lower, self.upper))
        tool = pin.updateFramePlacement(model, data, self.axis_frame_id).rotation.copy()
        return tool.T @ pin.updateFramePlacement(model, data, self.arm.sensor_frame_id).rotation


def check_tilt_observability(checker, factors) -> None:
    """Refuse a tilt limit that leaves every allowed orientation alike (names the parameters).

    ``factors(rotations)`` gives the weighted Jacobians ``(N, 6, 12)`` of
    :mod:`ftkin.planning.design`.
    """
    constraints = checker.constraints
    if constraints.max_tilt is None:
        return
    grid = np.linspace(0.0, 2.0 * np.pi, 8, endpoint=False)
    # Tool orientations R_BT = Rz(α) Ry(β) Rx(π) Rz(ψ): tool z tilted by β from straight down.
    tilted = euler_zyx_to_matrix(
        [[alpha, beta, np.pi] for alpha in grid for beta in (0.0, constraints.max_tilt)]
    )
    spins = euler_zyx_to_matrix([[psi, 0.0, 0.0] for psi in grid])
    rotations = np.einsum("aij,bjk,kl->abil", tilted, spins, checker.tool_to_sensor_rotation())
    check_information(factors(rotations.reshape(-1, 3, 3)), constraints)


def check_information(factors, constraints, rcond: float = 1e-10):
    """Refuse when the summed information of ``factors`` is singular; name every weak parameter."""
    information = np.einsum("nki,nkj->ij", factors, factors)
    scale = np.sqrt(np.maximum(np.diag(information), 1e-300))
    eigenvalues, eigenvectors = np.linalg.eigh(information / np.outer(scale, scale))
    weak = eigenvalues <= rcond * eigenvalues[-1]
    if not np.any(weak):
        return
    involved = np.any(np.abs(eigenvectors[:, weak]) > 0.3, axis=1) | (
        np.diag(information) <= rcond * information.max()
    )
    raise UnobservableParameters(
        [
            (COMPONENT_NAMES + MOUNT_NAMES[_MOUNT_MODE_BY_SIZE[len(information)]])[i]
            for i in np.flatnonzero(involved)
        ],
        f"every sensor orientation these constraints allow ({constraints.describe()}) sees gravity "
        "along (nearly) the same sensor direction, so the tool's weight cannot be told apart from "
        "the force bias, nor its centre of mass from the torque bias; allow more tilt or wider "
        "joint ranges",
        singular_values=eigenvalues[::-1],
    )
