"""First guesses where the user said nothing (the paper asks the user): orientation and signs.

Facing side from walking direction and knee bends; forward or backward (the Necker ambiguity) from
body growth, else the head's look (silhouette.facing.facing_away), else forward. Signs from joint limits
and the smoothest depths (second-order Viterbi); user entries are hard constraints on their frames."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import median_filter

from mocap.body import (
    JOINT_INDEX,
    LIMB_JOINTS,
    LIMBS,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SIDE_SIGN,
    SIDES,
    knee_bend,
    limb,
    limb_penalty,
    unit,
)
from mocap.lift.taylor import (
    LENGTH,
    TOWARD,
    exchange_legs,
    facing_yaw,
    image_left_is_right,
    lateral_axis,
    median_width,
    relative_depths,
    runs,
)
from mocap.smoothest import smoothest_states, two_state_path

NEGLIGIBLE = 0.25  # |dZ| / length at or below which a sign does not matter
PROFILE_SPREAD = 0.5  # torso spread below which the body is in profile (yaw 60..120)
RULE_SPREAD = (0.25, 0.65)  # torso spread over which a profile's image-side rule ramps up (rule_evidence)
PROFILE_RULE = 0.1  # the image-side rule's weight in a profile, at most (rule_evidence)
WALK_SPEED = 0.15  # body heights per second: slower pelvis tracks say nothing
GROWTH = 0.05  # relative body-size change per second that says toward/away
AWAY_SAYS = 0.25  # pooled head evidence (mocap.silhouette.facing.facing_away) that says away
CUE_WINDOW_S = 1.0  # half-window over which direction cues are pooled, seconds
MIN_RUN_S = 0.5  # orientation runs shorter than this join their neighbours
LIMIT_WEIGHT = 30.0  # model units of acceleration per unit of joint-limit violation
DEPTH_FILTER_S = 0.15  # seconds: a running median of each |dZ| the signs are chosen on
SAGITTAL_WEIGHT = 0.5  # limit units per length of depth against the sagittal-plane prior
_J = JOINT_INDEX
SWITCH_WEIGHT = 2.0  # per leg length apart: exchanging the legs' names between frames
SAGITTAL_SHOWS = 0.5  # |sin yaw| from which image x shows the legs' swing (yaw 30-150)
KEEP_RULE = 0.1  # per frame: overruling the image-side rule without a sign against it
_LEG_SEGMENTS = [SEGMENT_INDEX[s] for side in SIDES for s in limb("leg", side).segments]
_SIGN_PAIRS = np.array([[1, 1], [1, -1], [-1, 1], [-1, -1]])


# -- orientation ----------------------------------------------------------------------


def facing_side_cues(joints2d: np.ndarray, body_px: np.ndarray, fps: float) -> np.ndarray:
    """(F,) evidence that the performer faces image right (> 0) or left (< 0):
    pelvis speed in body heights per second (if brisk), plus the knees' bends."""
    pelvis = joints2d[:, _J["pelvis"], 0] / body_px
    speed = np.gradient(pelvis) * fps if len(pelvis) > 1 else np.zeros(1)
    walk = np.where(np.abs(speed) > WALK_SPEED, np.sign(speed), 0.0)
    knees = sum(knee_bend(joints2d, side) for side in SIDES) / body_px
    return 2.0 * walk + np.clip(10.0 * knees, -1.0, 1.0)


def pooled(values: np.ndarray, fps: float, pool=np.nanmean) -> np.ndarray:
    """Each frame's ``pool`` (mean) of the finite ``values`` within CUE_WINDOW_S."""
    half = max(1, int(round(CUE_WINDOW_S * fps)))
    out = np.full(len(values), np.nan)
    for i in np.flatnonzero(np.isfinite(values)):
        out[i] = pool(values[max(0, i - half) : i + half + 1])
    return out


def looks_away(away: np.ndarray | None, fps: float, n: int) -> np.ndarray:
    """(F,) bool: where the heads' look (``away``, pooled) says facing away; all False without it."""
    if away is None:
        return np.zeros(n, bool)
    return np.nan_to_num(pooled(np.asarray(away, float), fps), nan=0.0) > AWAY_SAYS


