"""Each segment's foreshortening sign over a clip, chosen by the cost of the 3D each choice implies:
a Viterbi over per-frame sign states, torso and head alone, each limb's two segments
together. A state costs its disagreement with the person model's signed depth (or with the first
guess where it gives none) and, for a limb, the hinge limit its 3D breaks; a flip between frames
costs the accelerations of the depth step it makes; the user's held signs are walls."""

from __future__ import annotations

import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, SEGMENT_INDEX, SEGMENT_JOINTS
from mocap.lift.clipdata import HINGES, SEGMENT_CLASS, ClipArrays, Weights, depth_scale
from mocap.lift.taylor import UNIT_M, runs

WALL = 1e6  # the cost of a state against a held sign
# (upper segment, lower segment, its HINGES entry) of every limb
LIMB_SEGMENTS = tuple(
    (
        SEGMENT_INDEX[f"upper_{kind}_{side}"],
        SEGMENT_INDEX[f"lower_{kind}_{side}"],
        next(i for i, hinge in enumerate(HINGES) if hinge[1] == f"{middle}_{side}"),
    )
    for kind, middle in (("arm", "elbow"), ("leg", "knee"))
    for side in "lr"
)
_PAIRS = ((0, 0), (0, 1), (1, 0), (1, 1))  # a limb's states: (upper, lower), 0 toward, 1 away
_STATES = {1: ((0,), (1,)), 2: _PAIRS}  # a chain's states by its number of segments


def sign_paths(
    clip: ClipArrays, model: np.ndarray, lengths: np.ndarray, weights: Weights, walls: np.ndarray | None = None
) -> np.ndarray:
    """(F, 10) +1 / -1 over every person stretch of ``clip``, each segment's |dZ| taken from ``model``
    (F, 16, 3) model units at class lengths ``lengths``; ``walls`` (F, 10) signs that must hold beside
    the user's (0: free)."""
    out = np.where(np.asarray(clip.signs) < 0, -1, 1).astype(int)
    for frames, segments, cost, flip in _chains(clip, model, lengths, weights, walls):
        path = np.array(_STATES[len(segments)])[viterbi(cost, flip)]
        out[frames, list(segments)] = np.where(path == 0, 1, -1)
    return out


def sign_margins(clip: ClipArrays, model: np.ndarray, lengths: np.ndarray, weights: Weights) -> np.ndarray:
    """(F, 10) how much more the best sign paths (``sign_paths``) cost with each segment's sign on each
    frame the other way: near 0 where toward and away explain the clip alike (a close call for the
    user to look at), WALL and above where the user holds it; NaN without a person."""
    out = np.full(clip.signs.shape, np.nan)
    for frames, segments, cost, flip in _chains(clip, model, lengths, weights):
        through = min_marginals(cost, flip)  # (n, S)
        states = np.array(_STATES[len(segments)])  # (S, len(segments)) 0 toward, 1 away
        for col, k in enumerate(segments):
            toward = np.where(states[:, col] == 0, through, np.inf).min(axis=1)
            away = np.where(states[:, col] == 1, through, np.inf).min(axis=1)
            out[frames, k] = np.abs(toward - away)
    return out


