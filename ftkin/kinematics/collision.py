"""Self-collision checks from a URDF's collision geometry (Pinocchio + coal).

:class:`SelfCollision` builds the pair list the way motion planners usually
do (MoveIt's setup assistant, Pinocchio's SRDF ``disable_collisions``):

1. every pair of collision objects (``addAllCollisionPairs``), then remove
2. pairs whose objects hang on the **same joint** (one rigid body, including
   links merged through fixed joints: flange, sensor, gripper, tool);
3. pairs whose joints are **parent and child** (adjacent links touch at
   their shared joint by construction);
4. pairs already in contact at the **reference configuration** (the middle
   of the joint limits clipped to zero where zero is allowed, i.e. the
   URDF's home pose): MoveIt's "collision by default" rule. Such pairs touch
   because of how the meshes were drawn (e.g. a motor housing overlapping
   the next link), not because of the configuration.

A configuration collides when a checked pair is closer than ``clearance`` [m] (a pair closer
than that at the reference configuration: closer than it is there). Meshes are checked as their
convex hulls, as MuJoCo collides them and as a robot's own collision model (capsules, spheres,
hulls drawn around each link) does: a concave mesh lets a link nest in another where the robot
(or a simulator) already reports contact. The clearance covers what remains between the URDF's
geometry and the robot's own model. On franky-sim's FR3 (MuJoCo, its own meshes), 3000 random
configurations: every contact MuJoCo reported was between hulls less than 0.016 m apart; the
triangle meshes had pairs 0.022 m apart in contact.

The geometry model is a copy, so the arm's cached model stays untouched.
"""

from dataclasses import dataclass

import coal
import numpy as np
import pinocchio as pin

from ..exceptions import InvalidInput

DEFAULT_CLEARANCE = 0.02
"""Default smallest distance kept between the arm's own links (convex hulls) [m]."""


@dataclass(frozen=True)
class RemovedPair:
    """A collision pair left out of the checks, and why."""

    first: str
    second: str
    reason: str


class SelfCollision:
    """Self-collision test of an :class:`~ftkin.kinematics.arm.Arm` at joint configurations.

    Args:
        arm: The arm (its URDF's collision geometry).
        reference_configuration: ``(nq,)`` [rad] of the "collision by default" rule (default:
            the URDF's home pose, see the module docstring).
        clearance: A configuration collides when a checked pair is closer than this [m]
            (0: only touching or overlapping pairs).

    Attributes:
        geometry_model: The (copied) collision geometry with the active pairs, meshes as their
            convex hulls.
        removed: Pairs left out, with the rule that removed each.
        clearance: [m].
        pair_clearances: ``(pairs,)`` the distance each checked pair keeps [m]: the clearance,
            or less for a pair closer than it at the reference configuration (how the links
            were drawn, as rule 4: it may not come closer than it is there).
    """

    def __init__(self, arm, reference_configuration=None, clearance: float = DEFAULT_CLEARANCE):
        try:
            clearance = float(clearance)
        except (TypeError, ValueError):
            clearance = float("nan")
        if not 0.0 <= clearance <= 1.0:
            raise InvalidInput(
                f"clearance must be a distance from 0 to 1 m between links, got {clearance!r}"
            )
        self.clearance = clearance
        self.model = arm.model
        self.data = arm.model.createData()
        self.geometry_model = pin.GeometryModel(arm.geometry("collision"))
        for item in self.geometry_model.geometryObjects:
            item.geometry = convex_hull(item.geometry)
        self.geometry_model.addAllCollisionPairs()
        if reference_configuration is None:  # zero where the limits allow it, else their middle
            lower, upper = arm.lower_limits, arm.upper_limits
            reference = np.where((lower <= 0.0) & (upper >= 0.0), 0.0, 0.5 * (lower + upper))
        else:
            reference = arm.check_configuration(reference_configuration)
        self.reference_configuration = reference
        self.removed = self._remove_pairs(reference)
        self.geometry_data = pin.GeometryData(self.geometry_model)
        pin.computeDistances(
            self.model, self.data, self.geometry_model, self.geometry_data, reference
        )
        at_reference = [result.min_distance for result in self.geometry_data.distanceResults]
        self.pair_clearances = np.minimum(clearance, np.maximum(at_reference, 0.0))
        for request, margin in zip(self.geometry_data.collisionRequests, self.pair_clearances):
            request.security_margin = float(margin)  # closer than this counts as a collision

    @property
    def pair_names(self) -> list[tuple[str, str]]:
        """Names of the object pairs that are checked."""
        objects = self.geometry_model.geometryObjects
        return [
            (objects[p.first].name, objects[p.second].name)
            for p in self.geometry_model.collisionPairs
        ]

    def _remove_pairs(self, reference: np.ndarray) -> list[RemovedPair]:
        objects, parents = self.geometry_model.geometryObjects, self.model.parents
        data = pin.GeometryData(self.geometry_model)
        pin.computeCollisions(self.model, self.data, self.geometry_model, data, reference, False)
        # Copy the index pairs first: removing while iterating skips pairs.
        pairs = [
            (pair.first, pair.second, result.isCollision())
            for pair, result in zip(self.geometry_model.collisionPairs, data.collisionResults)
        ]
        removed = []
        for first, second, touching in pairs:
            joint_a, joint_b = objects[first].parentJoint, objects[second].parentJoint
            if joint_a == joint_b:
                reason = "same rigid body"
            elif parents[joint_a] == joint_b or parents[joint_b] == joint_a:
                reason = "adjacent links"
            elif touching:
                reason = "in contact at the reference configuration"
            else:
                continue
            removed.append(RemovedPair(objects[first].name, objects[second].name, reason))
            self.geometry_model.removeCollisionPair(pin.CollisionPair(first, second))
        return removed

    def in_collision(self, q: np.ndarray) -> bool:
        """True when any checked pair is closer than its clearance (:attr:`pair_clearances`) at
        the validated ``(nq,)`` configuration ``q`` [rad].
        """
        return bool(
            pin.computeCollisions(
                self.model, self.data, self.geometry_model, self.geometry_data, q, True
            )
        )


def convex_hull(geometry):
    """A mesh (coal BVH model) as its convex hull; any other shape as it is."""
    if not isinstance(geometry, coal.BVHModelBase):
        return geometry
    geometry.buildConvexRepresentation(False)
    return geometry.convex
