"""Finding the body again after the tracker lost it (mocap.track.loss): a search of
the whole frame for the head by its colour model, the trunk hung from each head
found, the best pair kept if both match as well as they usually do.

Beyond the tracking paper (Pan, Zhuang and Liu, *Video motion capture in VBA*,
2000), which tracks from frame to frame only and so never finds a body it lost
(an occluder that crossed it, a jump cut, a performer who left the frame and came
back). Its own tools do the search: the head's morph block (mocap.track.blocks,
Eq. 3-5) scored on a grid over the whole frame, the best places refined by the
search path of Fig. 6; with them the head the image difference points to (the
tracker's own search on the frame, Eq. 1-5) and the last good pose's head. Each
head's trunk is searched from the last good pose's trunk hung from it; both
searches start only from the places that match best where they lie. The
limbs are then found from the trunk by the tracker's own limb search
(mocap.track.tracker), started from the last good pose carried by the trunk
(``carried``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from mocap.track import blocks
from mocap.track.blocks import M, N, THETA, X, Y, block_end, from_block, to_block
from mocap.track.parts import HEAD, TORSO

PEAKS = 6                  # the best places of the head's scan refined by the search path
SCAN_STEP = 0.4            # of the head's width: the spacing of the scan's grid
PEAK_SPACING = 1.0         # of the head's length: distinct places of the scan lie this far apart
ZOOMS = np.array([0.8, 1.0, 1.25])   # of the last good head's size: the sizes the head is looked for at
TRUNK_TURNS = np.radians(np.arange(-45.0, 46.0, 15.0))   # the trunk's turns tried from the last good one
CHUNK = 16384              # sub-pixel rows scored at once (OpenCV's remap takes fewer than 32767)
REFOUND = 0.7              # of their usual S: the least match of head and trunk found again
REFINED = 3                # heads refined by the search: the best matched where they lie
TRUNKS_REFINED = 3         # ... trunks hung from each head refined

# the tracker's searches: (frame, start block) -> the head's (block, S);
# (frame, start block, the head's block) -> the trunk's (block, S)
HeadSearch = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, float]]
TrunkSearch = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, float]]
# (frame, part, blocks (K, 5)) -> the part's S of each block where it lies, unrefined
Score = Callable[[np.ndarray, int, np.ndarray], np.ndarray]


class Found(NamedTuple):
    """A head and trunk found again: their blocks (2, 5) and S (2,)."""

    blocks: np.ndarray
    s: np.ndarray


def scanned(frame: np.ndarray, model: np.ndarray, grid: blocks.Grid,
            block: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(K, 5) ``block``'s shape (5,) moved to every place of a grid over ``frame``
    SCAN_STEP of its width apart (those whose both ends lie inside), and (K,) their S
    by the colour ``model``."""
    height, width = frame.shape[:2]
    step = max(SCAN_STEP * block[N], 2.0)
    xs, ys = np.arange(0.0, width, step), np.arange(0.0, height, step)
    cands = np.repeat(block[None], len(xs) * len(ys), axis=0)
    cands[:, X] = np.tile(xs, len(ys))
    cands[:, Y] = np.repeat(ys, len(xs))
    cands = cands[_inside(block_end(cands), frame.shape)]
    chunk = CHUNK // len(grid.along)
    s = np.concatenate([blocks.score(frame, model, grid, cands[i:i + chunk])
                        for i in range(0, len(cands), chunk)] or [np.zeros(0)])
    return cands, s


def scan_heads(frame: np.ndarray, model: np.ndarray, grid: blocks.Grid, head: np.ndarray,
               peaks: int = PEAKS) -> np.ndarray:
    """(K, 5) the ``peaks`` best head blocks of ``frame`` over the places of
    ``scanned`` (the ``head``'s shape moved there), scored by the head's colour
    ``model``; places nearer than PEAK_SPACING head lengths to a better one are left
    out (one place per head-like thing)."""
    cands, s = scanned(frame, model, grid, head)
    kept: list[np.ndarray] = []
    for cand in cands[np.argsort(-s)]:
        if all(np.hypot(*(cand[:2] - k[:2])) >= PEAK_SPACING * head[M] for k in kept):
            kept.append(cand)
            if len(kept) == peaks:
                break
    return np.array(kept).reshape(-1, 5)