def guess_orientations(
    joints2d: np.ndarray, body_px: np.ndarray, spread: np.ndarray, fps: float, away: np.ndarray | None = None
) -> list[str | None]:
    """Each frame's orientation (None: nobody): side from walking and knees, profile below PROFILE_SPREAD,
    backward where ``facing_evidence`` < -1/2; runs shorter than MIN_RUN_S merged into neighbours."""
    ok = np.isfinite(joints2d).all(axis=(1, 2)) & np.isfinite(body_px)
    side = np.full(len(ok), np.nan)
    for r in runs(ok):
        side[r] = pooled(facing_side_cues(joints2d[r], body_px[r], fps), fps)
    backward = facing_evidence(joints2d, body_px, fps, away) < -0.5
    names = [None] * len(ok)
    for i in np.flatnonzero(ok):
        facing = "left" if side[i] < 0 else "right"
        if spread[i] < PROFILE_SPREAD:
            names[i] = facing
        else:
            names[i] = f"{'backward' if backward[i] else 'forward'}_{facing}"
    return merge_short_runs(names, max(1, int(round(MIN_RUN_S * fps))))


def facing_evidence(
    joints2d: np.ndarray, body_px: np.ndarray, fps: float, away: np.ndarray | None = None
) -> np.ndarray:
    """(F,) in [-1, 1]: turned toward (> 0) or away (< 0): +-1 where the median growth over CUE_WINDOW_S
    passes GROWTH per second, else the pooled head look ``away`` / (2 AWAY_SAYS), negated; else 0."""
    ok = np.isfinite(joints2d).all(axis=(1, 2)) & np.isfinite(body_px)
    out = np.zeros(len(ok))
    for r in runs(ok):
        log_px = np.log(body_px[r])
        growth = pooled(np.gradient(log_px) * fps if len(log_px) > 1 else np.zeros(1), fps, np.nanmedian)
        behind = pooled(np.zeros(r.stop - r.start) if away is None else away[r], fps)
        out[r] = np.where(np.abs(growth) > GROWTH, np.sign(growth), np.clip(-behind / (2 * AWAY_SAYS), -1.0, 1.0))
    return out


def rule_evidence(orientations: list[str | None], spread: np.ndarray, facing: np.ndarray) -> np.ndarray:
    """(F,) evidence that the image-left limbs are the right ones (> 0), for sides.track_sides: +-1 in
    a turned view; in a profile ``facing`` (F,) x PROFILE_RULE x the spread's ramp over RULE_SPREAD's
    width above ``profile_read`` (a turned view may read low); 0 where nobody is."""
    low, high = RULE_SPREAD
    ramp = np.clip((np.nan_to_num(spread, nan=0.0) - profile_read(spread)) / (high - low), 0.0, 1.0)
    out = PROFILE_RULE * ramp * facing
    for i, name in enumerate(orientations):
        rule = None if name is None else image_left_is_right(name)
        out[i] = 0.0 if name is None else out[i] if rule is None else (1.0 if rule else -1.0)
    return out


def profile_read(spread: np.ndarray) -> float:
    """The torso spread a true profile reads on this clip (``spread`` (F,)): RULE_SPREAD[0], or the
    clip's lowest read if lower (a slim performer reads narrow at every turn)."""
    seen = np.asarray(spread, float)
    seen = seen[np.isfinite(seen)]
    return min(RULE_SPREAD[0], float(seen.min())) if len(seen) else RULE_SPREAD[0]


def merge_short_runs(names: list[str | None], shortest: int) -> list[str | None]:
    """Runs shorter than ``shortest`` frames take the preceding run's name (else the next long run's,
    else the next one's), so the user sees few changes."""
    out = list(names)
    bounds = [i for i in range(1, len(out) + 1) if i == len(out) or out[i] != out[i - 1]]
    pieces = list(zip([0] + bounds[:-1], bounds))
    for start, end in pieces:
        if out[start] is not None and end - start < shortest:
            left = out[start - 1] if start > 0 else None
            right = next(
                (names[a] for a, b in pieces if a >= end and names[a] is not None and b - a >= shortest),
                out[end] if end < len(out) else None,
            )
            fill = left if left is not None else right
            if fill is not None:
                out[start:end] = [fill] * (end - start)
    return out


# -- foreshortening signs -------------------------------------------------------------


def lean_penalty(axis: np.ndarray, facing: np.ndarray, left: np.ndarray, back: float) -> np.ndarray:
    """Torso or head leaning back more than ``back`` (a cosine) or sideways."""
    a = unit(axis)
    return np.maximum(0, -(a * facing).sum(-1) - back) + np.maximum(0, np.abs((a * left).sum(-1)) - 0.2)


