"""Finding the lost body again (mocap.track.loss), beyond the paper: the head's morph block (Eq. 3-5) scanned over the
frame and refined along Fig. 6's path, the trunk hung from it, the limbs from the last good pose (``carried``)."""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from mocap.track import blocks
from mocap.track.blocks import THETA, M, N, X, Y, block_end, from_block, to_block
from mocap.track.parts import HEAD, TORSO

PEAKS = 6  # the best places of the head's scan refined by the search path
SCAN_STEP = 0.4  # of the head's width: the spacing of the scan's grid
PEAK_SPACING = 1.0  # of the head's length: distinct places of the scan lie this far apart
ZOOMS = np.array([0.8, 1.0, 1.25])  # of the last good head's size: the sizes the head is looked for at
TRUNK_TURNS = np.radians(np.arange(-45.0, 46.0, 15.0))  # the trunk's turns tried from the last good one
CHUNK = 16384  # sub-pixel rows scored at once (OpenCV's remap takes fewer than 32767)
REFOUND = 0.7  # of their usual S: the least match of head and trunk found again
REFINED = 3  # heads refined by the search: the best matched where they lie
TRUNKS_REFINED = 3  # ... trunks hung from each head refined

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


def scanned(
    frame: np.ndarray, model: np.ndarray, grid: blocks.Grid, block: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(K, 5) ``block`` moved over a grid SCAN_STEP of its width apart (ends inside ``frame``), and (K,) their S."""
    height, width = frame.shape[:2]
    step = max(SCAN_STEP * block[N], 2.0)
    xs, ys = np.arange(0.0, width, step), np.arange(0.0, height, step)
    cands = np.repeat(block[None], len(xs) * len(ys), axis=0)
    cands[:, X] = np.tile(xs, len(ys))
    cands[:, Y] = np.repeat(ys, len(xs))
    cands = cands[_inside(block_end(cands), frame.shape)]
    chunk = CHUNK // len(grid.along)
    s = np.concatenate(
        [blocks.score(frame, model, grid, cands[i : i + chunk]) for i in range(0, len(cands), chunk)] or [np.zeros(0)]
    )
    return cands, s


def scan_heads(
    frame: np.ndarray, model: np.ndarray, grid: blocks.Grid, head: np.ndarray, peaks: int = PEAKS
) -> np.ndarray:
    """(K, 5) the ``peaks`` best head blocks of ``scanned``, each PEAK_SPACING head lengths from better ones."""
    cands, s = scanned(frame, model, grid, head)
    kept: list[np.ndarray] = []
    for cand in cands[np.argsort(-s)]:
        if all(np.hypot(*(cand[:2] - k[:2])) >= PEAK_SPACING * head[M] for k in kept):
            kept.append(cand)
            if len(kept) == peaks:
                break
    return np.array(kept).reshape(-1, 5)


def distinctness(frame: np.ndarray, model: np.ndarray, grid: blocks.Grid, block: np.ndarray) -> float:
    """``block`` (5,)'s S where it lies over the best S at least its length away in ``frame`` (inf: nowhere)."""
    cands, s = scanned(frame, model, grid, block)
    far = np.hypot(*(cands[:, :2] - block[:2]).T) >= block[M]
    own = blocks.score(frame, model, grid, block[None])[0]
    return float(own / s[far].max()) if far.any() else np.inf


def _inside(points: np.ndarray, shape: tuple) -> np.ndarray:
    """(K,) whether points (K, 2) lie inside a frame of ``shape``."""
    return ((points >= 0) & (points <= np.array([shape[1], shape[0]]) - 1)).all(axis=1)


def reacquired(
    frame: np.ndarray,
    starts: np.ndarray,
    good: np.ndarray,
    usual: np.ndarray,
    head_search: HeadSearch,
    trunk_search: TrunkSearch,
    score: Score,
    trunks: np.ndarray | None = None,
) -> Found | None:
    """Head and trunk found again on ``frame``, or None: heads of ``starts`` (K, 5) at ZOOMS, the REFINED best
    refined; under each matching REFOUND of ``usual`` (10,) the ``good`` (10, 5) trunk hung at each turn and
    ``trunks`` (T, 5), the TRUNKS_REFINED best refined; the pair whose worse ratio to ``usual`` is best, if at least
    REFOUND."""
    heads = np.concatenate([zooms(start) for start in starts])
    best, best_ratio = None, -np.inf
    for start in heads[np.argsort(-score(frame, HEAD, heads))[:REFINED]]:
        head, s_head = head_search(frame, start)
        if s_head < REFOUND * usual[HEAD]:
            continue
        hung = hung_trunks(good, head) if trunks is None else np.concatenate([hung_trunks(good, head), trunks])
        order = np.argsort(-score(frame, TORSO, hung))[:TRUNKS_REFINED]
        trunk, s_trunk = max((trunk_search(frame, start, head) for start in hung[order]), key=lambda match: match[1])
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
    """(A, 5) the ``good`` (10, 5) trunk from the end of ``head`` (5,), scaled as the head, turned by TRUNK_TURNS."""
    trunks = np.repeat(good[None, TORSO], len(TRUNK_TURNS), axis=0)
    trunks[:, :2] = block_end(head)
    trunks[:, THETA] += TRUNK_TURNS
    trunks[:, M:] *= head[N] / good[HEAD, N]
    return trunks


def carried(good: np.ndarray, trunk: np.ndarray) -> np.ndarray:
    """The ``good`` blocks (10, 5) carried rigidly by their trunk to ``trunk`` (5,), widths scaled as the trunk."""
    out = good.copy()
    zoom = trunk[M] / good[TORSO, M]
    for k, block in enumerate(good):
        start = from_block(to_block(block[:2], good[TORSO]), trunk)
        end = from_block(to_block(block_end(block), good[TORSO]), trunk)
        out[k] = blocks.between(start[None], end[None], block[N] * zoom)[0]
    return out