def distinctness(frame: np.ndarray, model: np.ndarray, grid: blocks.Grid, block: np.ndarray) -> float:
    """How much better a part's ``block`` (5,) matches its colour ``model`` where it
    lies than the same block anywhere else in ``frame``: its S over the best S of the
    places of ``scanned`` at least the block's length away (inf where there are none).

    Rendered motion capture over cluttered, panning backgrounds
    (benchmarks/bench_track.py, bench_track_clips.py, tests/test_track_loss.py): a
    tracked head or trunk stands out 5 to 13 times; one whose match halved because
    what lies behind it changed, 1.7 to 3.5 times; one sitting on what is left where
    the body went (it left, a board covers it, a cut regraded its colours), at most
    1.03; a head and trunk partly off the body (arms thrown over the head, a spin:
    the trunk 10-20% of the body's height off, still on the shirt), up to 2.4."""
    cands, s = scanned(frame, model, grid, block)
    far = np.hypot(*(cands[:, :2] - block[:2]).T) >= block[M]
    own = blocks.score(frame, model, grid, block[None])[0]
    return float(own / s[far].max()) if far.any() else np.inf


def _inside(points: np.ndarray, shape: tuple) -> np.ndarray:
    """(K,) whether points (K, 2) lie inside a frame of ``shape``."""
    return ((points >= 0) & (points <= np.array([shape[1], shape[0]]) - 1)).all(axis=1)


def reacquired(frame: np.ndarray, starts: np.ndarray, good: np.ndarray, usual: np.ndarray,
               head_search: HeadSearch, trunk_search: TrunkSearch, score: Score) -> Found | None:
    """The head and trunk found again on ``frame``, or None, coarse to fine: each head
    block of ``starts`` (K, 5) at each of ZOOMS (the body may have come nearer or gone
    away) matched where it lies (``score``), the REFINED best refined by the
    tracker's ``head_search``; under each head refined that matches at least REFOUND
    of usual (a head matched worse is not looked under), the last good pose's trunk
    (``good`` (10, 5)) hung from it at each turn (``hung_trunks``) matched where it
    lies, the TRUNKS_REFINED best refined by ``trunk_search``. The pair whose worse
    match (S over the part's ``usual`` S (10,)) is best is kept if that is at least
    REFOUND.

    Refining every head at every zoom and the trunk at every turn under each (about
    130 block searches a lost frame) made a lost frame cost 10 times a tracked one;
    the search moves a block a few pixels, degrees and a tenth of its size, which
    seldom reorders places matched that far apart. The three best heads of all places
    and zooms, not the best zoom of each of the three best places: with those the
    board passing the performer (tests/test_track_loss.py) was found 5 frames late;
    two trunks of seven, not three: laugh_arms_up (benchmarks/bench_track_clips.py)
    lost 3 frames more."""
    heads = np.concatenate([zooms(start) for start in starts])
    best, best_ratio = None, -np.inf
    for start in heads[np.argsort(-score(frame, HEAD, heads))[:REFINED]]:
        head, s_head = head_search(frame, start)
        if s_head < REFOUND * usual[HEAD]:
            continue
        hung = hung_trunks(good, head)
        order = np.argsort(-score(frame, TORSO, hung))[:TRUNKS_REFINED]
        trunk, s_trunk = max((trunk_search(frame, start, head) for start in hung[order]),
                             key=lambda match: match[1])
        ratio = min(s_head / usual[HEAD], s_trunk / usual[TORSO])
        if ratio > best_ratio:
            best, best_ratio = Found(np.stack([head, trunk]), np.array([s_head, s_trunk])), ratio
    return best if best_ratio >= REFOUND else None


def zooms(head: np.ndarray) -> np.ndarray:
    """(Z, 5) the head block (5,) at each of ZOOMS of its size, about its middle."""
    out = np.repeat(head[None], len(ZOOMS), axis=0)
    out[:, M:] *= ZOOMS[:, None]
    middle = head[:2] + (block_end(head) - head[:2]) / 2
    out[:, :2] = middle - (block_end(out) - out[:, :2]) / 2
    return out


def hung_trunks(good: np.ndarray, head: np.ndarray) -> np.ndarray:
    """(A, 5) the last good pose's trunk block (``good`` (10, 5)) from the end of
    ``head`` (5,), grown as the head did, turned by each of TRUNK_TURNS (the body
    may have bent or leant since)."""
    trunks = np.repeat(good[None, TORSO], len(TRUNK_TURNS), axis=0)
    trunks[:, :2] = block_end(head)
    trunks[:, THETA] += TRUNK_TURNS
    trunks[:, M:] *= head[N] / good[HEAD, N]
    return trunks


def carried(good: np.ndarray, trunk: np.ndarray) -> np.ndarray:
    """The last good pose's blocks (10, 5) carried rigidly by its trunk to ``trunk``
    (5,): every block's two ends kept where they were in the trunk's block frame,
    widths grown as the trunk."""
    out = good.copy()
    zoom = trunk[M] / good[TORSO, M]
    for k, block in enumerate(good):
        start = from_block(to_block(block[:2], good[TORSO]), trunk)
        end = from_block(to_block(block_end(block), good[TORSO]), trunk)
        out[k] = blocks.between(start[None], end[None], block[N] * zoom)[0]
    return out
