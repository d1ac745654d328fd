"""Which image-side limb of the 2D fit is which anatomical one, per frame (section 3.4: "From the
orientation, we also determine the left leg (arm) and the right leg (arm)"). Turned views follow
``taylor.image_left_is_right``; in a profile the legs are followed through their crossings
(``bridge_parity``) and named by a two-state Viterbi search (``naming_path``)."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import maximum_filter1d, median_filter

from mocap.body import JOINT_INDEX, LIMB_JOINTS, SIDES
from mocap.lift.taylor import image_left_is_right, runs
from mocap.smoothest import two_state_path

SEPARATED = 0.25  # distal joints this many limb lengths apart tell two limbs apart
# limb lengths of joint distance that a radian of segment turn counts as: a segment
# (half a limb) that turns a radian moves its distal joint about that far
ANGLE_WEIGHT = 0.5
MIN_APART = 3  # frames: shorter stretches apart are fit noise inside a crossing
STEP_S = 0.5  # s: about one step of a walk or run, so in a gait each leg leads within it
CROSSING_S = 0.15  # s with the legs close together that a constant pace carries them across
# The costs of a naming, in the units of bridge_parity's certainty (limb lengths of
# joint distance between the two ways of following the legs, a crossing's 1-2):
LINK_FLOOR = 0.5  # renaming the legs where nothing follows them (close together throughout)
NEAR_WEIGHT = (0.1, 3.0)  # per unit of the near arm's and the near leg's evidence (mocap.silhouette.facing.near_limbs)
CONVENTION_COST = 1e-3  # per frame against the forward (or, looking away, backward) convention
KNOWN_COST = 1e6  # per frame against what the user said
_J = JOINT_INDEX
_STATES = np.array([[False, True]])  # the legs' naming: keep, swap
# the joints whose image sides the arms' and the legs' parities swap
_PAIR_JOINTS = {"arms": LIMB_JOINTS["arm"][1:], "legs": LIMB_JOINTS["leg"][1:]}


def track_sides(
    joints2d: np.ndarray,
    known: np.ndarray,
    facing_x: np.ndarray,
    fps: float,
    away: np.ndarray | None = None,
    near: np.ndarray | None = None,
    rule: np.ndarray | None = None,
) -> np.ndarray:
    """(F, 3) bool: whether the image-left arm, the image-left leg (hip) is the right one, and whether the
    knees and ankles belong to the other hip. Per person run the legs' naming minimises ``_naming_costs``
    plus each departure's certainty from the followed legs (``naming_path``). ``known`` (F, 2) arms, legs:
    1 swap, 0 keep, -1 unknown (the user's, held); ``rule`` (F,) > 0 swap; ``away`` (F,) bool: keep by
    default, not swap; ``facing_x`` (F,) +1 image right; ``near`` (F, 2) (silhouette.facing.near_limbs)
    decides a run in profile throughout; arms by ``_arm_sides`` in a profile; ``fps`` sets the windows."""
    n = len(known)
    out = np.zeros((n, 3), bool)
    away = np.zeros(n, bool) if away is None else away
    near = np.zeros((n, 2)) if near is None else near
    rule = np.zeros(n) if rule is None else rule
    half = max(1, int(round(STEP_S * fps)))
    ok = np.isfinite(joints2d).all(axis=(1, 2))
    for r in runs(ok):
        legs = _limb_pair(joints2d[r], _PAIR_JOINTS["legs"])
        arms = _limb_pair(joints2d[r], _PAIR_JOINTS["arms"])
        leg_px = _limb_px(joints2d[r], *LIMB_JOINTS["leg"][::2])
        crossing = max(1, int(round(CROSSING_S * fps)))
        parity, links = bridge_parity(_limb_pair(joints2d[r], LIMB_JOINTS["leg"]), leg_px, crossing)
        followed = parity.astype(bool)
        arms_kept = _arm_sides(legs, arms, followed, facing_x[r], leg_px, half) ^ followed
        turned = (known[r, 1] >= 0) | (np.abs(rule[r]) >= 1.0)
        profile = (known[r] < 0).all() and not turned.any() and (facing_x[r] == facing_x[r.start]).all()
        links = np.maximum(links, LINK_FLOOR)
        hips = naming_path(_naming_costs(known[r], rule[r], arms_kept, away[r]), parity, links)
        costs = _naming_costs(known[r], rule[r] * _leg_order(legs, leg_px, crossing), arms_kept, away[r])
        knees = naming_path(costs, parity, links)
        if profile:
            flip = _nearer_naming(knees, costs + _near_costs(near[r] * facing_x[r, None], arms_kept)) != knees
            knees, hips = knees ^ flip, hips ^ flip
        out[r, 1], out[r, 2] = hips, hips != knees
        arm_sides = np.where(turned, hips, _arm_sides(legs, arms, hips, facing_x[r], leg_px, half))
        out[r, 0] = np.where(known[r, 0] >= 0, known[r, 0] == 1, arm_sides)
    return out


def _leg_order(legs: np.ndarray, leg_px: float, crossing: int) -> np.ndarray:
    """(F,) in [-1, 1]: 1 where the fit's image-left leg (``legs`` (F, 2, 2, 2): knee, ankle per side) lies
    image-left, down to -1 at SEPARATED leg lengths image-right of the other (median over ``crossing``)."""
    across = (legs[:, 1, :, 0] - legs[:, 0, :, 0]).mean(-1) / (SEPARATED * leg_px)
    held = median_filter(across, 2 * crossing + 1, mode="nearest")
    return np.where(held < 0, np.clip(held, -1.0, 0.0), 1.0)


def _naming_costs(known: np.ndarray, rule: np.ndarray, arms_kept: np.ndarray, away: np.ndarray) -> np.ndarray:
    """(F, 2) each frame's cost of the legs' keep/swap: KNOWN_COST against ``known`` (legs, or arms
    via ``arms_kept`` (F,)), |rule| against ``rule``, CONVENTION_COST against the convention (``away``)."""
    arm_swap = arms_kept[:, None] ^ _STATES
    costs = np.abs(rule)[:, None] * (_STATES != (rule > 0)[:, None]) + CONVENTION_COST * (_STATES == away[:, None])
    costs += KNOWN_COST * ((known[:, [1]] >= 0) & (_STATES != (known[:, [1]] == 1)))
    return costs + KNOWN_COST * ((known[:, [0]] >= 0) & (arm_swap != (known[:, [0]] == 1)))


def _near_costs(near: np.ndarray, arms_kept: np.ndarray) -> np.ndarray:
    """(F, 2) cost of the legs' keep/swap against ``near`` (F, 2) arms, legs (> 0: image-left is
    right), NEAR_WEIGHT times their sizes; the arms named through ``arms_kept``."""
    arm_swap = arms_kept[:, None] ^ _STATES
    return NEAR_WEIGHT[0] * np.abs(near[:, [0]]) * (arm_swap != (near[:, [0]] > 0)) + NEAR_WEIGHT[1] * np.abs(
        near[:, [1]]
    ) * (_STATES != (near[:, [1]] > 0))


def _nearer_naming(swap: np.ndarray, costs: np.ndarray) -> np.ndarray:
    """``swap`` (F,) or its opposite on every frame, whichever ``costs`` (F, 2) sum lower: the near
    limbs decide over a whole profile, as one frame's outlines say little."""
    frames = np.arange(len(swap))
    return ~swap if costs[frames, (~swap).astype(int)].sum() < costs[frames, swap.astype(int)].sum() else swap


