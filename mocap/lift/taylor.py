"""Scaled orthographic lifting of 2D joints to a 3D pose (section 3.4, Eq. 4-5, after Taylor).

x, y by Eq. 4 up to the scale s (the body's image height); each segment's depth by Eq. 5,
dZ = +-sqrt(l^2 - ((u1 - u2)^2 + (v1 - v2)^2) / s^2), signed by its foreshortening (``toward``: the
distal joint nearer the camera), chained from the pelvis. Model units (body.LENGTH) inside, metres out."""

from __future__ import annotations

import numpy as np

from mocap.body import (
    AWAY,
    BODY_HEIGHT,
    BODY_HEIGHT_M,
    CHEST_FRACTION,
    HIP_HALF_SPAN,
    JOINT_INDEX,
    LENGTH,
    LIMB_JOINTS,
    ORIENTATIONS,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    SHOULDER_DROP,
    SHOULDER_HALF_SPAN,
    SIDE_SIGN,
    TOWARD,
    left_direction,
)

UNIT_M = BODY_HEIGHT_M / BODY_HEIGHT  # metres per model unit
SPANS = (SHOULDER_HALF_SPAN, HIP_HALF_SPAN)  # model half-spans: shoulders, hips
# A yaw within this many degrees of a profile (+-90) is named a profile by
# ``orientation_of_yaw``: the six orientations split the circle into 60-degree sectors.
PROFILE_HALF_SECTOR = 30.0
_J = JOINT_INDEX
_TORSO, _HEAD = SEGMENT_INDEX["torso"], SEGMENT_INDEX["head"]
# limb segments in chain order (each one's proximal joint is placed before it)
_LIMB_SEGMENTS = [SEGMENT_INDEX[s] for s in SEGMENT_NAMES if s not in ("torso", "head")]


# -- orientation ----------------------------------------------------------------------


def facing_yaw(orientation: str, spread: float) -> float:
    """Facing yaw in degrees (section 3.4): 0 faces the camera, +90 image right, -90 image left, 180 away.
    ``spread`` = |cos yaw| (the torso's horizontal foreshortening); a profile is exactly +-90."""
    if orientation not in ORIENTATIONS:
        raise ValueError(f"unknown orientation {orientation!r}")
    side = -1.0 if orientation.endswith("left") else 1.0
    if orientation in ("left", "right"):
        return 90.0 * side
    turn = float(np.degrees(np.arccos(np.clip(spread, 0.0, 1.0))))
    return side * (turn if orientation.startswith("forward") else 180.0 - turn)


def orientation_of_yaw(yaw_deg: float) -> str:
    """The orientation naming a yaw: a profile within PROFILE_HALF_SECTOR of +-90, else forward/backward."""
    yaw = (float(yaw_deg) + 180.0) % 360.0 - 180.0
    side = "left" if yaw < 0 else "right"
    if abs(abs(yaw) - 90.0) <= PROFILE_HALF_SECTOR:
        return side
    return f"{'forward' if abs(yaw) < 90.0 else 'backward'}_{side}"


def lateral_axis(yaw_deg: float) -> np.ndarray:
    """The performer's left (unit, camera frame) facing ``yaw_deg``: up x (sin yaw, 0, cos yaw)."""
    yaw = np.radians(yaw_deg)
    return np.array([np.cos(yaw), 0.0, -np.sin(yaw)])


def image_left_is_right(orientation: str) -> bool | None:
    """Whether the fit's image-left limbs are the performer's right: True facing the camera, False
    turned away, None in a profile (the image cannot tell; ``mocap.lift.sides`` follows them in time)."""
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


def median_width(seconds: float, fps: float) -> int:
    """A running window's width in frames, odd: 2 round(seconds fps / 2) + 1 (0.1 s: three frames at 25 fps,
    five at 30; 0.2 s: five at 25)."""
    return 2 * int(round(seconds * fps / 2)) + 1


def anatomical_joints(joints_image: np.ndarray, swap: np.ndarray) -> np.ndarray:
    """(F, 16, 2) image-side joints with arms and legs swapped on the frames ``swap`` (F, 2) marks."""
    out = _exchanged(joints_image, swap[:, 0], LIMB_JOINTS["arm"])
    return _exchanged(out, swap[:, 1], LIMB_JOINTS["leg"])


