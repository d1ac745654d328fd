"""The oracle: what a user who knew the true 3D would annotate, so that benchmarks and
tests can measure the lift apart from the guesses it makes without input."""

from __future__ import annotations

import numpy as np

from mocap.body import FORESHORTENING, JOINTS, LIMB_JOINTS, SEGMENT_NAMES
from mocap.io.annotations import Annotations
from mocap.lift.taylor import orientation_of_yaw, signs_of, yaw_of


def annotations_for_poses(joints3d: np.ndarray, joints2d: np.ndarray | None = None) -> Annotations:
    """What a user who knew the 3D poses (F, 16, 3; contract frame) would say, for benchmarks and tests:
    each orientation change, every segment's sign on every frame and, with 2D joints (F, 16, 2), the left
    wrist and ankle once per profile (its widest-apart frame within 30), as a profile hides the sides."""
    joints3d = np.asarray(joints3d, float)
    names = [orientation_of_yaw(yaw_of(pose)) for pose in joints3d]
    notes = Annotations()
    for i, (pose, name) in enumerate(zip(joints3d, names)):
        if i == 0 or name != names[i - 1]:
            notes = notes.with_orientation(i, name)
            if joints2d is not None and name in ("left", "right"):
                notes = _side_anchors(notes, joints2d, i, names)
        for segment, sign in zip(SEGMENT_NAMES, signs_of(pose)):
            notes = notes.with_foreshortening(i, segment, FORESHORTENING[0] if sign > 0 else FORESHORTENING[1])
    return notes


def _side_anchors(notes: Annotations, joints2d: np.ndarray, start: int, names: list[str]) -> Annotations:
    stop = start
    while stop < min(len(names), start + 30) and names[stop] == names[start]:
        stop += 1
    for kind in LIMB_JOINTS.values():  # each limb's end, left
        joint = f"{kind[-1]}_l"
        j, k = JOINTS.index(joint), JOINTS.index(joint[:-1] + "r")
        gap = np.linalg.norm(joints2d[start:stop, j] - joints2d[start:stop, k], axis=-1)
        i = start + int(np.argmax(gap))
        notes = notes.with_joint(i, joint, tuple(float(v) for v in joints2d[i, j]))
    return notes
