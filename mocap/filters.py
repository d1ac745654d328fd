"""Running filters along time (axis 0) for the lift: the few of scipy.ndimage's that it
uses, in numpy, giving the same numbers bit for bit (tests/test_filters.py holds them to
scipy.ndimage's), since importing scipy.ndimage takes a quarter of a second of every
`mocap fit`'s start.

A window of ``width`` frames around frame i spans frames i - width // 2 to
i - width // 2 + width - 1, as scipy.ndimage's with origin 0; at the ends of the track
the end frames repeat (its "nearest" mode) unless said otherwise.
"""

from __future__ import annotations

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view

TRUNCATE = 4.0      # the Gaussian's kernel reaches this many sigmas (scipy.ndimage's default)


def gaussian_smooth(x: np.ndarray, sigma: float) -> np.ndarray:
    """scipy.ndimage.gaussian_filter1d(x, sigma, axis=0, mode="nearest"): the sampled
    Gaussian, normalised, reaching TRUNCATE sigmas, summed as scipy's correlate1d sums
    a symmetric kernel (the centre's term, then the pairs from the outermost in)."""
    radius = int(TRUNCATE * float(sigma) + 0.5)
    offsets = np.arange(-radius, radius + 1)
    weights = np.exp(-0.5 / (sigma * sigma) * offsets ** 2)
    weights = weights / weights.sum()
    padded = _edge_padded(np.asarray(x, dtype=np.float64), radius, radius)
    n = len(x)
    out = padded[radius:radius + n] * weights[radius]
    for j in range(radius, 0, -1):
        out += (padded[radius - j:radius - j + n] + padded[radius + j:radius + j + n]) * weights[radius - j]
    return out.astype(np.asarray(x).dtype, copy=False)


def running_median(x: np.ndarray, width: int) -> np.ndarray:
    """scipy.ndimage.median_filter along axis 0 over ``width`` frames ("nearest"):
    the window's value of rank width // 2."""
    return running_rank(x, width, width // 2)


def running_percentile(x: np.ndarray, percent: float, width: int) -> np.ndarray:
    """scipy.ndimage.percentile_filter along axis 0 over ``width`` frames ("nearest"):
    the window's value of rank int(width * percent / 100) (the largest at 100)."""
    rank = width - 1 if percent == 100.0 else int(float(width) * percent / 100.0)
    return running_rank(x, width, rank)


def running_rank(x: np.ndarray, width: int, rank: int) -> np.ndarray:
    """The window's ``rank``-th smallest value at every frame ("nearest")."""
    windows = sliding_window_view(_edge_padded(np.asarray(x), width // 2, width - 1 - width // 2), width, axis=0)
    return np.partition(windows, rank, axis=-1)[..., rank]


def running_any(x: np.ndarray, width: int) -> np.ndarray:
    """Whether any frame of the window is set (bool), frames beyond the ends unset:
    scipy.ndimage.maximum_filter1d(x, width, axis=0, mode="constant") > 0."""
    return _within(x, width // 2, width - 1 - width // 2, np.any)


def closed_then_opened(x: np.ndarray, width: int) -> np.ndarray:
    """scipy.ndimage.binary_opening(binary_closing(x, s, border_value=0), s) for ``s``
    a run of ``width`` frames along axis 0 (bool): gaps shorter than the run filled,
    then set runs shorter than it cleared (beyond the ends is unset, so a set run
    within width // 2 of an end is cut there as scipy cuts it)."""
    after, before = width // 2, width - 1 - width // 2         # the dilation's reach, reflected
    closed = _within(_within(x, before, after, np.any), after, before, np.all)
    return _within(_within(closed, after, before, np.all), before, after, np.any)


def _within(x: np.ndarray, before: int, after: int, reduce) -> np.ndarray:
    """``reduce`` (np.any or np.all) of the bool ``x`` over frames i - before to
    i + after at every frame i, frames beyond the ends unset."""
    padded = np.pad(np.asarray(x, bool), [(before, after)] + [(0, 0)] * (np.ndim(x) - 1))
    return reduce(sliding_window_view(padded, before + after + 1, axis=0), axis=-1)


def _edge_padded(x: np.ndarray, before: int, after: int) -> np.ndarray:
    return np.pad(x, [(before, after)] + [(0, 0)] * (x.ndim - 1), mode="edge")