def naming_path(costs: np.ndarray, parity: np.ndarray, links: np.ndarray) -> np.ndarray:
    """(F,) bool legs' naming minimising ``costs`` (F, 2) plus ``links`` (F - 1,) where it departs from
    the followed ``parity`` (F,) 0/1: a two-state Viterbi over which leg the first followed one is."""
    flip = parity.astype(bool)
    anchored = np.where(flip[:, None], costs[:, ::-1], costs)
    return two_state_path(anchored, links).astype(bool) ^ flip


def _arm_sides(
    legs: np.ndarray, arms: np.ndarray, legs_swap: np.ndarray, facing_x: np.ndarray, leg_px: float, half: int
) -> np.ndarray:
    """(F,) bool: whether the image-left arm is the right one in a profile, from the legs' sides."""
    stepping = _stepping(legs, legs_swap, facing_x, leg_px, half)
    return np.where(stepping, _counter_phase(legs, legs_swap, arms, facing_x), legs_swap)


def _limb_pair(joints2d: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """(F, 2, len(names), 2): image-left/right limb, its joints ``names``, xy about the pelvis."""
    idx = [[_J[f"{n}_{s}"] for n in names] for s in SIDES]
    return joints2d[:, idx] - joints2d[:, None, None, _J["pelvis"]]


def _limb_px(joints2d: np.ndarray, root: str, tip: str) -> float:
    """A limb's typical image length (root to tip), pixels."""
    ends = joints2d[:, [_J[f"{root}_l"], _J[f"{tip}_l"]]]
    return max(float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=-1))), 1e-6)


