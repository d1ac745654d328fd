"""Which image-side limb of the 2D fit is which anatomical one, frame by frame
(section 3.4: "From the orientation, we also determine the left leg (arm) and the
right leg (arm)"; the 2D fit names limbs by image side, section 3.3).

Turned toward or away from the camera the orientation's image-side rule says it
(``mocap.lift.taylor.image_left_is_right``); in a profile it cannot, and the limbs
are followed through time from frames where it is known, across the moments where
the legs pass each other (``bridge_parity``).
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import maximum_filter1d

from mocap.body import JOINT_INDEX, LIMB_JOINTS, SIDES
from mocap.lift.taylor import image_left_is_right, runs

SEPARATED = 0.25     # distal joints this many limb lengths apart tell two limbs apart
# limb lengths of joint distance that a radian of segment turn counts as: a segment
# (half a limb) that turns a radian moves its distal joint about that far
ANGLE_WEIGHT = 0.5
MIN_APART = 3        # frames: shorter stretches apart are fit noise inside a crossing
STEP_S = 0.5         # s: about one step of a walk or run, so in a gait each leg leads within it
_J = JOINT_INDEX
# the joints whose image sides the arms' and the legs' parities swap
_PAIR_JOINTS = {"arms": LIMB_JOINTS["arm"][1:], "legs": LIMB_JOINTS["leg"][1:]}


def track_sides(joints2d: np.ndarray, known: np.ndarray, facing_x: np.ndarray, fps: float,
                away: np.ndarray | None = None, near: np.ndarray | None = None) -> np.ndarray:
    """(F, 2) bool: for arms and legs, whether the image-left limb is the right one.

    ``known`` (F, 2) holds 1 (swap), 0 (keep) or -1 (unknown: a profile, where the 2D
    fit names limbs by their image order, back and front). In a profile the legs keep
    their identity through the moments where they pass each other by
    ``bridge_parity``; the arms, which the fit cannot see cross, are named from the
    legs (``_stepping``). A run in profile throughout, facing one image side, takes
    the naming whose arms agree over the run with the near arm (``near`` (F,):
    mocap.facing.near_arm, > 0 where the image-left arm's outline shows across the
    trunk; facing image right the near arm is the performer's right one); where it
    says nothing, or the run turns, a stretch with nothing known takes the
    forward-facing convention (swap), or the backward one (keep) where the head's
    look says the performer faces away over most of the run (``away`` (F,) bool),
    which the user corrects with one joint override. ``facing_x`` (F,) is +1 facing
    image right; ``fps`` sets the window of a step.
    """
    out = np.zeros(known.shape, bool)
    away = np.zeros(len(known), bool) if away is None else away
    near = np.zeros(len(known)) if near is None else near
    half = max(1, int(round(STEP_S * fps)))
    ok = np.isfinite(joints2d).all(axis=(1, 2))
    for r in runs(ok):
        legs = _limb_pair(joints2d[r], _PAIR_JOINTS["legs"])
        arms = _limb_pair(joints2d[r], _PAIR_JOINTS["arms"])
        chains = _limb_pair(joints2d[r], LIMB_JOINTS["leg"])
        leg_px = _limb_px(joints2d[r], *LIMB_JOINTS["leg"][::2])
        parity = _anchored(bridge_parity(chains, leg_px), known[r, 1], away[r])
        out[r, 1] = np.where(known[r, 1] >= 0, known[r, 1] == 1, parity)
        out[r, 0] = _arm_sides(legs, arms, out[r, 1], known[r, 0], facing_x[r], leg_px, half)
        one_way = (known[r] < 0).all() and (facing_x[r] == facing_x[r.start]).all()
        if one_way and np.sum(near[r] * facing_x[r] * np.where(out[r, 0], 1.0, -1.0)) < 0:
            out[r, 1] = ~out[r, 1]
            out[r, 0] = _arm_sides(legs, arms, out[r, 1], known[r, 0], facing_x[r], leg_px, half)
    return out


def _arm_sides(legs: np.ndarray, arms: np.ndarray, legs_swap: np.ndarray, known: np.ndarray,
               facing_x: np.ndarray, leg_px: float, half: int) -> np.ndarray:
    """(F,) bool: whether the image-left arm is the right one, from the legs' sides
    (``_stepping``, ``_counter_phase``) where ``known`` (F,) says nothing (-1)."""
    stepping = _stepping(legs, legs_swap, facing_x, leg_px, half)
    sides = np.where(stepping, _counter_phase(legs, legs_swap, arms, facing_x), legs_swap)
    return np.where(known >= 0, known == 1, sides)


def _limb_pair(joints2d: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """(F, 2, len(names), 2): image-left/right limb, its joints ``names``, xy about the pelvis."""
    idx = [[_J[f"{n}_{s}"] for n in names] for s in SIDES]
    return joints2d[:, idx] - joints2d[:, None, None, _J["pelvis"]]


def _limb_px(joints2d: np.ndarray, root: str, tip: str) -> float:
    """A limb's typical image length (root to tip), pixels."""
    ends = joints2d[:, [_J[f"{root}_l"], _J[f"{tip}_l"]]]
    return max(float(np.median(np.linalg.norm(ends[:, 1] - ends[:, 0], axis=-1))), 1e-6)


def bridge_parity(pair: np.ndarray, limb_px: float) -> np.ndarray:
    """(F,) 0/1: whether each frame's two limbs are swapped relative to the first
    stretch where they are apart. ``pair`` (F, 2, 3, 2): each limb's root, middle and
    distal joint. While apart, each frame's limbs follow the nearer ones of the frame
    before; across each stretch where they are close together the swap is decided by
    ``_crosses``; close frames take the parity of the nearer side."""
    apart = np.linalg.norm(pair[:, 0, 2] - pair[:, 1, 2], axis=-1) / limb_px > SEPARATED
    pieces = [p for p in runs(apart) if p.stop - p.start >= MIN_APART]
    parity = np.zeros(len(pair), int)
    if not pieces:
        return parity
    flat = pair[:, :, 1:].reshape(len(pair), 2, -1)
    current = 0
    for k, piece in enumerate(pieces):
        if k:
            current = int(_crosses(pair, pieces[k - 1], piece, parity, limb_px))
            middle = (pieces[k - 1].stop + piece.start + 1) // 2
            parity[middle:piece.start] = current
        for t in range(piece.start, piece.stop):
            if t > piece.start:
                step = np.linalg.norm(flat[t] - flat[t - 1], axis=-1).sum()
                cross = np.linalg.norm(flat[t, ::-1] - flat[t - 1], axis=-1).sum()
                current ^= int(cross < step)
            parity[t] = current
        end = pieces[k + 1].start if k + 1 < len(pieces) else len(pair)
        parity[piece.stop:end] = current
    return parity


def _crosses(pair: np.ndarray, before: slice, after: slice, parity: np.ndarray, limb_px: float) -> bool:
    """Whether the limbs of ``after``'s first frame, as labelled, are in the other
    order than ``before``'s limbs put in one order by ``parity`` so far.

    Each limb is followed across the stretch between at constant velocity from
    either side (crossing limbs continue, turning limbs come back): its middle and
    distal joints and its two segments' image angles. The angles carry a limb that
    swings past the other, even one that speeds up (a kick), where its joints come
    close to the other's and a fit that loses one segment there misplaces them."""
    ordered = pair.copy()
    ordered[parity == 1] = pair[parity == 1, ::-1]
    t0, t1 = before.stop - 1, after.start
    a0, a1 = max(before.start, t0 - 2), min(after.stop - 1, t1 + 2)
    later = pair[a1] if _same_order(pair[:, :, 1:], t1, a1) else pair[a1, ::-1]
    ahead = _ahead(ordered[a0], ordered[t0], t0 - a0, t1 - t0)
    back = _ahead(later, pair[t1], a1 - t1, t1 - t0)
    keep = _mismatch(ahead, pair[t1], limb_px) + _mismatch(back, ordered[t0], limb_px)
    swap = (_mismatch(ahead, pair[t1, ::-1], limb_px)
            + _mismatch((back[0][::-1], back[1][::-1]), ordered[t0], limb_px))
    return swap < keep


def _limb_features(limbs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(2, 2, 2) middle and distal joints and (2, 2) segment angles (radians) of
    two limbs (2, 3, 2) given by their root, middle and distal joints."""
    d = np.diff(limbs, axis=1)
    return limbs[:, 1:], np.arctan2(d[..., 0], d[..., 1])


def _ahead(earlier: np.ndarray, last: np.ndarray, span: int, frames: int) -> tuple[np.ndarray, np.ndarray]:
    """Two limbs' joints and angles (``_limb_features``) ``frames`` on from ``last``
    at their pace since ``earlier``, ``span`` frames before it (either way in time)."""
    (p0, q0), (p1, q1) = _limb_features(earlier), _limb_features(last)
    pace = frames / max(1, span)
    return p1 + (p1 - p0) * pace, q1 + _wrapped(q1 - q0) * pace


def _mismatch(predicted: tuple[np.ndarray, np.ndarray], limbs: np.ndarray, limb_px: float) -> float:
    """How far two limbs (2, 3, 2) lie from a prediction (``_ahead``): their middle
    and distal joints' distances in limb lengths, plus ANGLE_WEIGHT times their
    segments' turns in radians."""
    joints, angles = _limb_features(limbs)
    return float(np.linalg.norm(predicted[0] - joints, axis=-1).sum() / limb_px
                 + ANGLE_WEIGHT * np.abs(_wrapped(predicted[1] - angles)).sum())


def _wrapped(radians: np.ndarray) -> np.ndarray:
    """Angle differences in [-pi, pi)."""
    return (radians + np.pi) % (2 * np.pi) - np.pi


def _same_order(flat: np.ndarray, t: int, u: int) -> bool:
    """Whether the limbs of frame u follow those of frame t in the same order."""
    return (np.linalg.norm(flat[u] - flat[t], axis=-1).sum()
            <= np.linalg.norm(flat[u, ::-1] - flat[t], axis=-1).sum())


def _anchored(parity: np.ndarray, known: np.ndarray, away: np.ndarray, reach: int = 10) -> np.ndarray:
    """Relative parity -> swap per frame. Each stretch of unknown frames takes the
    constant that agrees with most known frames within ``reach`` of it (else in the
    whole run); with none known, the forward-facing convention (swap), or the
    backward one (keep) if the head looks away (``away``) in most frames."""
    out = (parity ^ int(away.mean() <= 0.5)).astype(bool)
    for stretch in runs(known < 0):
        near = slice(max(0, stretch.start - reach), min(len(known), stretch.stop + reach))
        votes = np.flatnonzero(known[near] >= 0) + near.start
        if not len(votes):
            votes = np.flatnonzero(known >= 0)
        if len(votes):
            flip = np.mean(parity[votes] != known[votes]) > 0.5
            out[stretch] = (parity[stretch] ^ int(flip)).astype(bool)
    return out


def _stepping(legs: np.ndarray, legs_swap: np.ndarray, facing_x: np.ndarray, leg_px: float,
              half: int) -> np.ndarray:
    """(F,) bool: frames of a gait, where within ``half`` frames either side the right
    leg is clearly ahead (SEPARATED leg lengths) at one time and the left at another.
    There the arms swing opposite to the legs (``_counter_phase``); elsewhere (standing,
    bending, kicking, jumping, even with the feet apart) each arm hangs from the
    shoulder above its own side's hip, so the arms take the legs' names."""
    lead = (legs[:, 1, :, 0].mean(-1) - legs[:, 0, :, 0].mean(-1)) * facing_x   # image-right leg ahead
    clear = np.abs(lead) > SEPARATED * leg_px
    right_ahead = legs_swap == (lead < 0)
    took_turns = [maximum_filter1d((clear & ahead).astype(np.uint8), 2 * half + 1, mode="constant") > 0
                  for ahead in (right_ahead, ~right_ahead)]
    return took_turns[0] & took_turns[1]


def _counter_phase(legs: np.ndarray, legs_swap: np.ndarray, arms: np.ndarray,
                   facing_x: np.ndarray) -> np.ndarray:
    """Arm swaps in a profile from the legs: the arm in front is on the other side
    than the leg in front (gait); where the legs are level the last decision holds."""
    lead = (legs[:, 1, :, 0].mean(-1) - legs[:, 0, :, 0].mean(-1)) * facing_x   # image-right leg ahead
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


def known_sides(orientations: list[str | None], overrides: dict[int, dict[str, tuple[float, float]]],
                joints2d: np.ndarray) -> np.ndarray:
    """(F, 2) int8 for ``track_sides``: the orientation's image-side rule (forward:
    swap, backward: keep, profile: unknown), and where the user placed an elbow, wrist,
    knee or ankle, the assignment that puts that side's limb nearer to it."""
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
