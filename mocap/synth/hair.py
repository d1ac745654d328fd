"""Hair for `mocap synth --hair` on the back of the head and crown: mostly face from the front,
mostly hair from behind, as mocap.silhouette.facing expects."""

from __future__ import annotations

import cv2
import numpy as np

from mocap.body import SEGMENT_INDEX, SEGMENT_JOINTS, left_direction, unit

HAIRLINE = 0.35  # of the head's length above the neck: hair above it at the back
FRINGE = 0.8  # above it, hair all round (the forehead's hairline)
HAIR_BGR = (38, 48, 66)  # dark brown
_BACK_ARC = 0.25  # hair where the head's surface faces less than this far forward


def hair_patches(joints: np.ndarray, radius: float, samples: int = 24) -> list[np.ndarray]:
    """Points (N, 3) per hair patch of a pose (16, 3; camera frame, z to the camera), head radius
    ``radius``: back above HAIRLINE, crown above FRINGE, camera side only (each projects convex)."""
    a, b = joints[SEGMENT_JOINTS[SEGMENT_INDEX["head"]]]
    axis = unit(b - a)
    left = unit(left_direction(joints) - (left_direction(joints) @ axis) * axis)
    angle = 2 * np.pi * np.arange(samples) / samples
    normal = np.cos(angle)[:, None] * left + np.sin(angle)[:, None] * np.cross(left, axis)
    seen = normal[:, 2] > -0.1
    patches = []
    for start, arc in ((HAIRLINE, seen & (np.sin(angle) < _BACK_ARC)), (FRINGE, seen)):
        for run in _circular_runs(arc):
            ring = normal[run] * radius
            patches.append(np.concatenate([a + start * (b - a) + ring, b + ring]))
    return patches


def _circular_runs(mask: np.ndarray) -> list[np.ndarray]:
    """Index arrays of the stretches of True (two or more) around a circular mask."""
    if mask.all():
        return [np.arange(len(mask))]
    shift = int(np.argmin(mask))  # start on a False: no run wraps
    edges = np.flatnonzero(np.diff(np.r_[0, np.roll(mask, -shift).astype(int), 0]))
    return [(np.arange(a, b) + shift) % len(mask) for a, b in zip(edges[::2], edges[1::2]) if b - a >= 2]


def draw_hair(img: np.ndarray, joints: np.ndarray, radius: float, project, outline: np.ndarray, line: int) -> None:
    """Paint ``hair_patches`` onto a drawn head; ``project``: camera frame -> pixels; ``outline``:
    the head's hull in sixteenths of a pixel, which clips the patches."""
    outline = outline.reshape(-1, 2).astype(np.float32)
    for points in hair_patches(joints, radius):
        patch = cv2.convexHull(np.round(project(points) * 16).astype(np.float32))
        area, shape = cv2.intersectConvexConvex(patch, outline)
        if area > 0:
            cv2.fillConvexPoly(img, np.round(shape).astype(np.int32), HAIR_BGR, line, 4)
