"""Morph blocks and their weighted similarity (Pan, Zhuang and Liu 2000, Fig. 6-7, block-matching Eq. 3-5): a block is
a row (x, y, theta, m, n), (x, y) where a short side meets the middle line, theta in radians (y down)."""

from __future__ import annotations

import itertools
from collections.abc import Callable
from dataclasses import dataclass
from functools import cache, cached_property

import cv2
import numpy as np

X, Y, THETA, M, N = range(5)
ROWS, COLS = 14, 7  # largest sub-pixel grid of a block
CHANNEL_WEIGHTS = np.full(3, 1 / 3, np.float32)  # W_R, W_G, W_B of Eq. 3
CENTRE_WEIGHT, MARGIN_WEIGHT = 2.0, 1.0  # W_1 > W_2 of Eq. 4
Penalty = Callable[[np.ndarray], np.ndarray]  # blocks (K, 5) -> grey levels (K,), never negative
MIN_DIFF = 1.0  # grey levels: keeps S = 1/D finite for a perfect match
# candidates of Fig. 6's path scored in one call at most (search): with a lower part's penalties, a call costs about
# as much as this many candidates on top of them
BATCH = 256


@dataclass(frozen=True, eq=False)
class Grid:
    """Sub-pixel positions and Eq. 5 region weights: ``along`` (R,) 0 at (x, y) to 1 at the far side (units of m,
    maybe past both), ``across`` (C,) -1/2 to 1/2 (units of n), ``weights`` (R, C) W_1 / W_2 summing to one."""

    along: np.ndarray
    across: np.ndarray
    weights: np.ndarray

    @cached_property
    def basis(self) -> np.ndarray:
        """(3, R*C) every sub-pixel's (1, along, across), rows first: what a block's origin and axes weigh there."""
        along, across = np.meshgrid(self.along, self.across, indexing="ij")
        return np.stack([np.ones(along.size), along.ravel(), across.ravel()])


def make_grid(m: float, n: float, beyond: float = 0.0) -> Grid:
    """The grid of an m x n block, one sub-pixel per pixel up to ROWS x COLS, centre region b_1 of Eq. 5; a positive
    ``beyond`` extends rows that fraction of m past both ends, so a block's length shows in S."""
    rows = int(np.clip(round(m), 3, ROWS))
    cols = int(np.clip(round(n), 3, COLS))
    along = (np.arange(rows) + 0.5) / rows * (1 + 2 * beyond) - beyond
    across = (np.arange(cols) + 0.5) / cols - 0.5
    centre = (np.abs(along - 0.5) <= 0.25)[:, None] & (np.abs(across) <= 0.25)[None, :]
    weights = np.where(centre, CENTRE_WEIGHT, MARGIN_WEIGHT)
    return Grid(along, across, (weights / weights.sum()).astype(np.float32))


def between(start: np.ndarray, end: np.ndarray, n) -> np.ndarray:
    """Blocks (K, 5) of width(s) n from points ``start`` (K, 2) to ``end`` (K, 2)."""
    d = end - start
    return np.column_stack(
        [start, np.arctan2(d[:, 1], d[:, 0]), np.maximum(np.hypot(d[:, 0], d[:, 1]), 2.0), np.broadcast_to(n, len(d))]
    )


def block_end(blocks: np.ndarray) -> np.ndarray:
    """(..., 2) the middle of the far side of blocks (..., 5)."""
    return blocks[..., :2] + blocks[..., M, None] * np.stack(
        [np.cos(blocks[..., THETA]), np.sin(blocks[..., THETA])], axis=-1
    )


def to_block(point: np.ndarray, block: np.ndarray) -> np.ndarray:
    """A pixel in a block's frame: (along, across) in units of its height m."""
    d = point - block[:2]
    c, s = np.cos(block[THETA]), np.sin(block[THETA])
    return np.array([d[0] * c + d[1] * s, -d[0] * s + d[1] * c]) / block[M]


