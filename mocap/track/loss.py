"""Noticing that the tracker lost the body: a confidence in [0, 1] for every part on
every frame from what the tracking (Pan, Zhuang and Liu, *Video motion capture in
VBA*, 2000, section "Feature tracking") already knows, and which frames are lost.

Beyond the paper, which takes the similarity S of a part's match as its
reliability. A tracker that lost the body still matches something (clutter, the
image's border, where blocks are clipped to): its S drops, but not always far. So
each part's confidence is the product of five checks, each 1 where the part looks
as tracked and falling to 0 where it looks lost:

- its match S against the part's usual S (its median over the frames not lost):
  full from MATCH_FULL of it, none below MATCH_NONE;
- the body's change of scale (the head block's length) since the last frame;
- its length against the calibrated one at the body's scale (a part stretched past
  its bone's length is on something else);
- how fast its ends moved, in metres per second at the body's scale;
- whether its ends stay inside the frame (a lost tracker drifts to the border).

A frame is lost where the head or the trunk, which every limb hangs from, is below
LOST, and stays lost until the body is found again (mocap.track.reacquire) with both
above FOUND; the limbs' joints take the trunk's confidence too (``joint_confidence``).
Where the head and the trunk both stand out of the frame (DISTINCT times better
matched where they lie than anywhere else, mocap.track.reacquire.distinctness) the
body is held whatever their match against the usual S (mocap.track.tracker).
"""

from __future__ import annotations

import numpy as np

from mocap.body import JOINT_INDEX, JOINTS, LENGTH, SEGMENT_INDEX
from mocap.track.blocks import M, X, Y, block_end
from mocap.track.calibration import UNIT_M
from mocap.track.parts import HEAD, LIMBS, PART_JOINTS, TORSO

MATCH_FULL, MATCH_NONE = 0.7, 0.25   # of the part's usual S
SCALE_FULL, SCALE_NONE = 0.08, 0.3   # |log| of the body's change of scale over one frame
STRETCH_FULL, STRETCH_NONE = 1.25, 1.8   # a part's length over its calibrated length
# metres per second an end of the part may move (the trunk, the rest)
SPEED = {TORSO: (3.0, 8.0), HEAD: (3.0, 8.0)}
LIMB_SPEED = (8.0, 20.0)
BORDER_PX = 2.0                      # an end this near the border (or past it) has left the frame
GAP_S = 0.4                          # seconds: lost stretches no longer are bridged (``bridged``)
FOUND = 0.7                          # ... both above this again: the body is found again
LOST = 0.3                           # the head's or the trunk's confidence below this: the body is lost
DISTINCT = 2.5                       # ... unless both match this many times better than anywhere else
HEAD_M = float(LENGTH[SEGMENT_INDEX["head"]]) * UNIT_M


def ramp(value: np.ndarray, full: float, none: float) -> np.ndarray:
    """1 where ``value`` is at most ``full``, 0 from ``none`` on, linear between."""
    return np.clip((none - np.asarray(value, float)) / (none - full), 0.0, 1.0)


def part_confidence(new: np.ndarray, last: np.ndarray, s: np.ndarray, usual: np.ndarray,
                    expected: np.ndarray, shape: tuple, fps: float) -> np.ndarray:
    """(10,) the confidence of every part's block ``new`` (10, 5) on a frame of
    ``shape``, tracked from ``last`` (10, 5) with similarities ``s`` (10,) against the
    parts' ``usual`` S (inf: none yet, the match then counts full), ``expected`` (10,)
    its calibrated length in pixels at the frame's scale, ``fps`` frames a second."""
    zoom = new[HEAD, M] / last[HEAD, M]
    px_per_m = new[HEAD, M] / HEAD_M
    match = np.where(np.isfinite(usual), ramp(-s / usual, -MATCH_FULL, -MATCH_NONE), 1.0)
    scale = ramp(abs(np.log(zoom)), SCALE_FULL, SCALE_NONE)
    stretch = ramp(new[:, M] / expected, STRETCH_FULL, STRETCH_NONE)
    moved = np.maximum(np.linalg.norm(new[:, :2] - last[:, :2], axis=-1),
                       np.linalg.norm(block_end(new) - block_end(last), axis=-1)) * fps / px_per_m
    speed = np.array([ramp(v, *SPEED.get(k, LIMB_SPEED)) for k, v in enumerate(moved)])
    return match * scale * stretch * speed * inside(new, shape)


def inside(new: np.ndarray, shape: tuple) -> np.ndarray:
    """(10,) 1 for a block whose both ends lie inside the frame, else 0."""
    ends = np.stack([new[:, [X, Y]], block_end(new)], axis=1)             # (10, 2, 2)
    size = np.array([shape[1], shape[0]], float) - 1.0
    ok = (ends >= BORDER_PX) & (ends <= size - BORDER_PX)
    return ok.all(axis=(1, 2)).astype(float)


def _joint_parts() -> list[tuple[int, ...]]:
    """For every joint, the parts its confidence is the least of: the head's joints
    the head's; the trunk's (with shoulders and hips) the trunk's; a limb's middle
    and end joints both of its parts' and the trunk's, which carries the limb."""
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
    """Whether the body is lost on a frame of parts' confidence ``parts`` (10,): the
    head or the trunk below LOST, or below FOUND where it was lost on the frame
    before (a tracker on clutter matches it now and then as well as the body)."""
    return min(parts[HEAD], parts[TORSO]) < (FOUND if was_lost else LOST)


def stretches(mask: np.ndarray) -> list[tuple[int, int]]:
    """The runs of True in ``mask`` (F,) as (first, stop) frame pairs."""
    edges = np.diff(np.r_[0, np.asarray(mask, int), 0])
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def bridged(joints2d: np.ndarray, lost: np.ndarray, gap: int) -> tuple[np.ndarray, np.ndarray]:
    """The joints (F, 16, 2) with every ``lost`` frame's put between the nearest
    found frames (linear interpolation; held beyond the clip's first or last found
    frame), and (F,) bool the frames that stay lost: those of lost stretches longer
    than ``gap`` frames or touching the clip's end (what is not seen on either side
    is not made up). The joints of frames left lost still get the bridged values, so
    that the reconstruction runs on a sane body; the motion file gives them none."""
    out, found = joints2d.copy(), np.flatnonzero(~lost)
    if not len(found):
        return out, np.ones(len(lost), bool)
    idx = np.flatnonzero(lost)
    for j in range(joints2d.shape[1]):
        for c in range(2):
            out[idx, j, c] = np.interp(idx, found, joints2d[found, j, c])
    left = np.zeros(len(lost), bool)
    for first, stop in stretches(lost):
        left[first:stop] = stop - first > gap or stop == len(lost)
    return out, left
