"""Edges inside the silhouette (mocap.image.edges) and the arm searches that follow them."""

from __future__ import annotations

import numpy as np

from mocap.body import JOINTS, SEGMENT_INDEX, SEGMENT_JOINTS, WIDTH
from mocap.image.edges import Edges
from mocap.silhouette.raster import Canvas, segment_quads, sweep_scorer

BAR = 6.0  # px: the width of the bar drawn over the trunk


def trunk_with_bar() -> tuple[np.ndarray, np.ndarray]:
    """A 40x60 px trunk in a frame whose grey levels show a vertical bar over it."""
    sil = np.zeros((100, 100), np.uint8)
    sil[20:80, 30:70] = 1
    grey = np.full(sil.shape, 200, np.uint8)
    grey[20:80, 30:70] = 90
    grey[25:75, 44:50] = 160
    return sil, grey


def vertical(x: float, top: float = 28.0, bottom: float = 72.0) -> tuple[np.ndarray, np.ndarray]:
    return np.array([[[x, top]]]), np.array([[[x, bottom]]])


def test_a_segment_on_an_outline_inside_the_silhouette_is_supported_flat_colour_and_the_silhouettes_own_outline_are_not():
    edges = Edges.inside(*trunk_with_bar()[::-1])
    on_bar = edges.support(*vertical(47.0), np.array([BAR]))[0]
    beside = edges.support(*vertical(58.0), np.array([BAR]))[0]
    on_outline = edges.support(*vertical(30.0 + BAR / 2), np.array([BAR]))[0]
    assert on_bar > 0.8
    assert beside < 0.05
    assert on_outline < 0.05


def test_an_arm_over_the_fitted_trunk_is_placed_by_the_edges_not_by_its_length():
    """The silhouette cannot tell where an arm in front of the fitted trunk lies (a
    strip of the trunk left unexplained, which only a fourth candidate covers): Eq. 1-3
    on the partial silhouette rate such arms alike whatever their length (counting
    the trunk under an arm as silhouette it covers made the longest arm win), and
    the frame's edges pick the one on the bar's outline."""
    sil, grey = trunk_with_bar()
    canvas = Canvas(sil, grey)
    canvas.commit(
        segment_quads(
            np.array([[41.0, 20.0], [62.0, 20.0]]), np.array([[41.0, 80.0], [62.0, 80.0]]), np.array([22.0, 16.0])
        )
    )
    following = canvas.fork(by_edges=True)
    tops, bottoms = np.array([40.0, 25.0, 25.0, 25.0]), np.array([60.0, 75.0, 75.0, 75.0])
    xs = np.array([47.0, 47.0, 60.0, 53.0])  # on the bar short and long, beside it, on the strip
    starts, ends = np.column_stack([xs, tops]), np.column_stack([xs, bottoms])
    scores, _ = sweep_scorer(following, segment_quads(starts, ends, np.full(4, BAR))[:, None])
    assert np.ptp(scores[:3]) < 1e-9 and scores[3] > scores[0]
    lower = SEGMENT_INDEX["lower_arm_l"]
    joints = np.zeros((4, len(JOINTS), 2))
    joints[:, SEGMENT_JOINTS[lower, 0]], joints[:, SEGMENT_JOINTS[lower, 1]] = starts, ends
    edges = following.edge_scores(joints, [lower], BAR / WIDTH[lower])
    assert edges[1] > edges[2] + 0.1
    assert not Canvas(sil).fork(by_edges=True).by_edges  # no frame, no edges to follow
