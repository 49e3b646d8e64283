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

import numpy as np
import pinocchio as pin

_AXES = {"X": (1.0, 0.0, 0.0), "Y": (0.0, 1.0, 0.0), "Z": (0.0, 0.0, 1.0)}

BLOCK = 16384
"""Configurations per block (the temporaries stay in the cache)."""

VECTOR_BLOCK = 8192
"""Configurations per block of :meth:`RotationChain.transposed_times` (its ``(N,)`` temporaries,
64 kB, stay below the allocator's mmap threshold and in the cache)."""


class RotationChain:
    """``R_BS(q)`` of one frame for a batch of configurations, vectorised in numpy.

    Build it with :meth:`from_model`, which returns None for chains with other
    joint kinds (spherical, free, planar, helical, mimic, ...).
    """

    def __init__(self, steps: list[tuple[int, np.ndarray]], head: np.ndarray, tail: np.ndarray):
        self._steps = steps
        self._indices = [index for index, _ in steps]
        self._head = head
        self._tail = tail

    @classmethod
    def from_model(
        cls, model: pin.Model, frame_id: int, tolerance: float = 1e-12
    ) -> "RotationChain | None":
        """The chain from the root to frame ``frame_id``, or None if a joint on it is neither
        revolute nor prismatic.

        Also None (callers fall back to Pinocchio) if the batched rotations
        differ from Pinocchio's by more than ``tolerance`` on a few seeded
        random configurations.
        """
        steps, carry = [], np.eye(3)
        for joint_id in list(model.supports[model.frames[frame_id].parentJoint])[1:]:  # root first
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
        chain = cls(steps, np.eye(3), carry @ model.frames[frame_id].placement.rotation)
        return chain if chain._agrees_with_pinocchio(model, frame_id, tolerance) else None

    def rotations(self, configurations: np.ndarray) -> np.ndarray:
        """``R_BS`` ``(N, 3, 3)`` for validated ``(N, nq)`` float joint positions [rad, m]."""
        out = np.empty((len(configurations), 3, 3))
        for start in range(0, len(configurations), BLOCK):
            out[start : start + BLOCK] = self._block(configurations[start : start + BLOCK])
        return out

    def transposed_times(self, configurations: np.ndarray, vector) -> np.ndarray:
        """``R_BS(q)ᵀ v`` ``(N, 3)`` for a base-frame vector ``v`` ``(3,)`` (e.g. the tool weight
        seen by the sensor).

        ``Rᵀ v = Tᵀ Rz(θₙ)ᵀ Cₙᵀ ⋯ Rz(θ₁)ᵀ C₁ᵀ v``: a 3-vector carried through the
        chain, six times cheaper than the rotation matrices.
        """
        count = len(configurations)
        out = np.empty(
            (3, count)
        )  # returned transposed: each component contiguous, as the compensation reads it
        size = min(count, VECTOR_BLOCK)
        angles, buffers = np.empty((len(self._steps), size)), _buffers((len(self._steps), size))
        for start in range(0, count, VECTOR_BLOCK):
            block = configurations[start : start + VECTOR_BLOCK]
            if len(block) != size:  # the last, shorter block
                size = len(block)
                angles, buffers = (
                    np.empty((len(self._steps), size)),
                    _buffers((len(self._steps), size)),
                )
            for row, index in enumerate(self._indices):
                angles[row] = block[:, index]
            self._vector_block(_cos_sin(angles, buffers), vector, out[:, start : start + size])
        return out.T

    def _vector_block(
        self, cos_sin: tuple[np.ndarray, np.ndarray], vector, out: np.ndarray
    ) -> None:
        cosines, sines = cos_sin
        v = (self._head.T @ np.asarray(vector, dtype=float)).tolist()
        for row, (_, constant) in enumerate(self._steps):
            v = [_combine(line, v) for line in constant.T.tolist()]  # Cᵀ v
            cos, sin = cosines[row], sines[row]
            v = [cos * v[0] + sin * v[1], cos * v[1] - sin * v[0], v[2]]  # Rz(θ)ᵀ v
        for component, line in zip(out, self._tail.T.tolist()):
            component[:] = _combine(line, v)

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
        lower = np.clip(model.lowerPositionLimit, -np.pi, np.pi)  # unbounded joints: one turn
        upper = np.maximum(np.clip(model.upperPositionLimit, -np.pi, np.pi), lower)
        configurations = np.random.default_rng(0).uniform(lower, upper, size=(4, model.nq))
        data = model.createData()
        expected = []
        for configuration in configurations:
            pin.forwardKinematics(model, data, configuration)
            expected.append(pin.updateFramePlacement(model, data, frame_id).rotation.copy())
        return bool(np.abs(self.rotations(configurations) - np.array(expected)).max() <= tolerance)


