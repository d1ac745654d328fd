"""numpy's percentile of a 1-D array and median of each row, bit for bit, without its general path
(any axis, many q, NaNs): the 'linear' method (Hyndman and Fan's definition 7), index (n - 1) q,
the same partition and two-sided interpolation in the array's own float type."""

from __future__ import annotations

import numpy as np


def percentile(values: np.ndarray, q: float) -> float:
    """``np.percentile(values, q)`` of a 1-D float array without NaNs, 0 <= q <= 100,
    bit-identical."""
    a = np.asarray(values)
    if a.size == 0:
        raise ValueError("percentile of no values")
    n = a.size
    virtual = (n - 1) * (q / 100)
    if virtual >= n - 1:  # numpy's top end: both neighbours the largest, index -1
        lower, upper, gamma = n - 1, n - 1, virtual + 1
    else:
        lower = int(virtual)
        upper, gamma = lower + 1, virtual - lower
    part = np.partition(a, (lower, upper) if upper > lower else lower)
    return float(interpolate(part[lower], part[upper], gamma))


def row_medians(values: np.ndarray) -> np.ndarray:
    """``np.median(values, axis=1)`` of a 2-D float array without NaNs, bit-identical."""
    a = np.asarray(values)
    n = a.shape[1]
    if n == 0:
        raise ValueError("median of no values")
    half = n // 2
    if n % 2:
        return np.partition(a, half, axis=1)[:, half]
    part = np.partition(a, (half - 1, half), axis=1)
    return (part[:, half - 1] + part[:, half]) / a.dtype.type(2)


def nanpercentile(values: np.ndarray, q: float) -> float:
    """``np.nanpercentile(values, q)`` of a 1-D float array, bit-identical; NaN if all are NaN."""
    a = np.asarray(values)
    kept = a[~np.isnan(a)]
    return percentile(kept, q) if kept.size else float("nan")


def interpolate(a, b, t: float):
    """numpy's quantile interpolation from a to b at t: from a below t = 0.5, else from b."""
    diff = b - a
    if t >= 0.5:
        return b - diff * (1 - t)
    return a + diff * t
