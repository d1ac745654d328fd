"""Which way the performer faces, from a video's silhouettes where the 2D pose cannot tell (beyond the paper):
the head's look (face or hair: ``facing_away``) and which arm and leg are near the camera (their outlines cross
the trunk and each other: ``near_limbs``); mocap.lift.orientation and mocap.lift.sides take both."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, LENGTH, LIMB_JOINTS, SEGMENT_INDEX, SIDES, WIDTH
from mocap.image.edges import Edges

# The upper head (from above the ears to the crown, of the fitted neck -> head top) is
# split into its dark and light tones (Otsu): the dark one (hair) grows as the head turns away.
HEAD_BAND = (0.35, 1.1, 0.4)  # along the head from, to; half-width across (head lengths)
SHARE_BETWEEN = 0.6  # the dark share between the three-quarter views, front and back
SHARE_SPAN = 0.15  # from it to a sure front or back
MIN_CONTRAST = 30.0  # grey levels between the two tones: less is one tone, no cue
_J_TOP, _J_NECK = JOINT_INDEX["head_top"], JOINT_INDEX["neck"]


def hair_share(grey: np.ndarray, mask: np.ndarray, neck: np.ndarray, top: np.ndarray) -> float:
    """The dark tone's share of the upper head in ``grey`` within ``mask`` (NaN: one tone, few pixels)."""
    u = top - neck
    length = float(np.hypot(*u))
    if not np.isfinite(length) or length < 2:
        return np.nan
    lo = np.maximum(np.floor(np.minimum(neck, top) - length).astype(int), 0)
    hi = np.minimum(np.ceil(np.maximum(neck, top) + length).astype(int) + 1, grey.shape[1::-1])
    yy, xx = np.mgrid[lo[1] : hi[1], lo[0] : hi[0]]
    rel = np.stack([xx - neck[0], yy - neck[1]], axis=-1) / length**2
    along, across = rel @ u, rel @ np.array([-u[1], u[0]])
    start, end, half = HEAD_BAND
    inside = mask[lo[1] : hi[1], lo[0] : hi[0]] & (along >= start) & (along <= end) & (np.abs(across) <= half)
    tones = grey[lo[1] : hi[1], lo[0] : hi[0]][inside]
    if tones.size < 10:
        return np.nan
    cut, _ = cv2.threshold(tones.reshape(-1, 1), 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    dark = tones <= cut
    if dark.all() or not dark.any() or tones[~dark].mean() - tones[dark].mean() < MIN_CONTRAST:
        return np.nan
    return float(dark.mean())


def facing_away(silhouettes: list, joints2d: np.ndarray, scale: float) -> np.ndarray:
    """(F,) evidence in [-1, 1] that the performer faces away (> 0) or toward the camera (< 0), by ``hair_share``
    on each Silhouette (pixels of ``scale`` times the video's) at the joints (F, 16, 2; video pixels); 0 where
    the head tells nothing or an arm lies over it (``arm_over_head``)."""
    out = np.zeros(len(joints2d))
    for i, (sil, joints) in enumerate(zip(silhouettes, joints2d)):
        if sil is None or sil.grey is None or not np.isfinite(joints).all():
            continue
        if arm_over_head(joints):
            continue
        origin = np.array(sil.box[:2], float)
        share = hair_share(sil.grey, sil.mask() > 0, joints[_J_NECK] * scale - origin, joints[_J_TOP] * scale - origin)
        if np.isfinite(share):
            out[i] = np.clip((share - SHARE_BETWEEN) / SHARE_SPAN, -1.0, 1.0)
    return out


_KINDS = ("arm", "leg")
_CHAINS = {kind: [[JOINT_INDEX[f"{n}_{s}"] for n in LIMB_JOINTS[kind]] for s in SIDES] for kind in _KINDS}
_WIDTHS = {kind: WIDTH[[SEGMENT_INDEX[f"{part}_{kind}_l"] for part in ("upper", "lower")]] for kind in _KINDS}
_ARM_SAMPLES = np.linspace(0.0, 1.0, 9)


def arm_over_head(joints: np.ndarray) -> bool:
    """Whether an arm of a pose (16, 2) lies over the head band ``hair_share`` reads (HEAD_BAND)."""
    neck, u = joints[_J_NECK], joints[_J_TOP] - joints[_J_NECK]
    length2 = float(u @ u)
    if not length2 > 0:
        return False
    ends = joints[_CHAINS["arm"]]  # (2, 3, 2)
    points = ends[:, :-1, None] + _ARM_SAMPLES[:, None] * (ends[:, 1:] - ends[:, :-1])[:, :, None]
    rel = (points - neck) / length2
    along, across = rel @ u, rel @ np.array([-u[1], u[0]])
    start, end, half = HEAD_BAND
    margin = _WIDTHS["arm"].max() / 2 / LENGTH[SEGMENT_INDEX["head"]]
    return bool(((along >= start - margin) & (along <= end + margin) & (np.abs(across) <= half + margin)).any())


# -- the near limbs: their outlines across the trunk and each other ------------------------


def near_limbs(silhouettes: list, joints2d: np.ndarray, body_px: np.ndarray, scale: float) -> np.ndarray:
    """(F, 2) for the arms and the legs (joints2d (F, 16, 2), image sides, video pixels; ``body_px`` (F,)): how
    much more the image-left limb's outline shows inside the silhouette than the right one's (edge support,
    mocap.image.edges, 0..1): a near limb's edges show over the trunk or the other limb. 0 without a silhouette."""
    out = np.zeros((len(joints2d), 2))
    for i, (sil, joints) in enumerate(zip(silhouettes, joints2d)):
        if sil is None or sil.grey is None or not np.isfinite(joints).all() or not np.isfinite(body_px[i]):
            continue
        edges = Edges.inside(sil.grey, sil.mask() > 0)
        for k, kind in enumerate(_KINDS):
            chains = joints[_CHAINS[kind]] * scale - np.array(sil.box[:2], float)  # (2, 3, 2)
            widths = _WIDTHS[kind] * body_px[i] * scale / BODY_HEIGHT
            support = edges.support(chains[:, :-1], chains[:, 1:], widths)
            out[i, k] = float(support[0] - support[1])
    return out