_TABLE_SIZE = 4096
_STEP = 2.0 * np.pi / _TABLE_SIZE
_STEP_HIGH = float(np.float32(_STEP))  # 24 significant bits: k · _STEP_HIGH is exact for |k| < 2²⁹
_STEP_LOW = ((2.0 * np.pi - _TABLE_SIZE * _STEP_HIGH) + 2.4492935982947064e-16) / _TABLE_SIZE
"""``2π/4096 − _STEP_HIGH``, with the part of 2π below the double ``2.0 * np.pi`` (Cody–Waite
reduction).
"""


def _table() -> tuple[np.ndarray, np.ndarray]:
    """``cos``/``sin`` of ``j 2π/4096`` to within an ulp: numpy's on the rounded angle, corrected to
    first order.
    """
    j = np.arange(_TABLE_SIZE, dtype=float)
    rounded = j * _STEP_HIGH + j * _STEP_LOW
    error = (j * _STEP_HIGH - rounded) + j * _STEP_LOW
    return np.cos(rounded) - error * np.sin(rounded), np.sin(rounded) + error * np.cos(rounded)


_COS_TABLE, _SIN_TABLE = _table()
_TABLE_RANGE = 1e4
"""Angles beyond ±this [rad] take numpy's ``cos``/``sin`` (the table's residual loses digits)."""


def _cos_sin(
    angles: np.ndarray, buffers: list[np.ndarray] | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """``cos`` and ``sin`` of an array of angles [rad] from a table and a short Taylor series.

    ``θ = k h + r`` with ``h = 2π/4096`` and ``|r| ≤ h/2``; ``cos``/``sin`` of
    ``k h`` come from a table and those of ``r`` from ``1 − r²/2 + r⁴/24`` and
    ``r − r³/6`` (the next terms are below 3e-18), combined by the angle-sum
    formulas: within a few ulp of numpy's ``cos``/``sin``, which cost ~20 ns an
    angle here against a few ns for this. Non-finite angles give NaN.

    ``buffers`` (from :func:`_buffers`, of the angles' shape) are reused
    across calls: fresh arrays larger than the allocator's mmap threshold
    (128 kB) cost a page fault per 4 kB page, more than the arithmetic.
    The returned arrays are two of them.
    """
    if angles.size and not (
        angles.max() <= _TABLE_RANGE and angles.min() >= -_TABLE_RANGE
    ):  # also NaN
        with np.errstate(invalid="ignore"):
            return np.cos(angles), np.sin(angles)
    turns, residual, squared, table_cos, table_sin, cos, sin, index = buffers or _buffers(
        angles.shape
    )
    np.multiply(angles, 1.0 / _STEP, out=turns)
    np.rint(turns, out=turns)
    np.multiply(turns, _STEP_HIGH, out=residual)
    np.subtract(angles, residual, out=residual)
    residual -= np.multiply(turns, _STEP_LOW, out=squared)  # r = θ − k h, h in two parts
    np.copyto(index, turns, casting="unsafe")
    index &= (
        _TABLE_SIZE - 1
    )  # k mod 4096 (two's complement); "clip" then never clips and is the fastest take
    _COS_TABLE.take(index, out=table_cos, mode="clip")
    _SIN_TABLE.take(index, out=table_sin, mode="clip")
    np.multiply(residual, residual, out=squared)
    cos_residual = np.multiply(squared, 1.0 / 24.0, out=turns)
    np.subtract(0.5, cos_residual, out=cos_residual)
    cos_residual *= squared
    np.subtract(1.0, cos_residual, out=cos_residual)  # 1 − r²(1/2 − r²/24)
    squared *= 1.0 / 6.0
    squared *= residual
    sin_residual = np.subtract(residual, squared, out=residual)  # r − r³/6
    np.multiply(table_cos, cos_residual, out=cos)
    cos -= np.multiply(table_sin, sin_residual, out=squared)
    np.multiply(table_sin, cos_residual, out=sin)
    sin += np.multiply(table_cos, sin_residual, out=squared)
    return cos, sin


def _buffers(shape: tuple[int, ...]) -> list[np.ndarray]:
    """Work arrays of :func:`_cos_sin` for angles of ``shape``."""
    return [np.empty(shape) for _ in range(7)] + [np.empty(shape, dtype=np.intp)]


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
