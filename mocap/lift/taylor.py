"""2D joints and the user's inputs -> a 3D pose: scaled orthographic lifting
(section 3.4, Eq. 4-5, after Taylor).

Under scaled orthographic projection (Eq. 4) a joint's image position gives its x
and y up to the scale s; the body's height in the image gives s. A segment of model
length l whose ends are (u1, v1) and (u2, v2) apart in the image then has the
relative depth of Eq. 5,

    dZ = +-sqrt(l^2 - ((u1 - u2)^2 + (v1 - v2)^2) / s^2),

whose sign is the user's foreshortening direction (``toward``: the distal joint is
nearer the camera, larger z). Depths are chained from the pelvis outward.

The body's orientation (one of six) and the torso's horizontal foreshortening
(``spread``, the seen fraction of the shoulder/hip span) give how far the performer
is turned about the vertical axis (the yaw), which places the hips and shoulders in
depth, and which image-side limb is which anatomical one (``image_left_is_right``,
``track_sides``).

Coordinates (CONTRACT.md): 2D in video pixels (x right, y down); 3D in metres, origin
at the pelvis, x to the image right, y up, z toward the camera, body height 1.75 m.
Inside this module lengths are model units of a 175-unit body (body.LENGTH).
"""

from __future__ import annotations

import numpy as np

from mocap.body import (BODY_HEIGHT, BODY_HEIGHT_M, CHEST_FRACTION, HIP_HALF_SPAN,
                        JOINT_INDEX, LENGTH, LIMB_JOINTS, SEGMENT_INDEX, SEGMENT_JOINTS,
                        SEGMENT_NAMES, SHOULDER_DROP, SHOULDER_HALF_SPAN, SIDE_SIGN, SIDES, AWAY,
                        ORIENTATIONS, TOWARD, left_direction)

UNIT_M = BODY_HEIGHT_M / BODY_HEIGHT            # metres per model unit
SPANS = (SHOULDER_HALF_SPAN, HIP_HALF_SPAN)     # model half-spans: shoulders, hips
# A yaw within this many degrees of a profile (+-90) is named a profile by
# ``orientation_of_yaw``: the six orientations split the circle into 60-degree sectors.
PROFILE_HALF_SECTOR = 30.0
SEPARATED = 0.25     # distal joints this many limb lengths apart tell two limbs apart
# limb lengths of joint distance that a radian of segment turn counts as: a segment
# (half a limb) that turns a radian moves its distal joint about that far
ANGLE_WEIGHT = 0.5
MIN_APART = 3        # frames: shorter stretches apart are fit noise inside a crossing
_J = JOINT_INDEX
_TORSO, _HEAD = SEGMENT_INDEX["torso"], SEGMENT_INDEX["head"]
# limb segments in chain order (each one's proximal joint is placed before it)
_LIMB_SEGMENTS = [SEGMENT_INDEX[s] for s in SEGMENT_NAMES if s not in ("torso", "head")]
# the joints whose image sides the arms' and the legs' parities swap
_PAIR_JOINTS = {"arms": LIMB_JOINTS["arm"][1:], "legs": LIMB_JOINTS["leg"][1:]}


# -- orientation ----------------------------------------------------------------------

def facing_yaw(orientation: str, spread: float) -> float:
    """The performer's facing direction in degrees about the vertical (section 3.4):
    0 faces the camera, +90 faces image right, -90 image left, 180 away.

    ``spread`` = |cos(yaw)| is the torso's horizontal foreshortening; the
    orientation says which of the four yaws with that spread it is. A profile is
    taken as exactly +-90 (its spread cannot say whether the performer is turned a
    little toward the camera or a little away).
    """
    if orientation not in ORIENTATIONS:
        raise ValueError(f"unknown orientation {orientation!r}")
    side = -1.0 if orientation.endswith("left") else 1.0
    if orientation in ("left", "right"):
        return 90.0 * side
    turn = float(np.degrees(np.arccos(np.clip(spread, 0.0, 1.0))))
    return side * (turn if orientation.startswith("forward") else 180.0 - turn)


