"""Foot contacts and pinning: a foot is planted while its smoothed ankle is near the floor (a running
low percentile of the lower ankle: a reconstructed floor drifts) and hardly moves across the image
plane (depth is least certain); ``foot_lock`` moves the body to where its planted feet ask, then holds
each there by two-bone IK, moving the body where the leg cannot reach, so exports do not slide."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import binary_closing, binary_opening, gaussian_filter1d, percentile_filter

from mocap.body import JOINT_INDEX

FEET = ("ankle_l", "ankle_r")
_ANKLES = [JOINT_INDEX[a] for a in FEET]
# thresholds for a 1.75 m body: a planted foot's ankle stays near the floor level (heel
# to toe roll lifts it) and creeps; a swinging one travels at one to three times walking speed
CONTACT_HEIGHT_M = 0.15
CONTACT_SPEED_M_S = 1.0
SMOOTH_S = 0.08  # Gaussian sigma of the ankle track before differencing
MIN_RUN_S = 0.1  # shorter contacts and gaps are noise
FLOOR_PERCENTILE = 10.0  # of the lower ankle's height around a frame: the floor's level
FLOOR_WINDOW_S = 1.0  # that running window (a walk plants a foot several times in it)
BLEND_S = 0.1  # a pin fades in and out over this much time around its contact
# a pin beyond this share of its leg's length from the hip moves the body toward it (a leg at
# full stretch has no knee left to bend), in rounds that settle two planted feet together
REACH_SHARE = 0.999
REACH_ROUNDS = 4


def foot_contacts(world: np.ndarray, fps: float, depth: bool = False) -> np.ndarray:
    """(F, 2) bool: left and right foot planted on each frame of world joints (F, 16, 3; metres, y up);
    ``depth``: the speed along z counts too (a motion whose depth is known, such as motion capture's)."""
    ankles = gaussian_filter1d(world[:, _ANKLES], max(SMOOTH_S * fps, 1e-6), axis=0, mode="nearest")
    floor = percentile_filter(
        ankles[..., 1].min(axis=1), FLOOR_PERCENTILE, size=int(round(FLOOR_WINDOW_S * fps)) | 1, mode="nearest"
    )
    speed = np.linalg.norm(np.gradient(ankles[..., : 3 if depth else 2], axis=0), axis=-1) * fps
    planted = (ankles[..., 1] - floor[:, None] < CONTACT_HEIGHT_M) & (speed < CONTACT_SPEED_M_S)
    width = max(1, int(round(MIN_RUN_S * fps)))
    structure = np.ones((width, 1), bool)
    return binary_opening(binary_closing(planted, structure, border_value=0), structure)


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of each stretch of True."""
    edges = np.diff(np.concatenate([[0], flags.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def pin_weight(start: int, stop: int, n: int, fps: float) -> np.ndarray:
    """(n,) how much of a contact's pin (frames start..stop-1) each frame takes: 1 on the contact, fading out
    over BLEND_S either side."""
    blend = max(1, int(round(BLEND_S * fps)))
    frames = np.arange(n)
    return np.clip(1 - np.maximum(start - frames, frames - (stop - 1)) / (blend + 1), 0, 1)


def pinned_targets(ankle: np.ndarray, planted: np.ndarray, fps: float) -> np.ndarray:
    """(F, 3) where an ankle (F, 3) should be: each contact's mean position, fading out over BLEND_S."""
    shift = np.zeros_like(ankle)
    weight = np.zeros(len(ankle))
    frames = np.arange(len(ankle))
    for start, stop in _runs(planted):
        pin = ankle[start:stop].mean(axis=0)
        w = pin_weight(start, stop, len(ankle), fps)
        near = w > weight
        shift[near] = (pin - ankle[np.clip(frames[near], start, stop - 1)]) * w[near, None]
        weight[near] = w[near]
    return ankle + shift


def two_bone_ik(
    hip: np.ndarray, knee: np.ndarray, ankle: np.ndarray, target: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(knee, ankle) (F, 3) of a leg reaching ``target`` as near as it can, thigh and shin lengths
    kept, the knee in the plane of hip, target and old knee (law of cosines)."""
    thigh = np.linalg.norm(knee - hip, axis=-1, keepdims=True)
    shin = np.linalg.norm(ankle - knee, axis=-1, keepdims=True)
    reach = target - hip
    dist = np.linalg.norm(reach, axis=-1, keepdims=True)
    dist_c = np.clip(dist, np.abs(thigh - shin) + 1e-9, thigh + shin - 1e-9)
    along = reach / np.maximum(dist, 1e-12)
    pole = (knee - hip) - ((knee - hip) * along).sum(-1, keepdims=True) * along
    pole /= np.maximum(np.linalg.norm(pole, axis=-1, keepdims=True), 1e-12)
    a = (thigh**2 - shin**2 + dist_c**2) / (2 * dist_c)
    new_knee = hip + a * along + np.sqrt(np.maximum(thigh**2 - a**2, 0)) * pole
    return new_knee, hip + along * dist_c


def planted_shift(world: np.ndarray, contacts: np.ndarray, fps: float) -> np.ndarray:
    """(F, 3) the body's move that meets its planted feet's pins on average: each contact asks the ankle's
    way to its pin (``pinned_targets``' mean), by ``pin_weight``; fading with the pins where they fade, so the
    body does not jump as a contact ends. The root's depth is read off the body's image height, which wavers;
    the feet on the floor say where the body is better than that."""
    asked, weight = np.zeros((len(world), 3)), np.zeros(len(world))
    for ankle, planted in zip(_ANKLES, contacts.T):
        for start, stop in _runs(planted):
            w = pin_weight(start, stop, len(world), fps)
            asked += w[:, None] * (world[start:stop, ankle].mean(axis=0) - world[:, ankle])
            weight += w
    return asked / np.maximum(weight, 1.0)[:, None]


def foot_lock(world: np.ndarray, contacts: np.ndarray, fps: float) -> tuple[np.ndarray, np.ndarray]:
    """(world joints (F, 16, 3), the body's shift (F, 3)): the body moved where its planted feet ask
    (``planted_shift``), then each planted ankle held through its contact (``two_bone_ik``), the whole body
    moved the least that brings every pin within its leg's reach."""
    legs = [tuple(JOINT_INDEX[f"{j}_{side}"] for j in ("hip", "knee", "ankle")) for side in "lr"]
    shift = planted_shift(world, contacts, fps)
    moved = world + shift[:, None]
    targets = [pinned_targets(moved[:, ankle], planted, fps) for (_, _, ankle), planted in zip(legs, contacts.T)]
    for _ in range(REACH_ROUNDS):
        for (hip, knee, ankle), target in zip(legs, targets):
            reach = np.linalg.norm(world[:, knee] - world[:, hip], axis=-1)
            reach += np.linalg.norm(world[:, ankle] - world[:, knee], axis=-1)
            away = target - (world[:, hip] + shift)
            dist = np.linalg.norm(away, axis=-1)
            beyond = np.maximum(dist - REACH_SHARE * reach, 0.0)
            shift += away * (beyond / np.maximum(dist, 1e-12))[:, None]
    out = world + shift[:, None]
    for (hip, knee, ankle), target in zip(legs, targets):
        out[:, knee], out[:, ankle] = two_bone_ik(out[:, hip], out[:, knee], out[:, ankle], target)
    return out, shift
