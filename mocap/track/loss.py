"""Noticing that the tracker lost the body (beyond the paper): each part's confidence in [0, 1] is a product of ramps
on its S, scale change, stretch, speed and ends in frame; lost below LOST, found again above FOUND."""

from __future__ import annotations

import numpy as np

from mocap.body import JOINT_INDEX, JOINTS, LENGTH, SEGMENT_INDEX
from mocap.track.blocks import M, X, Y, block_end
from mocap.track.calibration import UNIT_M
from mocap.track.parts import HEAD, LIMBS, PART_JOINTS, TORSO

MATCH_FULL, MATCH_NONE = 0.7, 0.25  # of the part's usual S
SCALE_FULL, SCALE_NONE = 0.08, 0.3  # |log| of the body's change of scale over one frame
STRETCH_FULL, STRETCH_NONE = 1.25, 1.8  # a part's length over its calibrated length
# metres per second an end of the part may move (the trunk, the rest)
SPEED = {TORSO: (3.0, 8.0), HEAD: (3.0, 8.0)}
LIMB_SPEED = (8.0, 20.0)
BORDER_PX = 2.0  # an end this near the border (or past it) has left the frame
GAP_S = 0.4  # seconds: lost stretches no longer are bridged (``bridged``)
FOUND = 0.7  # ... both above this again: the body is found again
LOST = 0.3  # the head's or the trunk's confidence below this: the body is lost
DISTINCT = 2.5  # ... unless both match this many times better than anywhere else
HEAD_M = float(LENGTH[SEGMENT_INDEX["head"]]) * UNIT_M


def ramp(value: np.ndarray, full: float, none: float) -> np.ndarray:
    """1 where ``value`` is at most ``full``, 0 from ``none`` on, linear between."""
    return np.clip((none - np.asarray(value, float)) / (none - full), 0.0, 1.0)


def part_confidence(
    new: np.ndarray, last: np.ndarray, s: np.ndarray, usual: np.ndarray, expected: np.ndarray, shape: tuple, fps: float
) -> np.ndarray:
    """(10,) confidence of blocks ``new`` (10, 5) tracked from ``last`` (10, 5) with S ``s`` (10,) against ``usual`` S
    (inf: none yet), ``expected`` (10,) calibrated lengths in px, on a frame of ``shape`` at ``fps``."""
    zoom = new[HEAD, M] / last[HEAD, M]
    px_per_m = new[HEAD, M] / HEAD_M
    match = np.where(np.isfinite(usual), ramp(-s / usual, -MATCH_FULL, -MATCH_NONE), 1.0)
    scale = ramp(abs(np.log(zoom)), SCALE_FULL, SCALE_NONE)
    stretch = ramp(new[:, M] / expected, STRETCH_FULL, STRETCH_NONE)
    moved = (
        np.maximum(
            np.linalg.norm(new[:, :2] - last[:, :2], axis=-1), np.linalg.norm(block_end(new) - block_end(last), axis=-1)
        )
        * fps
        / px_per_m
    )
    speed = np.array([ramp(v, *SPEED.get(k, LIMB_SPEED)) for k, v in enumerate(moved)])
    return match * scale * stretch * speed * inside(new, shape)


def inside(new: np.ndarray, shape: tuple) -> np.ndarray:
    """(10,) 1 for a block whose both ends lie inside the frame, else 0."""
    ends = np.stack([new[:, [X, Y]], block_end(new)], axis=1)  # (10, 2, 2)
    size = np.array([shape[1], shape[0]], float) - 1.0
    ok = (ends >= BORDER_PX) & (ends <= size - BORDER_PX)
    return ok.all(axis=(1, 2)).astype(float)


def _joint_parts() -> list[tuple[int, ...]]:
    """For every joint, the parts whose least confidence is its own; a limb's joints also take the trunk's."""
    out = [(TORSO,)] * len(JOINTS)
    out[JOINT_INDEX["head_top"]] = out[JOINT_INDEX["neck"]] = (HEAD,)
    for k in LIMBS:
        out[PART_JOINTS[k, 1]] = out[PART_JOINTS[k + 1, 1]] = (TORSO, k, k + 1)
    return out


JOINT_PARTS = _joint_parts()


def joint_confidence(parts: np.ndarray) -> np.ndarray:
    """(..., 16) joints' confidence from the parts' (..., 10) (JOINT_PARTS)."""
    return np.stack([parts[..., list(p)].min(axis=-1) for p in JOINT_PARTS], axis=-1)


def body_lost(parts: np.ndarray, was_lost: bool = False) -> bool:
    """Whether the body is lost given parts' confidence ``parts`` (10,): head or trunk below LOST, or below FOUND if
    ``was_lost`` (a tracker on clutter now and then matches as well as the body)."""
    return min(parts[HEAD], parts[TORSO]) < (FOUND if was_lost else LOST)


def stretches(mask: np.ndarray) -> list[tuple[int, int]]:
    """The runs of True in ``mask`` (F,) as (first, stop) frame pairs."""
    edges = np.diff(np.r_[0, np.asarray(mask, int), 0])
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def bridged(joints2d: np.ndarray, lost: np.ndarray, gap: int) -> tuple[np.ndarray, np.ndarray]:
    """Joints (F, 16, 2) with ``lost`` frames interpolated (held past the ends), and (F,) bool the frames left lost:
    stretches over ``gap`` frames or touching either end of the clip, where nothing on one side says where the
    body was (a performer who walks in after the recording starts)."""
    out, found = joints2d.copy(), np.flatnonzero(~lost)
    if not len(found):
        return out, np.ones(len(lost), bool)
    idx = np.flatnonzero(lost)
    for j in range(joints2d.shape[1]):
        for c in range(2):
            out[idx, j, c] = np.interp(idx, found, joints2d[found, j, c])
    left = np.zeros(len(lost), bool)
    for first, stop in stretches(lost):
        left[first:stop] = stop - first > gap or first == 0 or stop == len(lost)
    return out, left
