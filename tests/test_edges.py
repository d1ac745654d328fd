"""Edges inside the silhouette (mocap.edges) and the arm searches that follow them."""

from __future__ import annotations

import numpy as np

from mocap.edges import Edges
from mocap.silhouette.raster import Canvas, segment_quads, sweep_scorer

BAR = 6.0      # px: the width of the bar drawn over the trunk


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


def test_an_arm_over_the_trunk_scores_as_inside_the_silhouette_where_edges_are_followed():
    """With a sliver of the trunk's outline left unexplained, Eq. 1-3 on the partial
    silhouette rate an arm wholly over the fitted trunk (no pixel of the sliver
    covered) below one sticking out of the silhouette; on a canvas following edges
    the trunk under the arm counts as silhouette it covers, and the arm over the
    trunk wins."""
    sil, grey = trunk_with_bar()
    canvas = Canvas(sil, grey)
    canvas.commit(segment_quads(np.array([[50.0, 20.0]]), np.array([[50.0, 80.0]]), np.array([36.0])))
    starts, ends = np.array([[47.0, 25.0], [47.0, 25.0]]), np.array([[47.0, 75.0], [97.0, 25.0]])
    arms = segment_quads(starts, ends, np.full(2, BAR))[:, None]        # over the trunk, out of it
    plain, _ = sweep_scorer(canvas.fork(), arms)
    following, _ = sweep_scorer(canvas.fork(by_edges=True), arms)
    assert plain[0] < plain[1]
    assert following[0] > following[1]
    assert not Canvas(sil).fork(by_edges=True).by_edges          # no frame, no edges to follow
