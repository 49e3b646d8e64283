"""Order poses so the arm travels little between consecutive ones.

An open path through all configurations (no return to the start) with short
total joint travel: nearest-neighbour tours from every start, each improved
by 2-opt (reverse a segment while that shortens the path); the shortest wins.
Distance is the Euclidean norm of the joint difference [rad], a proxy for
motion time and cable wind-up. Exact for a handful of poses, within a few per
cent of optimal for the tens a calibration uses.

Before ordering, :func:`unwind_revolute` moves each revolute joint by whole
turns toward zero where its limits allow (same pose, same collision state):
arms with ±2π joints otherwise plan poses a full turn apart.
"""

from __future__ import annotations

import numpy as np

REVOLUTE_KINDS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")


def revolute_mask(model) -> np.ndarray:
    """``(nq,)`` True for the coordinates of revolute joints (one coordinate each)."""
    mask = np.zeros(model.nq, dtype=bool)
    for joint in list(model.joints)[1:]:
        if joint.shortname() in REVOLUTE_KINDS:
            mask[joint.idx_q] = True
    return mask


def unwind_revolute(joint_positions, lower, upper, mask) -> np.ndarray:
    """Shift revolute coordinates by multiples of 2π toward zero while within ``[lower, upper]`` [rad]."""
    q = np.array(joint_positions, dtype=float)
    turns = np.round(q / (2.0 * np.pi))
    for _ in range(int(np.max(np.abs(turns), initial=0))):
        step = np.sign(turns) * 2.0 * np.pi
        shifted = q - step
        ok = mask & (turns != 0) & (shifted >= lower) & (shifted <= upper)
        q = np.where(ok, shifted, q)
        turns = np.where(ok, turns - np.sign(turns), 0.0 * turns)
    return q


def joint_distances(joint_positions: np.ndarray) -> np.ndarray:
    """Pairwise joint-space distances ``(N, N)`` [rad] of ``(N, nq)`` configurations."""
    difference = joint_positions[:, None, :] - joint_positions[None, :, :]
    return np.sqrt(np.sum(difference**2, axis=-1))


def path_length(distances: np.ndarray, order) -> float:
    """Total travel along ``order`` (open path) [rad]."""
    order = np.asarray(order)
    return float(np.sum(distances[order[:-1], order[1:]]))


def _nearest_neighbour(distances: np.ndarray, start: int) -> list[int]:
    count = len(distances)
    order = [start]
    visited = np.zeros(count, dtype=bool)
    visited[start] = True
    for _ in range(count - 1):
        row = np.where(visited, np.inf, distances[order[-1]])
        nxt = int(np.argmin(row))
        order.append(nxt)
        visited[nxt] = True
    return order


def _two_opt(distances: np.ndarray, order: list[int]) -> list[int]:
    order = list(order)
    count = len(order)
    improved = True
    while improved:
        improved = False
        for i in range(count - 1):
            for j in range(i + 1, count):
                # Reverse order[i..j]; edges (i-1, i) and (j, j+1) change.
                before = distances[order[i - 1], order[i]] if i > 0 else 0.0
                after = distances[order[j], order[j + 1]] if j < count - 1 else 0.0
                new_before = distances[order[i - 1], order[j]] if i > 0 else 0.0
                new_after = distances[order[i], order[j + 1]] if j < count - 1 else 0.0
                if new_before + new_after < before + after - 1e-12:
                    order[i : j + 1] = order[i : j + 1][::-1]
                    improved = True
    return order


def short_travel_order(joint_positions) -> np.ndarray:
    """Permutation of ``(N, nq)`` configurations giving a short open path (deterministic).

    Returns:
        Indices ``(N,)``: visit ``joint_positions[order[0]]`` first.
    """
    joint_positions = np.asarray(joint_positions, dtype=float)
    count = len(joint_positions)
    if count <= 2:
        return np.arange(count)
    distances = joint_distances(joint_positions)
    best, best_length = None, np.inf
    for start in range(count):
        order = _two_opt(distances, _nearest_neighbour(distances, start))
        length = path_length(distances, order)
        if length < best_length - 1e-12:
            best, best_length = order, length
    return np.array(best)