def orientation_of_yaw(yaw_deg: float) -> str:
    """The one of the six orientations that names a yaw (see ``facing_yaw``):
    profiles within PROFILE_HALF_SECTOR of +-90 degrees, forward or backward beyond."""
    yaw = (float(yaw_deg) + 180.0) % 360.0 - 180.0
    side = "left" if yaw < 0 else "right"
    if abs(abs(yaw) - 90.0) <= PROFILE_HALF_SECTOR:
        return side
    return f"{'forward' if abs(yaw) < 90.0 else 'backward'}_{side}"


def lateral_axis(yaw_deg: float) -> np.ndarray:
    """The performer's left (unit, camera frame) when facing ``yaw_deg``:
    up x facing, with facing = (sin yaw, 0, cos yaw)."""
    yaw = np.radians(yaw_deg)
    return np.array([np.cos(yaw), 0.0, -np.sin(yaw)])


def image_left_is_right(orientation: str) -> bool | None:
    """Whether the image-left limbs of the 2D fit are the performer's right ones.

    Facing the camera (forward_*) the performer's right is on the image left;
    turned away (backward_*) their left is. In a profile both shoulders and both
    hips fall on one image point, so image sides say nothing: the limb nearer the
    camera is the right one when facing image right (their left when facing
    image left), which the image cannot show either (a silhouette looks the same
    with the depths mirrored and the sides swapped). Profiles therefore return
    None: the sides are followed through time from a frame where they are known
    (``track_sides``).
    """
    if orientation.startswith("forward"):
        return True
    if orientation.startswith("backward"):
        return False
    if orientation in ("left", "right"):
        return None
    raise ValueError(f"unknown orientation {orientation!r}")


def runs(mask: np.ndarray) -> list[slice]:
    """Slices of the consecutive True stretches of a boolean array."""
    edges = np.flatnonzero(np.diff(np.r_[0, mask.astype(int), 0]))
    return [slice(a, b) for a, b in zip(edges[::2], edges[1::2])]


# -- which image-side limb is which ----------------------------------------------------
# Section 3.4: "From the orientation, we also determine the left leg (arm) and the
# right leg (arm)." The 2D fit names limbs by image side (section 3.3).

def track_sides(joints2d: np.ndarray, known: np.ndarray, facing_x: np.ndarray) -> np.ndarray:
    """(F, 2) bool: for arms and legs, whether the image-left limb is the right one.

    ``known`` (F, 2) holds 1 (swap), 0 (keep) or -1 (unknown: a profile, where the 2D
    fit names limbs by their image order, back and front). In a profile the legs keep
    their identity through the moments where they pass each other by
    ``bridge_parity``; the arms swing opposite to the legs (the front arm is on the
    other side than the front leg), since the fit cannot see arms cross. A stretch
    with nothing known starts from the forward-facing convention (swap), which the
    user corrects with one joint override. ``facing_x`` (F,) is +1 facing image right.
    """
    out = np.zeros(known.shape, bool)
    ok = np.isfinite(joints2d).all(axis=(1, 2))
    for r in runs(ok):
        legs = _limb_pair(joints2d[r], _PAIR_JOINTS["legs"])
        chains = _limb_pair(joints2d[r], LIMB_JOINTS["leg"])
        parity = _anchored(bridge_parity(chains, _limb_px(joints2d[r], *LIMB_JOINTS["leg"][::2])), known[r, 1])
        out[r, 1] = np.where(known[r, 1] >= 0, known[r, 1] == 1, parity)
        arms = _counter_phase(legs, out[r, 1], _limb_pair(joints2d[r], _PAIR_JOINTS["arms"]), facing_x[r])
        out[r, 0] = np.where(known[r, 0] >= 0, known[r, 0] == 1, arms)
    return out


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