def _frame_axes(yaw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    rad = np.radians(yaw)
    facing = np.stack([np.sin(rad), np.zeros_like(rad), np.cos(rad)], axis=-1)
    left = np.stack([lateral_axis(y) for y in yaw]) if len(yaw) else np.zeros((0, 3))
    return facing, left


def segment_vectors(joints2d: np.ndarray, px_per_unit: np.ndarray, lengths: np.ndarray):
    """(F, 10, 2) image vectors (x right, y up, model units) and (F, 10) |dZ| (Eq. 5)."""
    ends = joints2d[:, SEGMENT_JOINTS]
    vec = (ends[:, :, 1] - ends[:, :, 0]) * np.array([1.0, -1.0]) / px_per_unit[:, None, None]
    depth = relative_depths(joints2d, px_per_unit, np.full(10, TOWARD), lengths)
    return vec, depth


def guess_signs(
    joints2d: np.ndarray,
    px_per_unit: np.ndarray,
    yaw: np.ndarray,
    lengths: np.ndarray = LENGTH,
    fixed: np.ndarray | None = None,
    fps: float = 30.0,
) -> np.ndarray:
    """(F, 10) +1 toward / -1 away for anatomical NaN-free 2D joints (F, 16, 2), per torso, head and limb
    by ``smoothest_states``: joint limits and (legs, torso, head) ``sagittal_depth`` per frame, the
    acceleration of |dZ| (median over DEPTH_FILTER_S) between; ``fixed`` (F, 10) user signs, 0: none."""
    fixed = np.zeros((len(joints2d), 10), int) if fixed is None else fixed
    vec, depth = segment_vectors(joints2d, px_per_unit, lengths)
    width = median_width(DEPTH_FILTER_S, fps)
    depth = median_filter(depth, size=(width, 1), mode="nearest")
    yaw = np.asarray(yaw, float)
    facing, left = _frame_axes(yaw)
    sagittal = sagittal_depth(vec[..., 0], yaw, lengths)  # (F, 10)
    out = np.ones((len(joints2d), 10), int)
    for name, back in (("torso", 0.2), ("head", 0.3)):
        k = SEGMENT_INDEX[name]
        states = np.array([1, -1])[None]
        z = states * depth[:, [k]]  # (F, 2)
        axis = np.concatenate([np.repeat(vec[:, None, k], 2, 1), z[..., None]], axis=-1)
        cost = lean_penalty(axis, facing[:, None], left[:, None], back) + SAGITTAL_WEIGHT * np.maximum(
            0, -states * sagittal[:, [k]]
        )
        allowed = (fixed[:, [k]] == 0) | (fixed[:, [k]] == states)
        out[:, k] = states[0, smoothest_states(z[..., None], LIMIT_WEIGHT * cost, allowed)]
    for one in LIMBS:
        ku, kl = (SEGMENT_INDEX[s] for s in one.segments)
        pick = _limb_signs(
            vec[:, [ku, kl]],
            depth[:, [ku, kl]],
            sagittal[:, [ku, kl]],
            fixed[:, [ku, kl]],
            facing,
            left,
            SIDE_SIGN[one.side],
            one.kind == "leg",
        )
        out[:, ku], out[:, kl] = _SIGN_PAIRS[pick, 0], _SIGN_PAIRS[pick, 1]
    return out


def _limb_signs(
    vec: np.ndarray,
    depth: np.ndarray,
    sagittal: np.ndarray,
    fixed: np.ndarray,
    facing: np.ndarray,
    left: np.ndarray,
    side: float,
    leg: bool,
) -> np.ndarray:
    """(F,) index into _SIGN_PAIRS of one limb's (upper, lower) signs; arguments are
    the two segments' image vectors (F, 2, 2), |dZ|, sagittal depths and user signs."""
    su, sl = _SIGN_PAIRS[:, 0][None], _SIGN_PAIRS[:, 1][None]
    zu, zl = su * depth[:, [0]], sl * depth[:, [1]]  # (F, 4)
    u3 = np.concatenate([np.repeat(vec[:, None, 0], 4, 1), zu[..., None]], axis=-1)
    l3 = np.concatenate([np.repeat(vec[:, None, 1], 4, 1), zl[..., None]], axis=-1)
    cost = limb_penalty(u3, l3, facing[:, None], left[:, None], side, leg)
    if leg:  # arms swing out of the sagittal plane too (and their 2D x is the fit's worst)
        cost = cost + SAGITTAL_WEIGHT * (np.maximum(0, -su * sagittal[:, [0]]) + np.maximum(0, -sl * sagittal[:, [1]]))
    allowed = ((fixed[:, [0]] == 0) | (fixed[:, [0]] == su)) & ((fixed[:, [1]] == 0) | (fixed[:, [1]] == sl))
    return smoothest_states(np.stack([zu, zu + zl], axis=-1), LIMIT_WEIGHT * cost, allowed)


def sagittal_depth(dx: np.ndarray, yaw: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(F, 10) depth / length were each segment in the sagittal plane (as in gait): dZ = dx / tan(yaw)
    from image x, the fit's best; |sin yaw| held >= 1/3, as near frontal dx is mostly sideways."""
    rad = np.radians(yaw)
    sin = np.where(np.sin(rad) < 0, -1.0, 1.0) * np.maximum(np.abs(np.sin(rad)), 1 / 3)
    return np.clip(dx * (np.cos(rad) / sin)[:, None] / lengths, -1.0, 1.0)


def yaws(orientations: list[str | None], spread: np.ndarray) -> np.ndarray:
    """(F,) facing yaw per frame (NaN where no orientation)."""
    return np.array([np.nan if o is None else facing_yaw(o, s) for o, s in zip(orientations, spread)])


def held_user_signs(values: np.ndarray, since: np.ndarray) -> np.ndarray:
    """(F, 10) the user's signs where they hold, else 0: sticky, as the contract has it, from the entry's
    frame (``since``, -1 none) until a later entry changes it (``values``: the latest entry's sign)."""
    frames = np.arange(len(values))[:, None]
    return np.where((since >= 0) & (since <= frames), values, 0)


# -- which leg is which, from the user's signs ---------------------------------------


def legs_crossed(
    joints: np.ndarray,
    user_signs: np.ndarray,
    yaw: np.ndarray,
    px_per_unit: np.ndarray,
    lengths: np.ndarray,
    pinned: np.ndarray,
) -> np.ndarray:
    """(F,) bool: frames of anatomical 2D joints (F, 16, 2) whose knees and ankles belong to the other
    hip, by the user's held signs (``user_signs`` (F, 10)) against ``sagittal_depth``: a two-state path,
    SWITCH_WEIGHT per leg length apart to exchange, KEEP_RULE a crossed frame; ``pinned`` (F,) never."""
    crossed = np.ones(len(joints), bool)
    costs = np.stack(
        [
            _leg_sign_cost(joints, user_signs, yaw, px_per_unit, lengths),
            _leg_sign_cost(exchange_legs(joints, crossed), user_signs, yaw, px_per_unit, lengths),
        ],
        axis=1,
    )  # (F, 2)
    if not costs.any():
        return ~crossed
    costs[:, 1] += KEEP_RULE
    costs[pinned, 1] = np.inf
    legs = joints[:, [[_J[f"{n}_{s}"] for n in LIMB_JOINTS["leg"][1:]] for s in SIDES]]
    apart = np.linalg.norm(legs[:, 0] - legs[:, 1], axis=-1).sum(-1) / (
        px_per_unit * (lengths[SEGMENT_INDEX["upper_leg_l"]] + lengths[SEGMENT_INDEX["lower_leg_l"]])
    )
    switch = SWITCH_WEIGHT * np.minimum(apart[1:], apart[:-1])
    return two_state_path(costs, switch).astype(bool)


def _leg_sign_cost(
    joints: np.ndarray, user_signs: np.ndarray, yaw: np.ndarray, px_per_unit: np.ndarray, lengths: np.ndarray
) -> np.ndarray:
    """(F,) how far the legs' sagittal depths point against the user's signs (0 near frontal)."""
    vec, _ = segment_vectors(joints, px_per_unit, lengths)
    sagittal = sagittal_depth(vec[..., 0], yaw, lengths)[:, _LEG_SEGMENTS]
    turned = np.abs(np.sin(np.radians(yaw))) >= SAGITTAL_SHOWS
    return turned * np.maximum(0.0, -user_signs[:, _LEG_SEGMENTS] * sagittal).sum(-1)