def from_block(coords: np.ndarray, block: np.ndarray) -> np.ndarray:
    """The pixel at block-frame coordinates (the inverse of ``to_block``)."""
    return block[:2] + turned(coords * block[M], block)


def turned(offset, block: np.ndarray) -> np.ndarray:
    """An offset (along, across) from a block's frame, in pixels, turned into the image's."""
    c, s = np.cos(block[THETA]), np.sin(block[THETA])
    a, b = offset
    return np.array([a * c - b * s, a * s + b * c])


def block_points(blocks: np.ndarray, grid: Grid) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (x, y), each (B*R, C) float32, of every block's sub-pixels: each block's origin and its
    axes (m along the middle line, n across it) times the grid's ``basis``, one matrix product for all blocks
    (a broadcast sum loops over rows only C long)."""
    cos, sin = np.cos(blocks[:, THETA]), np.sin(blocks[:, THETA])
    m, n = blocks[:, M], blocks[:, N]
    axes = np.array([[blocks[:, X], m * cos, -n * sin], [blocks[:, Y], m * sin, n * cos]])  # (2, 3, B)
    x, y = (axes.transpose(0, 2, 1) @ grid.basis).astype(np.float32)
    shape = (-1, len(grid.across))
    return x.reshape(shape), y.reshape(shape)


def sample_blocks(image: np.ndarray, blocks: np.ndarray, grid: Grid) -> np.ndarray:
    """Colours (B, R, C, 3) float32 of the blocks' sub-pixels by bilinear interpolation (steps 2-3)."""
    return sampled(image, blocks, grid).astype(np.float32)


