"""Drawing fitted bodies, silhouettes and a person model's additions over images (OpenCV), for
the app's views and contact sheets."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.body import JOINT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES, SEGMENTS
from mocap.person import SURE

# BGR per segment kind: torso/head white, the performer's left limbs orange, right ones blue
_COLOURS = {"torso": (240, 240, 240), "head": (240, 240, 240)}
_LEFT, _RIGHT = (40, 160, 255), (255, 140, 40)
SILHOUETTE_GREY = 110
LEARNED_BGR = (150, 140, 30)  # teal: silhouette pixels only the person model's mask gave
LANDMARK_BGR = (230, 70, 230)  # magenta: the person model's joints
# the segments' bones, and the shoulders and hips joined to the neck and the pelvis
LANDMARK_BONES = tuple(
    (JOINT_INDEX[a], JOINT_INDEX[b])
    for a, b in (
        *SEGMENTS.values(),
        ("neck", "shoulder_l"),
        ("neck", "shoulder_r"),
        ("pelvis", "hip_l"),
        ("pelvis", "hip_r"),
    )
)


def segment_colour(segment: str) -> tuple[int, int, int]:
    if segment in _COLOURS:
        return _COLOURS[segment]
    return _LEFT if segment.endswith("_l") else _RIGHT


def draw_skeleton(
    image: np.ndarray, joints2d: np.ndarray, thickness: int = 2, colour: tuple[int, int, int] | None = None
) -> np.ndarray:
    """Draw the 10 segments and 16 joints onto image (in place) and return it."""
    pts = np.round(np.asarray(joints2d) * 16).astype(np.int32)
    for name, (a, b) in zip(SEGMENT_NAMES, SEGMENT_JOINTS):
        cv2.line(image, tuple(pts[a]), tuple(pts[b]), colour or segment_colour(name), thickness, cv2.LINE_AA, shift=4)
    for p in pts:
        cv2.circle(image, tuple(p), (thickness + 1) * 16, colour or (0, 0, 255), -1, cv2.LINE_AA, shift=4)
    return image


def silhouette_view(mask: np.ndarray, joints2d: np.ndarray | None, learned: np.ndarray | None = None) -> np.ndarray:
    """The silhouette in grey with the fitted model drawn over it; the pixels of
    ``learned`` (nonzero: those only the person model's mask gave) tinted LEARNED_BGR."""
    view = cv2.cvtColor((mask > 0).astype(np.uint8) * SILHOUETTE_GREY, cv2.COLOR_GRAY2BGR)
    if learned is not None:
        view[(learned > 0) & (mask > 0)] = LEARNED_BGR
    if joints2d is not None:
        draw_skeleton(view, joints2d)
    return view


def draw_landmarks(image: np.ndarray, joints2d: np.ndarray, confidence: np.ndarray, radius: float = 3.0) -> np.ndarray:
    """Draw (in place) a person model's 16 joints (pixels) as LANDMARK_BGR dots, filled where
    confidence >= SURE, else rings, with LANDMARK_BONES between sure joints; return the image."""
    pts = np.round(np.asarray(joints2d, float) * 16).astype(np.int32)
    sure = np.asarray(confidence) >= SURE
    for a, b in LANDMARK_BONES:
        if sure[a] and sure[b]:
            cv2.line(image, tuple(pts[a]), tuple(pts[b]), LANDMARK_BGR, 1, cv2.LINE_AA, shift=4)
    r = int(round(radius * 16))
    for p, filled in zip(pts, sure):
        cv2.circle(image, tuple(p), r, LANDMARK_BGR, -1 if filled else 1, cv2.LINE_AA, shift=4)
    return image