def _chains(clip: ClipArrays, model: np.ndarray, lengths: np.ndarray, weights: Weights, walls=None):
    """(frames, segments, cost (n, S), transition (n - 1, S, S)) of each sign chain of every person
    stretch: the torso and the head alone (states _STATES[1]), each limb's two segments together
    (_STATES[2]); the cost of a state its disagreement with the person model's signed depth (or
    the first guess), a limb's also the hinge limit it breaks, a flip the accelerations it makes."""
    w, h = weights, BODY_HEIGHT
    vec = model[:, SEGMENT_JOINTS[:, 1]] - model[:, SEGMENT_JOINTS[:, 0]]  # (F, 10, 3)
    size = np.abs(vec[..., 2])
    held = clip.held_signs() if walls is None else np.where(clip.held_signs() != 0, clip.held_signs(), walls)
    measured = np.full(clip.signs.shape, np.nan)
    if clip.depths is not None:
        measured = np.where(held != 0, np.nan, clip.signs) * clip.depths * depth_scale(clip, lengths)
    sa = w.accel / (UNIT_M * clip.fps**2)

    def emission(k: int, f: slice) -> np.ndarray:
        """(n, 2) costs of sign +1, -1 of segment k."""
        cost = np.zeros((f.stop - f.start, 2))
        m, s = measured[f, k], size[f, k]
        for col, sign in enumerate((1, -1)):
            guessed = 2 * (s * (clip.signs[f, k] != sign)) ** 2 / (w.sigma_guess * h) ** 2
            seen = (m - sign * s) ** 2 / (2 * (w.sigma_depth * h) ** 2)
            cost[:, col] = np.where(np.isfinite(m), seen, guessed)
            cost[:, col] += np.where((held[f, k] != 0) & (held[f, k] != sign), WALL, 0.0)
        return cost

    def flips(k: int, f: slice) -> np.ndarray:
        """(n - 1,) the cost of a sign change between consecutive frames."""
        step = size[f.start : f.stop - 1, k] + size[f.start + 1 : f.stop, k]
        return step**2 / sa**2

    for r in runs(clip.person):
        for k in (SEGMENT_INDEX["torso"], SEGMENT_INDEX["head"]):
            yield r, (k,), emission(k, r), flips(k, r)[:, None, None] * (1 - np.eye(2))[None]
        for upper, lower, hinge in LIMB_SEGMENTS:
            eu, el = emission(upper, r), emission(lower, r)
            cost = np.stack([eu[:, a] + el[:, b] for a, b in _PAIRS], axis=1)
            cost += _hinge_costs(model[r], vec[r], size[r], lengths, upper, lower, hinge, w)
            fu, fl = flips(upper, r), flips(lower, r)
            flip = np.stack(
                [np.stack([fu * (a != c) + fl * (b != d) for c, d in _PAIRS], axis=1) for a, b in _PAIRS], axis=1
            )
            yield r, (upper, lower), cost, flip


def _hinge_costs(model, vec, size, lengths, upper: int, lower: int, hinge: int, w: Weights) -> np.ndarray:
    """(n, 4) the hinge penalty of each of a limb's sign pairs (_PAIRS) on poses ``model`` (n, 16, 3)."""
    left, right, bend = HINGES[hinge][3:]
    sigma = w.hinge_knee if bend > 0 else w.hinge_elbow
    axis = model[:, JOINT_INDEX[left]] - model[:, JOINT_INDEX[right]]
    scale = (
        lengths[SEGMENT_CLASS[upper]] * lengths[SEGMENT_CLASS[lower]] * max(np.linalg.norm(axis, axis=-1).mean(), 1e-9)
    )
    out = np.zeros((len(model), len(_PAIRS)))
    for col, (a, b) in enumerate(_PAIRS):
        t, u = vec[:, upper].copy(), vec[:, lower].copy()
        t[:, 2] = size[:, upper] * (1 - 2 * a)
        u[:, 2] = size[:, lower] * (1 - 2 * b)
        gap = np.maximum(-bend * np.einsum("fi,fi->f", np.cross(t, u), axis) / scale, 0.0)
        out[:, col] = 0.5 * (gap / sigma) ** 2
    return out


def min_marginals(emission: np.ndarray, transition: np.ndarray) -> np.ndarray:
    """(F, S) the least total cost of a path through each state on each frame (``viterbi``'s costs):
    the least cost of reaching it plus that of going on from it."""
    ahead, behind = emission.copy(), np.zeros(emission.shape)
    for f in range(1, len(emission)):
        ahead[f] += (ahead[f - 1][:, None] + transition[f - 1]).min(axis=0)
    for f in range(len(emission) - 2, -1, -1):
        behind[f] = (transition[f] + (emission[f + 1] + behind[f + 1])[None]).min(axis=1)
    return ahead + behind


def viterbi(emission: np.ndarray, transition: np.ndarray) -> np.ndarray:
    """(F,) the state indices of least total cost: ``emission`` (F, S), ``transition`` (F - 1, S, S)
    from a state to a state."""
    total = emission[0].copy()
    back = np.zeros(emission.shape, int)
    for f in range(1, len(emission)):
        step = total[:, None] + transition[f - 1]
        back[f] = step.argmin(axis=0)
        total = step.min(axis=0) + emission[f]
    path = np.zeros(len(emission), int)
    path[-1] = int(total.argmin())
    for f in range(len(emission) - 1, 0, -1):
        path[f - 1] = back[f, path[f]]
    return path
