"""The review queue (the app's Review): which frames' fits deserve a look, and why.

Signs of doubt over a session's resolved 2D joints: a low score (S of Eq. 3, or the tracking's
reliability), a segment seen end-on (its direction and Eq. 5 depth least sure), a foreshortening
sign the clip solve found a close call (toward and away cost nearly alike, on a segment whose depth
is at stake), a Table 1 joint limit broken, a likely left/right swap of hands or feet, a
silhouette partly from a guessed background; the closer a frame's closest call, the higher it
ranks. Lost tracking stretches come first (``lost_stretches``); the tracking method otherwise stops
evenly (``covering``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.body import (
    ANGLE_LIMITS,
    BODY_HEIGHT,
    JOINT_INDEX,
    LIMB_JOINTS,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    segment_label,
)
from mocap.silhouette.masks import DOUBTFUL
from mocap.track.loss import stretches

LOW_SCORE = 0.7  # S below this is a doubtful fit
END_ON_RATIO = 0.3  # seen length / length below this: the segment points at the camera
AT_STAKE_RATIO = 0.95  # seen length / length below this: its sign moves the 3D (|dZ| >= 0.3 length)
CLOSE_CALL = 2.0  # a sign's cost margin (signpath.sign_margins) below this: the two choices are
# within a likelihood ratio of e^2 of each other
SWAP_MARGIN = 0.5  # crossed distances below this fraction of the kept ones: a swap
SWAP_MIN_MOVE = 0.03  # of the body height: smaller motions say nothing about sides
REASON_WEIGHT = 0.3  # doubt added by each reason beyond the score's own 1 - S
LOST_DOUBT = 10.0  # doubt of a lost stretch: above every other reason's
_PAIRS = tuple((f"{names[-1]}_l", f"{names[-1]}_r") for names in LIMB_JOINTS.values())  # limb ends


@dataclass(frozen=True)
class Doubt:
    """A frame worth reviewing: how doubtful (higher first) and why."""

    frame: int
    value: float
    reasons: tuple[str, ...]


def seen_fractions(joints2d: np.ndarray, px_per_unit: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(F, 10) each segment's length in the image over its length."""
    ends = joints2d[:, SEGMENT_JOINTS]
    return np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1) / px_per_unit[:, None] / lengths


def close_calls(margins: np.ndarray | None, seen: np.ndarray) -> np.ndarray:
    """(F, 10) bool: signs whose cost ``margins`` are below CLOSE_CALL on segments at stake (``seen``
    fractions below AT_STAKE_RATIO); none without margins."""
    if margins is None:
        return np.zeros(seen.shape, bool)
    return (np.nan_to_num(margins, nan=np.inf) < CLOSE_CALL) & (seen < AT_STAKE_RATIO)


def broken_limits(joints2d: np.ndarray) -> np.ndarray:
    """(F, len(ANGLE_LIMITS)) bool: image angles outside Table 1's joint limits."""
    out = []
    for segment, (lo, hi) in ANGLE_LIMITS.items():
        a, b = SEGMENT_JOINTS[SEGMENT_INDEX[segment]]
        d = joints2d[:, b] - joints2d[:, a]
        angle = np.degrees(np.arctan2(-d[:, 1], d[:, 0])) % 360.0
        out.append((angle < lo) | (angle > hi))
    return np.stack(out, axis=1)


def likely_swaps(joints2d: np.ndarray, px_per_unit: np.ndarray) -> np.ndarray:
    """(F, 2) bool for hands and feet: each of the pair lies much nearer the other's
    place on the previous frame than its own (frame 0 never)."""
    out = np.zeros((len(joints2d), len(_PAIRS)), bool)
    for p, (left, right) in enumerate(_PAIRS):
        now = joints2d[1:, [JOINT_INDEX[left], JOINT_INDEX[right]]]
        before = joints2d[:-1, [JOINT_INDEX[left], JOINT_INDEX[right]]]
        kept = np.linalg.norm(now - before, axis=-1).sum(-1)
        crossed = np.linalg.norm(now - before[:, ::-1], axis=-1).sum(-1)
        moved = kept > SWAP_MIN_MOVE * BODY_HEIGHT * px_per_unit[1:]
        out[1:, p] = moved & (crossed < SWAP_MARGIN * kept)
    return out