def exchange_legs(joints2d: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """(F, 16, 2) with knees and ankles exchanged between the hips on ``rows`` (F,) bool."""
    return _exchanged(joints2d, rows, LIMB_JOINTS["leg"][1:])


def _exchanged(joints2d: np.ndarray, rows: np.ndarray, names: tuple[str, ...]) -> np.ndarray:
    """(F, 16, 2) with the left and right joints ``names`` exchanged on ``rows`` (F,) bool."""
    left, right = [_J[f"{n}_l"] for n in names], [_J[f"{n}_r"] for n in names]
    out = joints2d.copy()
    out[np.ix_(rows, left)], out[np.ix_(rows, right)] = joints2d[np.ix_(rows, right)], joints2d[np.ix_(rows, left)]
    return out


# -- Eq. 4-5 --------------------------------------------------------------------------


def relative_depths(joints2d: np.ndarray, px_per_unit, signs: np.ndarray, lengths: np.ndarray = LENGTH) -> np.ndarray:
    """(..., 10) dZ per segment (Eq. 5), model units, distal minus proximal, of joints (..., 16, 2) at
    ``px_per_unit`` (scalar or (...,)); ``signs`` +1 toward, -1 away (0: toward); 0 if seen over-long."""
    ends = np.asarray(joints2d, float)[..., SEGMENT_JOINTS, :]  # (..., 10, 2, 2)
    seen = np.linalg.norm(ends[..., 1, :] - ends[..., 0, :], axis=-1) / np.asarray(px_per_unit, float)[..., None]
    depth = np.sqrt(np.maximum(np.asarray(lengths, float) ** 2 - seen**2, 0.0))
    return np.where(np.asarray(signs) < 0, -depth, depth)


def image_to_model(joints2d: np.ndarray, px_per_unit: float) -> np.ndarray:
    """(16, 2) x right, y up in model units about the pelvis (Eq. 4 inverted)."""
    rel = np.asarray(joints2d, float) - np.asarray(joints2d, float)[_J["pelvis"]]
    return np.stack([rel[:, 0], -rel[:, 1]], axis=-1) / px_per_unit


def lift_pose(
    joints2d: np.ndarray,
    px_per_unit: float,
    yaw_deg: float,
    signs: np.ndarray,
    lengths: np.ndarray = LENGTH,
    spans: tuple[float, float] = SPANS,
    seen_depths: np.ndarray | None = None,
) -> np.ndarray:
    """(16, 3) metres (contract frame) from anatomical 2D joints (16, 2): x, y by Eq. 4; z from the pelvis:
    torso and head by Eq. 5, hips and shoulders at ``spans`` along the yaw's lateral axis, then each limb
    by Eq. 5. ``seen_depths`` (10,): a person model's |dZ| (cues.world_depths), signed by ``signs``, where finite."""
    xy = image_to_model(joints2d, px_per_unit)
    dz = relative_depths(joints2d, px_per_unit, signs, lengths)
    if seen_depths is not None:
        dz = np.where(np.isfinite(seen_depths), np.asarray(signs) * seen_depths, dz)
    z = np.zeros(len(xy))
    z[_J["neck"]] = dz[_TORSO]
    z[_J["chest"]] = CHEST_FRACTION * dz[_TORSO]
    z[_J["head_top"]] = dz[_TORSO] + dz[_HEAD]
    across = lateral_axis(yaw_deg)[2]  # z of the performer's left
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
    """Facing yaw (degrees) of a 3D pose (16, 3) from its left direction (inverse of ``lateral_axis``)."""
    j = np.asarray(joints3d, float)
    left = left_direction(j)
    return float(np.degrees(np.arctan2(-left[2], left[0])))


def signs_of(joints3d: np.ndarray) -> np.ndarray:
    """(..., 10) each segment's foreshortening (+1 toward, -1 away) in 3D poses (..., 16, 3)."""
    ends = np.asarray(joints3d, float)[..., SEGMENT_JOINTS, :]
    return np.where(ends[..., 1, 2] >= ends[..., 0, 2], TOWARD, AWAY)


def depth_fractions(joints3d: np.ndarray) -> np.ndarray:
    """(..., 10) |dZ| / length per segment of 3D poses (..., 16, 3); 0 in the image plane."""
    ends = np.asarray(joints3d, float)[..., SEGMENT_JOINTS, :]
    vec = ends[..., 1, :] - ends[..., 0, :]
    return np.abs(vec[..., 2]) / np.maximum(np.linalg.norm(vec, axis=-1), 1e-12)


# -- lengths seen in a clip -----------------------------------------------------------


def clip_lengths(joints2d: np.ndarray, px_per_unit: np.ndarray, q=90.0, pool: bool = False) -> np.ndarray:
    """(10,) segment lengths (model units) seen over a clip: the ``q``-th percentile (scalar or (10,))
    of each projected length, pairs pooled with ``pool``; the model's where nothing is seen. Beyond the
    paper: real bodies differ from Table 1, and most segments pass the image plane at full length."""
    j = np.asarray(joints2d, float)
    ends = j[:, SEGMENT_JOINTS]  # (F, 10, 2, 2)
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
