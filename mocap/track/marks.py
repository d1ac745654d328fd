"""The user's marks: the 16 joints placed by hand on frame 0, the tracking method's only input (Pan, Zhuang and Liu
2000), checked once here so that the tracker and the calibration can trust them."""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, JOINTS, LENGTH, SEGMENT_NAMES, SIDES, limb
from mocap.errors import MocapError

KEY_TRIANGLE = ("shoulder_l", "shoulder_r", "chest")
MIN_KEY_SIDE = 0.04  # of the body height: shorter key-triangle sides "coincide"
MIN_KEY_ANGLE_DEG = 8.0  # a key-triangle corner nearer 0 or 180 degrees is "collinear"
_LENGTH = dict(zip(SEGMENT_NAMES, LENGTH))


def check_marks(marks, width: int, height: int) -> np.ndarray:
    """The marks as (16, 2) in JOINTS order, from a (16, 2) array (NaN: unmarked) or joint -> (x, y); a MocapError
    names a missing joint, one outside the ``width`` x ``height`` frame, or a degenerate key triangle."""
    if isinstance(marks, Mapping):
        unknown = sorted(set(marks) - set(JOINTS))
        if unknown:
            raise MocapError(f"unknown joint {unknown[0]!r} in the marks")
        marks = np.array([marks.get(j, (np.nan, np.nan)) for j in JOINTS], dtype=float)
    marks = np.asarray(marks, dtype=float)
    if marks.shape != (len(JOINTS), 2):
        raise MocapError(f"expected 16 marked joints (x, y), got an array of shape {marks.shape}")
    for name, (x, y) in zip(JOINTS, marks):
        if not (np.isfinite(x) and np.isfinite(y)):
            raise MocapError(f"joint {name} is not marked on frame 0 (all 16 joints are needed)")
        if not (0 <= x < width and 0 <= y < height):
            raise MocapError(f"joint {name} at ({x:.1f}, {y:.1f}) is outside the {width}x{height} frame")
    check_key_triangle(marks)
    return marks


def check_key_triangle(marks: np.ndarray) -> None:
    """Refuse a key triangle with two corners nearly on one point (a profile view) or nearly collinear."""
    pts = marks[[JOINT_INDEX[j] for j in KEY_TRIANGLE]]
    least = MIN_KEY_SIDE * BODY_HEIGHT * body_scale(marks)
    for i, j in ((0, 1), (0, 2), (1, 2)):
        if np.hypot(*(pts[i] - pts[j])) < least:
            raise MocapError(
                f"degenerate key triangle: {KEY_TRIANGLE[i]} and {KEY_TRIANGLE[j]} "
                f"nearly coincide (a profile view?); the shoulders and the chest "
                f"must span a triangle"
            )
    for k in range(3):
        a, b = pts[(k + 1) % 3] - pts[k], pts[(k + 2) % 3] - pts[k]
        cos = a @ b / (np.hypot(*a) * np.hypot(*b))
        if np.degrees(np.arccos(np.clip(cos, -1.0, 1.0))) > 180.0 - MIN_KEY_ANGLE_DEG:
            raise MocapError(
                f"degenerate key triangle: {KEY_TRIANGLE[k]} is nearly on the line through the other two key joints"
            )


def across_trunk(marks: np.ndarray, side: str) -> float:
    """Pixels the left joint of pair ``side`` ("shoulder", "hip") lies from the right, square to the marked trunk:
    positive on the image right of an upright body (one sign for both pairs of a rigid trunk)."""
    axis = marks[JOINT_INDEX["pelvis"]] - marks[JOINT_INDEX["neck"]]
    across = np.array([axis[1], -axis[0]]) / max(np.hypot(*axis), 1e-9)
    return float((marks[JOINT_INDEX[f"{side}_l"]] - marks[JOINT_INDEX[f"{side}_r"]]) @ across)


def turned_apart(marks: np.ndarray) -> bool:
    """Whether shoulders and hips are marked turned opposite ways (``across_trunk`` signs differ), as no trunk is."""
    return across_trunk(marks, "shoulder") * across_trunk(marks, "hip") < 0


def shoulders_as_hips(marks: np.ndarray) -> np.ndarray:
    """The marks with the shoulders exchanged where ``turned_apart`` from the hips: the silhouette method's fit seen
    from the side orders its shoulders arbitrarily while its hips follow the legs."""
    if not turned_apart(marks):
        return marks
    out = marks.copy()
    pair = [JOINT_INDEX["shoulder_l"], JOINT_INDEX["shoulder_r"]]
    out[pair] = marks[pair[::-1]]
    return out


def body_scale(marks: np.ndarray) -> float:
    """Pixels per model unit of marks: the least foreshortened of head-and-trunk and the two legs."""

    def seen(*names: str) -> float:
        return sum(np.hypot(*(marks[JOINT_INDEX[a]] - marks[JOINT_INDEX[b]])) for a, b in zip(names, names[1:]))

    trunk = seen("head_top", "neck", "pelvis") / (_LENGTH["head"] + _LENGTH["torso"])
    leg = _LENGTH["upper_leg_l"] + _LENGTH["lower_leg_l"]
    legs = [seen(*limb("leg", side).joints) / leg for side in SIDES]
    return max(trunk, *legs, 1e-6)
