"""Batched forward kinematics in numpy for chains of revolute and prismatic joints.

Pinocchio computes one configuration per call (about a microsecond of work
behind a few microseconds of Python overhead). For a log of many
configurations, :class:`RotationChain` computes the rotation ``R_BS`` of one
frame for the whole batch at once.

A revolute joint about the unit axis ``u`` rotates by ``R_u(θ) = Q Rz(θ) Qᵀ``,
with ``Q`` any rotation whose third column is ``u``. The constant rotations
(joint placements, ``Q`` and ``Qᵀ`` of neighbouring joints) fold into one
``(3, 3)`` matrix per joint, applied to the batch as a single matrix product,
and ``Rz(θ)`` mixes two columns. A prismatic joint does not rotate. The result
is checked against Pinocchio on a few configurations when the chain is built.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}

BLOCK = 16384
"""Configurations per block (the temporaries stay in the cache)."""


class RotationChain:
    """``R_BS(q)`` of one frame for a batch of configurations, vectorised in numpy.

    Build it with :meth:`from_model`, which returns None for chains with other
    joint kinds (spherical, free, planar, helical, mimic, ...).
    """

    def __init__(self, steps: list[tuple[int, np.ndarray]], head: np.ndarray, tail: np.ndarray):
        self._steps = steps
        self._head = head
        self._tail = tail

    @classmethod
    def from_model(cls, model: pin.Model, frame_id: int, tolerance: float = 1e-12) -> RotationChain | None:
        """The chain from the root to frame ``frame_id``, or None if a joint on it is neither revolute nor prismatic.

        Also None (callers fall back to Pinocchio) if the batched rotations
        differ from Pinocchio's by more than ``tolerance`` on a few seeded
        random configurations.
        """
        path, joint_id = [], model.frames[frame_id].parentJoint
        while joint_id > 0:
            path.append(joint_id)
            joint_id = model.parents[joint_id]
        steps, carry = [], np.eye(3)
        for joint_id in reversed(path):
            joint = model.joints[joint_id]
            kind = _joint_kind(joint)
            if kind is None:
                return None
            carry = carry @ model.jointPlacements[joint_id].rotation
            revolute, axis = kind
            if revolute:
                basis = _basis_with_z(axis)
                steps.append((joint.idx_q, carry @ basis))
                carry = basis.T
        tail = carry @ model.frames[frame_id].placement.rotation
        chain = cls(steps, np.eye(3), tail)
        if not chain._agrees_with_pinocchio(model, frame_id, tolerance):
            return None
        return chain

    def rotations(self, configurations: np.ndarray) -> np.ndarray:
        """``R_BS`` ``(N, 3, 3)`` for validated ``(N, nq)`` float joint positions [rad, m]."""
        out = np.empty((len(configurations), 3, 3))
        for start in range(0, len(configurations), BLOCK):
            out[start:start + BLOCK] = self._block(configurations[start:start + BLOCK])
        return out

    def transposed_times(self, configurations: np.ndarray, vector) -> np.ndarray:
        """``R_BS(q)ᵀ v`` ``(N, 3)`` for a base-frame vector ``v`` ``(3,)`` (e.g. the tool weight seen by the sensor).

        ``Rᵀ v = Tᵀ Rz(θₙ)ᵀ Cₙᵀ ⋯ Rz(θ₁)ᵀ C₁ᵀ v``: a 3-vector carried through the
        chain, six times cheaper than the rotation matrices.
        """
        out = np.empty((len(configurations), 3))
        for start in range(0, len(configurations), BLOCK):
            out[start:start + BLOCK] = self._vector_block(configurations[start:start + BLOCK], vector).T
        return out

    def _vector_block(self, configurations: np.ndarray, vector) -> np.ndarray:
        count = len(configurations)
        cosines, sines = _cos_sin(np.ascontiguousarray(configurations.T))
        v = (self._head.T @ np.asarray(vector, dtype=float)).tolist()
        for index, constant in self._steps:
            v = [_combine(row, v) for row in constant.T.tolist()]  # Cᵀ v
            cos, sin = cosines[index], sines[index]
            v = [cos * v[0] + sin * v[1], cos * v[1] - sin * v[0], v[2]]  # Rz(θ)ᵀ v
        return np.array([np.broadcast_to(_combine(row, v), (count,)) for row in self._tail.T.tolist()])

    def _block(self, configurations: np.ndarray) -> np.ndarray:
        count = len(configurations)
        cosines, sines = np.cos(configurations), np.sin(configurations)
        current = np.broadcast_to(self._head, (count, 3, 3))
        for index, constant in self._steps:
            current = (current.reshape(-1, 3) @ constant).reshape(count, 3, 3)
            c, s = cosines[:, index, np.newaxis], sines[:, index, np.newaxis]
            x, y = current[:, :, 0].copy(), current[:, :, 1]
            current[:, :, 0] = c * x + s * y  # (A Rz(θ)) column 0
            current[:, :, 1] = c * y - s * x  # (A Rz(θ)) column 1
        return (current.reshape(-1, 3) @ self._tail).reshape(count, 3, 3)

    def _agrees_with_pinocchio(self, model: pin.Model, frame_id: int, tolerance: float) -> bool:
        rng = np.random.default_rng(0)
        lower = np.clip(model.lowerPositionLimit, -np.pi, np.pi)  # unbounded joints: one turn
        upper = np.maximum(np.clip(model.upperPositionLimit, -np.pi, np.pi), lower)
        configurations = rng.uniform(lower, upper, size=(4, model.nq))
        data = model.createData()
        expected = []
        for configuration in configurations:
            pin.forwardKinematics(model, data, configuration)
            expected.append(pin.updateFramePlacement(model, data, frame_id).rotation.copy())
        return bool(np.abs(self.rotations(configurations) - np.array(expected)).max() <= tolerance)


def _cos_sin(angles: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``cos`` and ``sin`` from one ``tan`` of the half angle (``t = tan(θ/2)``).

    ``cos θ = (1 − t²)/(1 + t²)``, ``sin θ = 2t/(1 + t²)``: one transcendental
    call instead of two (numpy's float64 ``sin``/``cos`` cost ~20 ns each),
    within a few ulp of them.
    """
    half = np.tan(0.5 * angles)
    squared = half * half
    scale = 1.0 / (1.0 + squared)
    return (1.0 - squared) * scale, 2.0 * half * scale