def _anchored(parity: np.ndarray, known: np.ndarray, reach: int = 10) -> np.ndarray:
    """Relative parity -> swap per frame. Each stretch of unknown frames takes the
    constant that agrees with most known frames within ``reach`` of it (else in the
    whole run); with none known, the forward-facing convention (swap)."""
    out = (parity ^ 1).astype(bool)
    for stretch in runs(known < 0):
        near = slice(max(0, stretch.start - reach), min(len(known), stretch.stop + reach))
        votes = np.flatnonzero(known[near] >= 0) + near.start
        if not len(votes):
            votes = np.flatnonzero(known >= 0)
        if len(votes):
            flip = np.mean(parity[votes] != known[votes]) > 0.5
            out[stretch] = (parity[stretch] ^ int(flip)).astype(bool)
    return out


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


def anatomical_joints(joints_image: np.ndarray, swap: np.ndarray) -> np.ndarray:
    """(F, 16, 2) image-side joints with each frame's arms and legs swapped as told."""
    out = _exchanged(joints_image, swap[:, 0], LIMB_JOINTS["arm"])
    return _exchanged(out, swap[:, 1], LIMB_JOINTS["leg"])


def exchange_legs(joints2d: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(F, 16, 2) with the knees and ankles of the ``rows`` (F,) bool frames exchanged
    between the hips: legs crossed in the image, the hips where they were."""
    return _exchanged(joints2d, rows, _PAIR_JOINTS["legs"])


def _exchanged(joints2d: np.ndarray, rows: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """(F, 16, 2) with the left and right joints ``names`` exchanged on the ``rows`` (F,)
    bool frames."""
    left, right = [_J[f"{n}_l"] for n in names], [_J[f"{n}_r"] for n in names]
    out = joints2d.copy()
    out[np.ix_(rows, left)], out[np.ix_(rows, right)] = joints2d[np.ix_(rows, right)], joints2d[np.ix_(rows, left)]
    return out


# -- Eq. 4-5 --------------------------------------------------------------------------

def relative_depths(joints2d: np.ndarray, px_per_unit, signs: np.ndarray,
                    lengths: np.ndarray = LENGTH) -> np.ndarray:
    """(..., 10) dZ of every segment in model units, distal minus proximal (Eq. 5),
    for joints (..., 16, 2) at px_per_unit (scalar or (...,)).

    A segment drawn longer than its model length lies in the image plane (dZ = 0).
    ``signs`` are +1 (toward the camera) or -1 (away); 0 counts as toward.
    """
    ends = np.asarray(joints2d, float)[..., SEGMENT_JOINTS, :]          # (..., 10, 2, 2)
    seen = (np.linalg.norm(ends[..., 1, :] - ends[..., 0, :], axis=-1)
            / np.asarray(px_per_unit, float)[..., None])
    depth = np.sqrt(np.maximum(np.asarray(lengths, float) ** 2 - seen ** 2, 0.0))
    return np.where(np.asarray(signs) < 0, -depth, depth)


def image_to_model(joints2d: np.ndarray, px_per_unit: float) -> np.ndarray:
    """(16, 2) x right, y up in model units about the pelvis (Eq. 4 inverted)."""
    rel = np.asarray(joints2d, float) - np.asarray(joints2d, float)[_J["pelvis"]]
    return np.stack([rel[:, 0], -rel[:, 1]], axis=-1) / px_per_unit


def lift_pose(joints2d: np.ndarray, px_per_unit: float, yaw_deg: float, signs: np.ndarray,
              lengths: np.ndarray = LENGTH, spans: tuple[float, float] = SPANS) -> np.ndarray:
    """(16, 3) joints in metres (contract frame) from anatomical 2D joints (section 3.4).

    x and y come from the image (Eq. 4); depths are chained from the pelvis: the torso
    and head by Eq. 5, the hips and shoulders from the yaw (their model half-spans
    ``spans`` along the performer's lateral axis), then every limb segment by Eq. 5
    from its proximal joint.
    """
    xy = image_to_model(joints2d, px_per_unit)
    dz = relative_depths(joints2d, px_per_unit, signs, lengths)
    z = np.zeros(len(xy))
    z[_J["neck"]] = dz[_TORSO]
    z[_J["chest"]] = CHEST_FRACTION * dz[_TORSO]
    z[_J["head_top"]] = dz[_TORSO] + dz[_HEAD]
    across = lateral_axis(yaw_deg)[2]                    # z of the performer's left
    axis_z = dz[_TORSO] * (1.0 - SHOULDER_DROP / LENGTH[_TORSO])
    for side, sign in SIDE_SIGN.items():
        z[_J[f"shoulder_{side}"]] = axis_z + sign * across * spans[0]
        z[_J[f"hip_{side}"]] = sign * across * spans[1]
    for k in _LIMB_SEGMENTS:
        proximal, distal = SEGMENT_JOINTS[k]
        z[distal] = z[proximal] + dz[k]
    return np.column_stack([xy, z]) * UNIT_M


# -- reading a 3D pose back (ground truth, tests, annotations from a pose) -----------

def yaw_of(joints3d: np.ndarray) -> float:
    """The facing yaw (degrees) of a 3D pose in the contract frame, from its hips'
    and shoulders' right-to-left direction (the inverse of ``lateral_axis``)."""
    j = np.asarray(joints3d, float)
    left = left_direction(j)
    return float(np.degrees(np.arctan2(-left[2], left[0])))


def signs_of(joints3d: np.ndarray) -> np.ndarray:
    """(..., 10) foreshortening of each segment of 3D poses (..., 16, 3): +1 toward,
    -1 away."""
    ends = np.asarray(joints3d, float)[..., SEGMENT_JOINTS, :]
    return np.where(ends[..., 1, 2] >= ends[..., 0, 2], TOWARD, AWAY)


def depth_fractions(joints3d: np.ndarray) -> np.ndarray:
    """(..., 10) |dZ| / length of each segment of 3D poses (..., 16, 3) (0 in the
    image plane)."""
    ends = np.asarray(joints3d, float)[..., SEGMENT_JOINTS, :]
    vec = ends[..., 1, :] - ends[..., 0, :]
    return np.abs(vec[..., 2]) / np.maximum(np.linalg.norm(vec, axis=-1), 1e-12)


# -- lengths seen in a clip -----------------------------------------------------------

def clip_lengths(joints2d: np.ndarray, px_per_unit: np.ndarray, q=90.0,
                 pool: bool = False) -> np.ndarray:
    """(10,) segment lengths (model units) as seen over a clip: the q-th percentile
    (one for all, or one per segment) of each segment's projected length, both sides
    of a pair pooled with ``pool``.

    Beyond the paper: real bodies differ from Table 1 (forearms of motion-capture
    skeletons are ~25% shorter), and Eq. 5 with a too long l invents depth. A segment
    passes through the image plane in most motions, where its projection is its
    length. Falls back to the model's length where nothing is seen.
    """
    j = np.asarray(joints2d, float)
    ends = j[:, SEGMENT_JOINTS]                                             # (F, 10, 2, 2)
    seen = np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1) / np.asarray(px_per_unit, float)[:, None]
    out = LENGTH.astype(float).copy()
    q = np.broadcast_to(np.asarray(q, float), out.shape)
    for k, name in enumerate(SEGMENT_NAMES):
        pair = [k] if name in ("torso", "head") or not pool else [SEGMENT_INDEX[name[:-1] + s] for s in "lr"]
        values = seen[:, pair].ravel()
        values = values[np.isfinite(values)]
        if len(values):
            out[k] = np.percentile(values, q[k])
    return out