def bridge_parity(pair: np.ndarray, limb_px: float, crossing: int = 1) -> tuple[np.ndarray, np.ndarray]:
    """(F,) 0/1: limbs swapped relative to the first stretch apart, and (F - 1,) each link's certainty,
    of ``pair`` (F, 2, 3, 2) (root, middle, distal joint). Apart, limbs follow the nearer of the frame
    before; across a close stretch ``_crosses`` decides, less surely past ``crossing`` frames."""
    n = len(pair)
    apart = np.linalg.norm(pair[:, 0, 2] - pair[:, 1, 2], axis=-1) / limb_px > SEPARATED
    pieces = [p for p in runs(apart) if p.stop - p.start >= MIN_APART]
    parity, links = np.zeros(n, int), np.zeros(max(n - 1, 0))
    if not pieces:
        return parity, links
    flat = pair[:, :, 1:].reshape(n, 2, -1)
    current = 0
    for k, piece in enumerate(pieces):
        if k:
            margin = _crosses(pair, pieces[k - 1], piece, parity, limb_px)
            current = int(margin > 0)
            middle = (pieces[k - 1].stop + piece.start + 1) // 2
            parity[middle : piece.start] = current
            close = piece.start - pieces[k - 1].stop
            links[pieces[k - 1].stop - 1 : piece.start] = abs(margin) * min(1.0, crossing / close)
        parity[piece.start] = current
        for t in range(piece.start + 1, piece.stop):
            step = np.linalg.norm(flat[t] - flat[t - 1], axis=-1).sum()
            cross = np.linalg.norm(flat[t, ::-1] - flat[t - 1], axis=-1).sum()
            current ^= int(cross < step)
            links[t - 1] = abs(cross - step) / limb_px
            parity[t] = current
        end = pieces[k + 1].start if k + 1 < len(pieces) else n
        parity[piece.stop : end] = current
    return parity, links


def _crosses(pair: np.ndarray, before: slice, after: slice, parity: np.ndarray, limb_px: float) -> float:
    """How much more ``after``'s first frame has its limbs in the other order than ``before``'s (ordered
    by ``parity``; > 0: crossed): the weaker of the forward and backward constant-pace predictions of
    joints and segment angles (``_ahead``), 0 where they disagree."""
    ordered = pair.copy()
    ordered[parity == 1] = pair[parity == 1, ::-1]
    t0, t1 = before.stop - 1, after.start
    a0, a1 = max(before.start, t0 - 2), min(after.stop - 1, t1 + 2)
    later = pair[a1] if _same_order(pair[:, :, 1:], t1, a1) else pair[a1, ::-1]
    ahead = _order_margin(_ahead(ordered[a0], ordered[t0], t0 - a0, t1 - t0), pair[t1], limb_px)
    back = _order_margin(_ahead(later, pair[t1], a1 - t1, t1 - t0), ordered[t0], limb_px)
    return min(ahead, back, key=abs) if ahead * back > 0 else 0.0