def sampled(image: np.ndarray, blocks: np.ndarray, grid: Grid) -> np.ndarray:
    """``sample_blocks``'s colours as the image's type (uint8 frames): what ``score`` compares, unconverted."""
    x, y = block_points(np.atleast_2d(blocks), grid)
    out = cv2.remap(image, x, y, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
    return out.reshape(len(np.atleast_2d(blocks)), len(grid.along), len(grid.across), -1)


def similarity(model: np.ndarray, samples: np.ndarray, grid: Grid) -> np.ndarray:
    """S (B,) of sampled blocks against the colour model (R, C, 3), 1/S a weighted mean difference in grey levels:
        diff_ij = W_R |X_ij[R] - X'_ij[R]| + W_G |...G| + W_B |...B|          (Eq. 3)
        S = 1 / (W_1 sum_{b_1} diff_ij + W_2 sum_{b_2} diff_ij)                 (Eq. 4)
    A model (A, R, C, 3) holds A alternatives (beyond the paper): a block's S is its best one's."""
    if model.ndim == 4:
        return np.max([similarity(one, samples, grid) for one in model], axis=0)
    weights = (grid.weights[:, :, None] * CHANNEL_WEIGHTS).ravel()  # W_1 or W_2 times W_c
    diff = np.subtract(samples, model, dtype=np.float32)  # samples as sampled or float32
    np.abs(diff, out=diff)  # in place: a second array this large came fresh from the system, ten times slower
    return 1.0 / np.maximum(diff.reshape(len(samples), -1) @ weights, MIN_DIFF)  # (B, R * C * 3) @ weights


def score(image: np.ndarray, model: np.ndarray, grid: Grid, blocks: np.ndarray) -> np.ndarray:
    """S (B,) of blocks (B, 5) (or one block (5,)) of ``image`` against ``model``."""
    return similarity(model, sampled(image, blocks, grid), grid)


@cache
def ring(radius: int) -> np.ndarray:
    """Integer offsets (8r, 2) on the square ring of radius r, one circle of Fig. 6's path (r = 0: the centre); made
    once per radius (every search walks the same few), read-only."""
    if radius == 0:
        out = np.zeros((1, 2))
    else:
        r = radius
        side = np.arange(-r, r)
        out = np.concatenate(
            [
                np.c_[side, np.full(2 * r, -r)],
                np.c_[np.full(2 * r, r), side],
                np.c_[-side, np.full(2 * r, r)],
                np.c_[np.full(2 * r, -r), -side],
            ]
        )
    out.flags.writeable = False
    return out


def morphs(block: np.ndarray, d_theta: np.ndarray, d_m: np.ndarray, zoom: bool) -> np.ndarray:
    """Candidate blocks (K, 5): every (theta + d_theta, m + d_m); with ``zoom`` n' = n + (n/m) d_m
    (head zooms whole)."""
    t, dm = np.meshgrid(d_theta, d_m, indexing="ij")
    out = np.repeat(block[None], t.size, axis=0)
    out[:, THETA] += t.ravel()
    out[:, M] = np.maximum(block[M] + dm.ravel(), 2.0)
    if zoom:
        out[:, N] = block[N] * out[:, M] / block[M]
    return out


def penalised(s: np.ndarray, cands: np.ndarray, penalty: Penalty | None) -> np.ndarray:
    """S (K,) of blocks (K, 5) with ``penalty(cands)`` grey levels added to their 1/S; S as is without a penalty."""
    return s if penalty is None else 1.0 / (1.0 / s + penalty(cands))


def search(
    image: np.ndarray,
    model: np.ndarray,
    grid: Grid,
    start: np.ndarray,
    d_theta: np.ndarray,
    d_m: np.ndarray,
    *,
    zoom: bool = False,
    max_ring: int = 0,
    step: float = 1.0,
    penalty: Penalty | None = None,
) -> tuple[np.ndarray, float]:
    """The best block and its S on Fig. 6's path: all morphs at each point of a circle, on while a circle improves, up
    to ``max_ring`` circles ``step`` px apart (0: position fixed); ``penalty`` added to 1/S. Runs of circles
    (``circle_runs``) are scored in one call each, then walked circle by circle."""
    shapes = morphs(start, d_theta, d_m, zoom)
    best, best_s = start, -1.0
    for radii in circle_runs(max_ring, len(shapes)):
        cands, bounds = on_circles(shapes, radii, step)
        s = penalised(score(image, model, grid, cands), cands, penalty)
        for a, b in itertools.pairwise(bounds):
            k = a + int(np.argmax(s[a:b]))
            if s[k] <= best_s:
                return best, best_s
            best, best_s = cands[k], float(s[k])
    return best, best_s


def circle_runs(max_ring: int, shapes: int) -> list[range]:
    """Circles 0..max_ring of a path with ``shapes`` morphs in runs of radii, each as many as hold at most BATCH
    candidates (or one circle): a call's own cost (the penalties' most) is spared where a path goes on, at the
    price of a run's later circles where it stops."""
    runs, first, size = [], 0, 0
    for radius in range(max_ring + 1):
        n = shapes * max(8 * radius, 1)
        if size and size + n > BATCH:
            runs.append(range(first, radius))
            first, size = radius, 0
        size += n
    return [*runs, range(first, max_ring + 1)]


def on_circles(shapes: np.ndarray, radii: range, step: float) -> tuple[np.ndarray, np.ndarray]:
    """Blocks (K, 5): the morphs ``shapes`` (S, 5) at every point of the circles ``radii`` ``step`` px apart, circle
    by circle; and (len(radii) + 1,) where each circle's blocks start in them, then their end."""
    offsets = [ring(radius) * step for radius in radii]
    cands = np.repeat(shapes[None], sum(map(len, offsets)), axis=0)
    cands[..., :2] += np.concatenate(offsets)[:, None, :]
    return cands.reshape(-1, 5), np.cumsum([0, *(len(o) * len(shapes) for o in offsets)])


def lengthen(
    image: np.ndarray, model: np.ndarray, grid: Grid, block: np.ndarray, extra: np.ndarray, tolerance: float
) -> tuple[np.ndarray, float]:
    """The longest of ``block`` and its ``extra``-px lengthenings with S within ``tolerance`` of the best, its S."""
    cands = np.repeat(block[None], len(extra) + 1, axis=0)
    cands[1:, M] += extra
    s = score(image, model, grid, cands)
    k = int(np.flatnonzero(s >= (1.0 - tolerance) * s.max()).max())
    return cands[k], float(s[k])