def lost_stretches(session) -> list[Doubt]:
    """A stop at the first frame of every stretch where the body was lost, longest first."""
    out = [
        Doubt(
            first,
            LOST_DOUBT + (stop - first) / session.n_frames,
            (f"body lost on frames {first}-{stop - 1}: mark the body here",),
        )
        for first, stop in stretches(session.lost)
    ]
    return sorted(out, key=lambda d: (-d.value, d.frame))


def review_queue(session) -> list[Doubt]:
    """Every doubtful frame with a person of a session, most doubtful first, after ``lost_stretches``."""
    inputs = session.inputs
    scores = session.scores
    seen = seen_fractions(inputs.joints2d, inputs.px_per_unit, inputs.lengths)
    margins = session.sign_margins()
    close = close_calls(margins, seen)
    signs = (
        seen < END_ON_RATIO,
        close,
        broken_limits(inputs.joints2d),
        likely_swaps(inputs.joints2d, inputs.px_per_unit),
    )
    guessed = session.silhouette_confidence
    guessed = np.zeros(len(scores), bool) if guessed is None else guessed < DOUBTFUL
    queue = []
    for i in np.flatnonzero(np.isfinite(scores)):
        reasons = _reasons(
            f"{session.score_name} {scores[i]:.2f}", scores[i] < LOW_SCORE, *(sign[i] for sign in signs)
        ) + (GUESSED,) * bool(guessed[i])
        closest = 1.0 - margins[i][close[i]].min() / CLOSE_CALL if close[i].any() else 0.0
        if reasons:
            value = 1.0 - scores[i] + REASON_WEIGHT * (len(reasons) + closest)
            queue.append(Doubt(int(i), float(value), reasons))
    return lost_stretches(session) + sorted(queue, key=lambda d: (-d.value, d.frame))


GUESSED = "silhouette partly guessed (the performer never leaves those pixels: a clean plate helps)"


def covering(queue: list[Doubt], n_frames: int, spacing: int) -> list[Doubt]:
    """A stop at the middle of every 2 ``spacing``-frame stretch (pins carry ``spacing`` frames
    each way), most doubtful first by the stretch's worst frame in ``queue``; lost stretches stay
    first. Beyond the paper: the tracking's doubts are weak guides, even stops serve users better."""
    width = 2 * spacing
    lost = [d for d in queue if d.value >= LOST_DOUBT]
    queue = [d for d in queue if d.value < LOST_DOUBT]
    by_frame = {d.frame: d for d in queue}
    stops = []
    for start in range(0, n_frames, width):
        frames = range(start, min(start + width, n_frames))
        middle = min(start + spacing, n_frames - 1)
        top = max((by_frame[f] for f in frames if f in by_frame), key=lambda d: d.value, default=None)
        reasons = (
            ("nothing doubtful nearby",)
            if top is None
            else tuple(r if top.frame == middle else f"{r} (frame {top.frame})" for r in top.reasons)
        )
        stops.append(Doubt(middle, 0.0 if top is None else top.value, reasons))
    return lost + sorted(stops, key=lambda d: (-d.value, d.frame))


def _reasons(
    score: str, low: bool, end_on: np.ndarray, close: np.ndarray, limits: np.ndarray, swaps: np.ndarray
) -> tuple[str, ...]:
    """One frame's doubts in words (``score``: the frame's score, named)."""
    return (
        (f"low {score}",) * bool(low)
        + tuple(f"{segment_label(SEGMENT_NAMES[k])} seen end-on" for k in np.flatnonzero(end_on))
        + tuple(f"{segment_label(SEGMENT_NAMES[k])}: toward or away, a close call" for k in np.flatnonzero(close))
        + tuple(f"{segment_label(name)} outside its joint limit" for name, bad in zip(ANGLE_LIMITS, limits) if bad)
        + tuple(f"{('hands', 'feet')[p]} may have swapped sides" for p in np.flatnonzero(swaps))
    )
