"""Drawing a fitted body over an image (OpenCV): the views of the app and contact sheets."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.body import SEGMENT_JOINTS, SEGMENT_NAMES

# BGR per segment kind: torso/head white, the performer's left limbs orange, right ones blue
_COLOURS = {"torso": (240, 240, 240), "head": (240, 240, 240)}
_LEFT, _RIGHT = (40, 160, 255), (255, 140, 40)


def segment_colour(segment: str) -> tuple[int, int, int]:
    if segment in _COLOURS:
        return _COLOURS[segment]
    return _LEFT if segment.endswith("_l") else _RIGHT


def draw_skeleton(image: np.ndarray, joints2d: np.ndarray, thickness: int = 2,
                  colour: tuple[int, int, int] | None = None) -> np.ndarray:
    """Draw the 10 segments and 16 joints onto image (in place) and return it."""
    pts = np.round(np.asarray(joints2d) * 16).astype(np.int32)
    for name, (a, b) in zip(SEGMENT_NAMES, SEGMENT_JOINTS):
        cv2.line(image, tuple(pts[a]), tuple(pts[b]), colour or segment_colour(name),
                 thickness, cv2.LINE_AA, shift=4)
    for p in pts:
        cv2.circle(image, tuple(p), (thickness + 1) * 16, colour or (0, 0, 255), -1, cv2.LINE_AA, shift=4)
    return image


def silhouette_view(mask: np.ndarray, joints2d: np.ndarray | None) -> np.ndarray:
    """The silhouette in grey with the fitted model drawn over it."""
    view = cv2.cvtColor((mask > 0).astype(np.uint8) * 110, cv2.COLOR_GRAY2BGR)
    if joints2d is not None:
        draw_skeleton(view, joints2d)
    return view
