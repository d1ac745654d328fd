"""The smoothest sequence of discrete per-frame states (a foreshortening sign pair, a limb's
depth solution) by Viterbi search: state costs plus acceleration costs."""

from __future__ import annotations

import numpy as np

DEPTH_SMOOTH_S = (
    0.1  # seconds: Gaussian sigma of reconstructed depths over time (track.perspective; the old per-frame lift)
)


def smoothest_states(
    values: np.ndarray, emission: np.ndarray, allowed: np.ndarray | None = None, squared: bool = False
) -> np.ndarray:
    """(F,) state per frame minimising sum(emission) + sum ||x[t+1] - 2 x[t] + x[t-1]||
    (squared with ``squared``). ``values`` (F, S, D): each state's position; ``emission``
    (F, S): state costs; ``allowed`` (F, S): hard mask, one allowed state per frame."""
    n, s = emission.shape
    cost = np.where(allowed if allowed is not None else True, emission, np.inf)
    if n == 1:
        return np.array([int(np.argmin(cost[0]))])
    # acc[t, a, b, c]: the acceleration of states a, b, c at frames t, t+1, t+2
    jerk = values[2:, None, None, :] - 2 * values[1:-1, None, :, None] + values[:-2, :, None, None]
    acc = (jerk**2).sum(-1) if squared else np.linalg.norm(jerk, axis=-1)
    # best[a, b]: the cheapest path whose last two states are a (t-1), b (t)
    best = cost[0][:, None] + cost[1][None, :]
    back = []
    for t in range(2, n):
        total = best[:, :, None] + acc[t - 2]
        back.append(total.argmin(axis=0))  # (b, c)
        best = total.min(axis=0) + cost[t][None, :]
    a, b = np.unravel_index(int(np.argmin(best)), best.shape)
    path = [b, a]
    for arg in reversed(back):
        a, b = arg[a, b], a
        path.append(a)
    return np.array(path[::-1])


def two_state_path(costs: np.ndarray, switch: np.ndarray) -> np.ndarray:
    """(F,) 0/1 minimising sum(costs[t, state]) + sum(switch[t - 1] where the state
    changes between t - 1 and t): a two-state Viterbi search."""
    best, back = costs[0].copy(), []
    for t in range(1, len(costs)):
        stay, move = best, best[::-1] + switch[t - 1]
        back.append(move < stay)
        best = np.minimum(stay, move) + costs[t]
    state = int(np.argmin(best))
    path = [state]
    for moved in reversed(back):
        state = state ^ int(moved[state])
        path.append(state)
    return np.array(path[::-1])
