"""Facing marks: a nose on the head and a stub on the chest's front, so that the way the
body faces shows in 3D, where the cylinders alone look alike turned half round. The app's
3D bodies, the GLB/FBX character and the playback page draw them."""

from __future__ import annotations

import numpy as np

from mocap.body import BODY_HEIGHT, BODY_HEIGHT_M, SEGMENT_INDEX, SEGMENT_JOINTS, left_direction, semi_axes, unit

# name -> (segment, where along it from its proximal joint, length and radius in model
# units of a 175-unit body); each stands out of its segment's front
FACING_MARKS: dict[str, tuple[str, float, float, float]] = {
    "nose": ("head", 0.4, 6.0, 2.5),
    "chest": ("torso", 0.75, 4.0, 6.0),
}


def facing_marks(joints3d: np.ndarray, body_height: float = BODY_HEIGHT_M) -> np.ndarray:
    """(2, 3, 3) per FACING_MARKS entry of a pose (16, 3; y up, its left from the limbs'
    roots): its base on its segment's front (body.semi_axes' front-to-back radius), its
    unit direction out (forward: the body's left crossed with the segment's axis) and
    (length, radius, 0) in the pose's units."""
    j, out = np.asarray(joints3d, float), np.zeros((len(FACING_MARKS), 3, 3))
    for k, (segment, along, length, radius) in enumerate(FACING_MARKS.values()):
        i = SEGMENT_INDEX[segment]
        a, b = j[SEGMENT_JOINTS[i]]
        out[k, 1] = unit(np.cross(left_direction(j), b - a))
        out[k, 0] = a + along * (b - a) + out[k, 1] * semi_axes(body_height)[i, 1]
        out[k, 2, :2] = np.array([length, radius]) * body_height / BODY_HEIGHT
    return out
