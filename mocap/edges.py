"""Edges of a frame along a limb's sides: the cue where colour and silhouette have none.

Beyond both papers. An arm in front of the trunk lies wholly inside the silhouette,
where the similarity of Eq. 1-3 cannot tell one placement from another, and the fit
hangs it wherever it explains a sliver of the silhouette's edge. The frame still shows
the arm: its outline (a sleeve over a shirt, a forearm over the chest) is an edge
inside the silhouette, running along the arm. A candidate segment is scored by how
strongly the image changes across its two long sides (the gradient along the side's
normal), inside the silhouette only: the silhouette's own outline is Eq. 1-3's.
The tracking method's arm blocks use the whole frame's edges the same way
(mocap.tracker.outline_cost): a sleeve over a shirt of its colour matches the shirt
anywhere, and only its outline tells where it is.
"""

from __future__ import annotations

import cv2
import numpy as np
from scipy.ndimage import map_coordinates

INNER_PX = 2                       # edges this close to the silhouette's outline are left out
SIDE_SAMPLES = np.linspace(0.15, 0.85, 6)   # points along each side, fractions of the length
EDGE_WEIGHT = 0.3                  # S that a segment outlined by full-strength edges gains
STRONG_PERCENTILE = 90             # of gradient magnitudes inside: an edge of full strength


class Edges:
    """A frame's grey-level gradient in units of a strong edge of it (its
    STRONG_PERCENTILE magnitude where edges count), so that the support of a segment
    is about 1 on a clear outline, 0 on flat colour."""

    def __init__(self, grey: np.ndarray, where: np.ndarray | None = None):
        smooth = cv2.GaussianBlur(grey.astype(np.float32), (3, 3), 0)
        gx = cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3)
        gy = cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3)
        magnitude = np.hypot(gx, gy)
        magnitude = magnitude if where is None else magnitude[where]
        strong = float(np.percentile(magnitude, STRONG_PERCENTILE)) if magnitude.size else 0.0
        unit = (1.0 if where is None else where) / strong if strong > 0 else np.zeros(grey.shape)
        self.gx, self.gy = gx * unit, gy * unit

    @classmethod
    def inside(cls, grey: np.ndarray, silhouette: np.ndarray) -> "Edges":
        """The edges of a frame inside a silhouette (both at the fit's scale), INNER_PX
        from its outline."""
        size = 2 * INNER_PX + 1
        inner = cv2.erode((silhouette > 0).astype(np.uint8), np.ones((size, size), np.uint8)) > 0
        return cls(grey, inner)

    @classmethod
    def of_frame(cls, frame: np.ndarray) -> "Edges":
        """The edges of a whole BGR frame."""
        return cls(cv2.cvtColor(frame, cv2.COLOR_BGR2GRAY))

    def support(self, starts: np.ndarray, ends: np.ndarray, widths: np.ndarray) -> np.ndarray:
        """(B,) the mean edge strength (each point's capped at 1) across the long sides
        of segments (B, k) from ``starts`` to ``ends`` (B, k, 2), ``widths`` (k,) wide."""
        d = ends - starts
        length = np.maximum(np.linalg.norm(d, axis=-1, keepdims=True), 1e-9)
        normal = np.stack([-d[..., 1], d[..., 0]], axis=-1) / length          # (B, k, 2)
        offset = normal * (np.asarray(widths, float)[..., None] / 2)
        along = starts[..., None, :] + SIDE_SAMPLES[:, None] * d[..., None, :]  # (B, k, T, 2)
        sides = np.stack([along + offset[..., None, :], along - offset[..., None, :]])
        coords = [sides[..., 1].ravel(), sides[..., 0].ravel()]
        gx = map_coordinates(self.gx, coords, order=1, mode="constant").reshape(sides.shape[:-1])
        gy = map_coordinates(self.gy, coords, order=1, mode="constant").reshape(sides.shape[:-1])
        across = np.abs(gx * normal[None, ..., None, 0] + gy * normal[None, ..., None, 1])
        return np.minimum(across, 1.0).mean(axis=(0, 2, 3))
