"""Edges of a frame along a limb's sides (beyond both papers): the cue for an arm in front of the
trunk, where Eq. 1-3's silhouette similarity cannot place it but its outline still shows.

A segment is scored by the gradient across its two long sides, inside the silhouette only
(the outline itself is Eq. 1-3's); mocap.track.limbs uses the whole frame's edges the same way.
"""

from __future__ import annotations

import cv2
import numpy as np

from mocap.image.percentile import percentile

INNER_PX = 2  # edges this close to the silhouette's outline are left out
SIDE_SAMPLES = np.linspace(0.15, 0.85, 6)  # points along each side, fractions of the length
EDGE_WEIGHT = 0.3  # S that a segment outlined by full-strength edges gains
STRONG_PERCENTILE = 90  # of gradient magnitudes inside: an edge of full strength
STRONG_STRIDE = 3  # px between the pixels whose magnitudes give that percentile
_PERPENDICULAR = np.array([-1.0, 1.0])  # (dx, dy) reversed times this: the normal (-dy, dx)
_BOTH_SIDES = np.array([1.0, -1.0]).reshape(2, 1, 1, 1, 1)


class Edges:
    """A frame's grey gradient in units of its STRONG_PERCENTILE magnitude: support ~1 on a clear
    outline, 0 on flat colour."""

    def __init__(self, grey: np.ndarray, where: np.ndarray | None = None):
        smooth = cv2.GaussianBlur(grey, (3, 3), 0)
        planes = [cv2.Sobel(smooth, cv2.CV_32F, 1, 0, ksize=3), cv2.Sobel(smooth, cv2.CV_32F, 0, 1, ksize=3)]
        if where is not None:
            for plane in planes:  # each plane by a 2D mask: faster than (H, W, 2) at once
                plane[~where] = 0.0
        gradient = cv2.merge(planes)
        sample = gradient[::STRONG_STRIDE, ::STRONG_STRIDE]
        if where is not None:
            sample = sample[where[::STRONG_STRIDE, ::STRONG_STRIDE]]
        magnitude = np.linalg.norm(sample.reshape(-1, 2), axis=-1)
        strong = percentile(magnitude, STRONG_PERCENTILE) if magnitude.size else 0.0
        self.gradient = gradient  # (H, W, 2): x and y
        self.unit = 1.0 / strong if strong > 0 else 0.0

    @classmethod
    def inside(cls, grey: np.ndarray, silhouette: np.ndarray) -> "Edges":
        """The edges of a frame inside a silhouette (both at the fit's scale), INNER_PX from its outline."""
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
        length = np.maximum(np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]), 1e-9)[..., None]
        normal = d[..., ::-1] * _PERPENDICULAR / length  # (B, k, 2)
        offset = normal * (np.asarray(widths, float)[..., None] / 2)
        along = starts[..., None, :] + SIDE_SAMPLES[:, None] * d[..., None, :]  # (B, k, T, 2)
        sides = along + offset[..., None, :] * _BOTH_SIDES  # (2, B, k, T, 2)
        g = cv2.remap(
            self.gradient,
            sides.reshape(-1, 1, 2).astype(np.float32),
            None,
            cv2.INTER_LINEAR,
            borderMode=cv2.BORDER_CONSTANT,
        ).reshape(sides.shape)
        g = g * normal[..., None, :]
        across = np.abs(g[..., 0] + g[..., 1]) * self.unit
        return np.minimum(across, 1.0).mean(axis=(0, 2, 3))
