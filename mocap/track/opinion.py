"""The person model's second opinion on every frame, beyond the paper: a part whose block ends lie farther than its
search radius from sure landmarks (mocap.person.SURE) is searched again from the landmarks' block and kept where it
matches about as well (tracker.BodyTracker.step); the limbs only where the landmarks' trunk is the tracked one."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mocap.person import SURE, Landmarks
from mocap.track import blocks
from mocap.track.blocks import N, block_end
from mocap.track.landmarks import SEED_JOINTS
from mocap.track.limbs import limb_cost
from mocap.track.parts import PART_JOINTS

OPINION_MATCH = 0.7  # of the tracked S (limbs: 1/S summed): the least a part searched again from the landmarks matches
# the tracker's searches: (start block) -> (block, S); a limb hung from a lower block -> (10, 5) blocks, (10,) S
Search = Callable[[np.ndarray], tuple[np.ndarray, float]]
Hang = Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]


def landmark_block(seen: Landmarks, k: int, width: float) -> np.ndarray | None:
    """Part k's block (5,) ``width`` px wide between its two landmarks, None unless both are sure."""
    ends = PART_JOINTS[k]
    if (seen.confidence[ends] < SURE).any():
        return None
    return blocks.between(seen.joints2d[ends[:1]], seen.joints2d[ends[1:]], width)[0]


def radius(block: np.ndarray) -> float:
    """A part's search radius (px): its block's width."""
    return float(block[N])


def off(block: np.ndarray, other: np.ndarray) -> float:
    """Pixels the farther end of ``block`` (5,) lies from the same end of ``other`` (5,)."""
    starts, ends = np.linalg.norm(block[:2] - other[:2]), np.linalg.norm(block_end(block) - block_end(other))
    return float(max(starts, ends))


def trunk_apart(seen: Landmarks, joints: np.ndarray, trunk: np.ndarray) -> float:
    """How far the sure landmarks of the trunk and head (landmarks.SEED_JOINTS) lie from the tracked ``joints``
    (16, 2) on average, in search radii of the tracked ``trunk`` block (inf: none sure)."""
    sure = [j for j in SEED_JOINTS if seen.confidence[j] >= SURE]
    if not sure:
        return float("inf")
    return float(np.linalg.norm(seen.joints2d[sure] - joints[sure], axis=-1).mean()) / radius(trunk)


def second_opinion(k: int, new: np.ndarray, s: np.ndarray, seen: Landmarks, search: Search) -> None:
    """Part k (the head or the trunk) of ``new`` (10, 5) with S ``s`` (10,) searched again from the landmarks' block
    where they disagree, kept where it matches at least OPINION_MATCH as well."""
    start = landmark_block(seen, k, new[k, N])
    if start is None or off(new[k], start) <= radius(new[k]):
        return
    found, s_found = search(start)
    if s_found >= OPINION_MATCH * s[k]:
        new[k], s[k] = found, s_found


def limb_opinion(k: int, new: np.ndarray, s: np.ndarray, seen: Landmarks, hang: Hang) -> None:
    """Limb k (upper part k) of ``new`` hung again from the landmarks' lower part where either part disagrees,
    kept where its parts' 1/S summed is at most 1 / OPINION_MATCH times as much."""
    upper, lower = (landmark_block(seen, i, new[i, N]) for i in (k, k + 1))
    if upper is None or lower is None:
        return
    if off(new[k], upper) <= radius(new[k]) and off(new[k + 1], lower) <= radius(new[k + 1]):
        return
    placed, similarity = hang(lower)
    if limb_cost(similarity, k) <= limb_cost(s, k) / OPINION_MATCH:
        new[:], s[:] = placed, similarity
