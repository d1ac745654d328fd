"""mocap.image.percentile gives numpy's percentiles bit for bit."""

import numpy as np
import pytest

from mocap.image.percentile import nanpercentile, percentile, row_medians

QS = (0, 10, 12.5, 25, 33.3, 50, 75, 90, 95, 100)


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_percentile_equals_numpys(dtype):
    rng = np.random.default_rng(1)
    for n in (1, 2, 3, 7, 100, 333):
        for values in (rng.normal(size=n), rng.integers(0, 9, size=n).astype(float), rng.exponential(size=n) * 1e3):
            values = values.astype(dtype)
            for q in QS:
                assert percentile(values, q) == float(np.percentile(values, q)), (n, q)


def test_nanpercentile_equals_numpys():
    rng = np.random.default_rng(2)
    for n in (1, 4, 50, 301):
        values = rng.uniform(0.2, 1.0, size=n)
        values[rng.random(n) < 0.3] = np.nan
        values[0] = 0.5
        for q in QS:
            assert nanpercentile(values, q) == float(np.nanpercentile(values, q)), (n, q)
    assert np.isnan(nanpercentile(np.full(3, np.nan), 50))


@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_row_medians_equal_numpys(dtype):
    rng = np.random.default_rng(3)
    for n in (1, 2, 3, 8, 101, 1000):
        for values in (
            rng.normal(size=(3, n)),
            rng.integers(0, 9, size=(3, n)).astype(float),
            rng.uniform(0.5, 2.0, size=(3, n)),
        ):
            values = values.astype(dtype)
            expected = np.median(values, axis=1)
            got = row_medians(values)
            assert got.dtype == expected.dtype and np.array_equal(got, expected), n
