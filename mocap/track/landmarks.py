"""The person model (mocap.person) as the tracker's second pair of eyes, beyond the paper: its landmarks propose the
marks, seed a lost body anew and tell where a limb went (tracker.BodyTracker.step); the block matching stays where
colours hold, being the more precise."""

from __future__ import annotations

import numpy as np

from mocap.body import JOINT_INDEX
from mocap.camera import FLIP_YZ
from mocap.errors import MocapError
from mocap.person import SURE, Landmarks, PersonView
from mocap.silhouette.eyes import PERSON_LEVEL, crowned
from mocap.track.calibration import KEY
from mocap.track.keydepths import side_of, triangle_yaw
from mocap.track.marks import check_key_triangle

# the joints the head and trunk blocks and the key triangle rest on: a seed needs them seen
SEED_JOINTS = tuple(
    JOINT_INDEX[j] for j in ("head_top", "neck", "chest", "pelvis", "shoulder_l", "shoulder_r", "hip_l", "hip_r")
)


def seed_marks(seen: Landmarks | None, shape: tuple) -> np.ndarray | None:
    """Marks (16, 2) from landmarks on a frame of ``shape`` where the model is sure (SURE) of SEED_JOINTS and every
    joint lies inside the frame with a sound key triangle; the limb joints it is less sure of at its own guess (it
    places hidden joints too). None otherwise."""
    if seen is None or (seen.confidence[list(SEED_JOINTS)] < SURE).any():
        return None
    marks = seen.joints2d
    if not np.isfinite(marks).all() or (marks < 0).any() or (marks >= np.array(shape[1::-1]) - 1).any():
        return None
    try:
        check_key_triangle(marks)
    except MocapError:
        return None
    return marks.copy()


def proposed(view: PersonView | None) -> Landmarks | None:
    """The landmarks of ``view`` as the marks a person model proposes take them (seed_marks, where no seed holds
    the body yet): the head's top on its own mask's crown (silhouette.eyes.crowned), as the app's proposal from the
    silhouette fit has it. The model's head top is the ears' line extended, and a block from it to the neck takes
    in background above the hair."""
    if view is None:
        return None
    return crowned(view.landmarks, np.where(view.mask >= PERSON_LEVEL, 255, 0).astype(np.uint8))


def facing_yaw(seen: Landmarks | None) -> float:
    """The facing yaw in degrees (as Calibration.yaw) of the model's 3D key triangle, NaN where unsure of it."""
    if seen is None or (seen.confidence[list(KEY)] < SURE).any():
        return float("nan")
    return float(triangle_yaw(seen.world[list(KEY)] * FLIP_YZ))


def released(turns: list[str | None], starts: list[int], facing: np.ndarray) -> list[str | None]:
    """Each frame's side (keydepths.Turns) with every hold (from each frame of ``starts`` to the next) released
    from the first frame whose ``facing`` (F,) yaw clearly faces the other side: the body turned."""
    out = list(turns)
    for start, stop in zip(starts, [*starts[1:], len(out)]):
        held = out[start] if start < len(out) else None
        against = [f for f in range(start, min(stop, len(out))) if side_of(facing[f]) not in (None, held)]
        if held is not None and against:
            out[against[0] : stop] = [None] * (min(stop, len(out)) - against[0])
    return out
