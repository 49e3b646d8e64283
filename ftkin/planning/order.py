"""Order poses so the arm travels little between consecutive ones.

An open path through all configurations (no return to the start) with short
total joint travel: nearest-neighbour tours from every start (at most
:data:`MAX_STARTS` of them, evenly spread, for large sets), each improved
by 2-opt (reverse a segment while that shortens the path); the shortest wins.
Distance is the Euclidean norm of the joint difference [rad], a proxy for
motion time and cable wind-up. Exact for a handful of poses, within a few per
cent of optimal for the tens a calibration uses.

Before ordering, :func:`unwind_revolute` moves each revolute joint by whole
turns toward zero where its limits allow (same pose, same collision state):
arms with ±2π joints otherwise plan poses a full turn apart.
"""

import numpy as np

MAX_STARTS = 32
"""Nearest-neighbour starts tried (every pose for up to this many poses, else evenly spread
ones).
"""

REVOLUTE_KINDS = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")


def revolute_mask(model) -> np.ndarray:
    """``(nq,)`` True for the coordinates of revolute joints (one coordinate each)."""
    mask = np.zeros(model.nq, dtype=bool)
    # joints[0], the universe, reports JointModelRX with idx_q -1 (the last coordinate)
    mask[[j.idx_q for j in list(model.joints)[1:] if j.shortname() in REVOLUTE_KINDS]] = True
    return mask


def unwind_revolute(joint_positions, lower, upper, mask) -> np.ndarray:
    """Shift revolute coordinates by multiples of 2π toward zero while within ``[lower, upper]``
    [rad].
    """
    q = np.array(joint_positions, dtype=float)
    turns = np.round(q / (2.0 * np.pi))
    for _ in range(int(np.max(np.abs(turns), initial=0))):
        shifted = q - np.sign(turns) * 2.0 * np.pi
        ok = mask & (turns != 0) & (shifted >= lower) & (shifted <= upper)
        q = np.where(ok, shifted, q)
        turns = np.where(ok, turns - np.sign(turns), 0.0 * turns)
    return q


def joint_distances(joint_positions: np.ndarray) -> np.ndarray:
    """Pairwise joint-space distances ``(N, N)`` [rad] of ``(N, nq)`` configurations."""
    return np.linalg.norm(joint_positions[:, None, :] - joint_positions[None, :, :], axis=-1)


def path_length(distances: np.ndarray, order) -> float:
    """Total travel along ``order`` (open path) [rad]."""
    return float(np.sum(distances[order[:-1], order[1:]]))


def nearest_neighbour(distances: np.ndarray, start: int) -> list[int]:
    """Greedy open path from ``start``: next, always the unvisited pose nearest the last one."""
    order, visited = [start], np.zeros(len(distances), dtype=bool)
    visited[start] = True
    for _ in range(len(distances) - 1):
        order.append(int(np.argmin(np.where(visited, np.inf, distances[order[-1]]))))
        visited[order[-1]] = True
    return order


def _two_opt(distances: np.ndarray, order: list[int]) -> list[int]:
    """Reverse segments ``order[i..j]`` while that shortens the path (first improvement, in scan
    order).

    For each ``i`` the gains of every ``j`` are computed at once; after a
    reversal the scan goes on from ``j + 1`` on the new order, so the result
    is that of the plain double loop.
    """
    order = np.array(order)
    count = len(order)
    improved = True
    while improved:
        improved = False
        for i in range(count - 1):
            j = i + 1
            while j < count:
                j = _first_improvement(distances, order, i, j)
                if j < 0:
                    break
                order[i : j + 1] = order[i : j + 1][::-1].copy()
                improved = True
                j += 1
    return order.tolist()


def _first_improvement(distances: np.ndarray, order: np.ndarray, i: int, start: int) -> int:
    """The first ``j >= start`` whose reversal of ``order[i..j]`` shortens the path, or -1.

    Reversing changes the edges ``(i-1, i)`` and ``(j, j+1)`` into ``(i-1, j)``
    and ``(i, j+1)``; a missing edge at either end of the path counts 0.
    """
    ends, following = order[start:], order[start + 1 :]
    after, new_after = np.zeros(len(ends)), np.zeros(len(ends))
    after[:-1] = distances.ravel().take(
        ends[:-1] * len(distances) + following
    )  # distances[ends[:-1], following]
    new_after[:-1] = distances[order[i]].take(following)
    if i > 0:
        row = distances[order[i - 1]]
        before, new_before = row[order[i]], row.take(ends)
    else:
        before, new_before = 0.0, 0.0
    hits = new_before + new_after < before + after - 1e-12
    first = int(hits.argmax())
    return start + first if hits[first] else -1


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
    for start in sorted(
        set(np.linspace(0, count - 1, min(count, MAX_STARTS)).round().astype(int).tolist())
    ):
        order = _two_opt(distances, nearest_neighbour(distances, start))
        length = path_length(distances, order)
        if length < best_length - 1e-12:
            best, best_length = order, length
    return np.array(best)