def _limb_features(limbs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(2, 2, 2) middle and distal joints and (2, 2) segment angles (radians) of limbs (2, 3, 2)."""
    d = np.diff(limbs, axis=1)
    return limbs[:, 1:], np.arctan2(d[..., 0], d[..., 1])


def _ahead(earlier: np.ndarray, last: np.ndarray, span: int, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """``_limb_features`` ``frames`` on from ``last`` at the pace since ``earlier`` (``span`` frames away)."""
    (p0, q0), (p1, q1) = _limb_features(earlier), _limb_features(last)
    pace = frames / max(1, span)
    return p1 + (p1 - p0) * pace, q1 + _wrapped(q1 - q0) * pace


def _order_margin(predicted: tuple[np.ndarray, np.ndarray], limbs: np.ndarray, limb_px: float) -> float:
    """How much nearer limbs (2, 3, 2) lie to ``predicted`` in the other order than in theirs (> 0)."""
    return _mismatch(predicted, limbs, limb_px) - _mismatch(predicted, limbs[::-1], limb_px)


def _mismatch(predicted: tuple[np.ndarray, np.ndarray], limbs: np.ndarray, limb_px: float) -> float:
    """How far limbs (2, 3, 2) lie from ``predicted``: joints in limb lengths + ANGLE_WEIGHT x turns (rad)."""
    joints, angles = _limb_features(limbs)
    return float(
        np.linalg.norm(predicted[0] - joints, axis=-1).sum() / limb_px
        + ANGLE_WEIGHT * np.abs(_wrapped(predicted[1] - angles)).sum()
    )


def _wrapped(radians: np.ndarray) -> np.ndarray:
    """Angle differences in [-pi, pi)."""
    return (radians + np.pi) % (2 * np.pi) - np.pi


def _same_order(flat: np.ndarray, t: int, u: int) -> bool:
    """Whether the limbs of frame u follow those of frame t in the same order."""
    return np.linalg.norm(flat[u] - flat[t], axis=-1).sum() <= np.linalg.norm(flat[u, ::-1] - flat[t], axis=-1).sum()


def _stepping(legs: np.ndarray, legs_swap: np.ndarray, facing_x: np.ndarray, leg_px: float, half: int) -> np.ndarray:
    """(F,) bool gait frames: within ``half`` frames either side each leg is clearly ahead at some time;
    there arms swing opposite the legs (``_counter_phase``), elsewhere they take the legs' names."""
    lead = (legs[:, 1, :, 0].mean(-1) - legs[:, 0, :, 0].mean(-1)) * facing_x  # image-right leg ahead
    clear = np.abs(lead) > SEPARATED * leg_px
    right_ahead = legs_swap == (lead < 0)
    took_turns = [
        maximum_filter1d((clear & ahead).astype(np.uint8), 2 * half + 1, mode="constant") > 0
        for ahead in (right_ahead, ~right_ahead)
    ]
    return took_turns[0] & took_turns[1]


def _counter_phase(legs: np.ndarray, legs_swap: np.ndarray, arms: np.ndarray, facing_x: np.ndarray) -> np.ndarray:
    """(F,) bool arm swaps in a profile: front arm opposite the front leg; level legs hold the last."""
    lead = (legs[:, 1, :, 0].mean(-1) - legs[:, 0, :, 0].mean(-1)) * facing_x  # image-right leg ahead
    arm_lead = (arms[:, 1, :, 0].mean(-1) - arms[:, 0, :, 0].mean(-1)) * facing_x
    out = np.ones(len(legs), bool)
    last = True
    for t in range(len(legs)):
        if abs(lead[t]) > 1e-6 and abs(arm_lead[t]) > 1e-6:
            front_leg_right = legs_swap[t] == (lead[t] < 0)
            # the front arm is the left one then; the image-left arm is right iff it is behind
            last = front_leg_right == (arm_lead[t] > 0)
        out[t] = last
    return out


def known_sides(
    orientations: list[str | None], overrides: dict[int, dict[str, tuple[float, float]]], joints2d: np.ndarray
) -> np.ndarray:
    """(F, 2) int8 ``known`` for ``track_sides``: the orientation's rule (forward 1, backward 0, profile
    -1) and, where the user placed an elbow, wrist, knee or ankle, the naming that puts it nearer."""
    known = np.full((len(orientations), 2), -1, np.int8)
    for i, name in enumerate(orientations):
        rule = None if name is None else image_left_is_right(name)
        if rule is not None:
            known[i] = int(rule)
    for i, joints in overrides.items():
        for p, names in enumerate(_PAIR_JOINTS.values()):
            for joint, xy in joints.items():
                kind, _, side = joint.rpartition("_")
                if kind in names and np.isfinite(joints2d[i]).all():
                    same = np.linalg.norm(joints2d[i, _J[joint]] - xy)
                    other = np.linalg.norm(joints2d[i, _J[f"{kind}_{'r' if side == 'l' else 'l'}"]] - xy)
                    known[i, p] = int(other < same)
    return known