def _combine(row: list[float], v: list):
    """``row · v`` leaving out zero coefficients and multiplications by ±1.

    Axis-aligned joints and placements make most constant rotations signed
    permutations; a coefficient within 1e-15 of 0 or ±1 is taken as exact
    (well within the 1e-12 checked against Pinocchio).
    """
    total = None
    for coefficient, value in zip(row, v):
        if abs(coefficient) < 1e-15:
            continue
        if abs(abs(coefficient) - 1.0) < 1e-15:
            term = value if coefficient > 0 else -value
        else:
            term = coefficient * value
        total = term if total is None else total + term
    return 0.0 if total is None else total


def _joint_kind(joint) -> tuple[bool, np.ndarray] | None:
    """``(revolute, unit axis)`` of a one-coordinate revolute or prismatic joint, else None."""
    name = joint.shortname().removeprefix("JointModel")
    if joint.nq != 1:
        return None
    if name in ("RevoluteUnaligned", "PrismaticUnaligned"):
        axis = np.array(joint.extract().axis, dtype=float)
        return name.startswith("Revolute"), axis / np.linalg.norm(axis)
    if len(name) == 2 and name[0] in "RP" and name[1] in _AXES:
        return name[0] == "R", np.array(_AXES[name[1]])
    return None


def _basis_with_z(axis: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector ``axis``."""
    helper = np.array([1.0, 0.0, 0.0]) if abs(axis[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(helper, axis)
    x /= np.linalg.norm(x)
    return np.column_stack([x, np.cross(axis, x), axis])
