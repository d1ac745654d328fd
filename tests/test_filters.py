"""mocap.filters and mocap.rotation give the lift what scipy.ndimage and
scipy.spatial.transform gave it: the filters the same numbers bit for bit, the rotations
the same to the last bits (the motion files written are the same)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import ndimage
from scipy.spatial.transform import Rotation as ScipyRotation
from scipy.spatial.transform import Slerp as ScipySlerp

from mocap import filters
from mocap.rotation import Rotation, Slerp

RNG = np.random.default_rng(7)


def _track(n: int, *shape: int) -> np.ndarray:
    return RNG.normal(size=(n, *shape)) * 10 ** RNG.uniform(-3, 3)


@pytest.mark.parametrize("n", [1, 4, 25, 90])
@pytest.mark.parametrize("sigma", [1e-6, 0.7, 2.0, 7.5, 30.0])
def test_gaussian_smooth_is_scipys_gaussian_filter1d(n, sigma):
    x = _track(n, 2, 3)
    assert np.array_equal(filters.gaussian_smooth(x, sigma),
                          ndimage.gaussian_filter1d(x, sigma, axis=0, mode="nearest"))


@pytest.mark.parametrize("n", [1, 3, 40])
@pytest.mark.parametrize("width", [1, 2, 5, 8, 31])
def test_running_ranks_are_scipys_rank_filters(n, width):
    x = _track(n, 4, 2)
    assert np.array_equal(filters.running_median(x, width),
                          ndimage.median_filter(x, size=(width, 1, 1), mode="nearest"))
    line = x[:, 0, 0]
    for percent in (0.0, 10.0, 50.0, 100.0):
        assert np.array_equal(filters.running_percentile(line, percent, width),
                              ndimage.percentile_filter(line, percent, size=width, mode="nearest"))


@pytest.mark.parametrize("n", [1, 4, 60])
@pytest.mark.parametrize("width", [1, 2, 3, 4, 7])
def test_binary_runs_are_scipys_morphology(n, width):
    bits = RNG.random((n, 2)) < 0.5
    run = np.ones((width, 1), bool)
    assert np.array_equal(filters.closed_then_opened(bits, width),
                          ndimage.binary_opening(ndimage.binary_closing(bits, run, border_value=0), run))
    assert np.array_equal(filters.running_any(bits[:, 0], width),
                          ndimage.maximum_filter1d(bits[:, 0].astype(np.uint8), width, mode="constant") > 0)


def test_rotations_are_scipys():
    quats, other = RNG.normal(size=(2, 200, 4))
    rotvecs = RNG.normal(size=(200, 3)) * np.where(RNG.random((200, 1)) < 0.2, 1e-4, 1.0)
    ours, theirs = Rotation.from_quat(quats), ScipyRotation.from_quat(quats)
    matrices = theirs.as_matrix() + RNG.normal(size=(200, 3, 3)) * 1e-6    # some not orthogonal
    vectors = RNG.normal(size=(200, 3))
    pairs = [
        (ours.as_quat(), theirs.as_quat()),
        (ours.as_matrix(), theirs.as_matrix()),
        (Rotation.from_matrix(matrices).as_quat(), ScipyRotation.from_matrix(matrices).as_quat()),
        (Rotation.from_rotvec(rotvecs).as_quat(), ScipyRotation.from_rotvec(rotvecs).as_quat()),
        ((ours * Rotation.from_quat(other)).as_quat(), (theirs * ScipyRotation.from_quat(other)).as_quat()),
        (ours.inv().apply(vectors), theirs.inv().apply(vectors)),
        (ours.apply([0.0, 0.0, 1.0]), theirs.apply([0.0, 0.0, 1.0])),
        (Rotation.identity(3).as_quat(), ScipyRotation.identity(3).as_quat()),
    ]
    for mine, scipys in pairs:
        assert np.array_equal(mine, scipys)
    assert np.allclose(ours.as_rotvec(), theirs.as_rotvec(), rtol=0, atol=1e-14)


def test_slerp_is_scipys():
    keys = np.sort(RNG.choice(100, 12, replace=False))
    quats = RNG.normal(size=(12, 4))
    times = np.clip(np.arange(100), keys[0], keys[-1])
    assert np.allclose(Slerp(keys, Rotation.from_quat(quats))(times).as_quat(),
                       ScipySlerp(keys, ScipyRotation.from_quat(quats))(times).as_quat(), rtol=0, atol=1e-14)
