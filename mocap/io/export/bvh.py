"""BVH export of a Motion: the skeleton of ``mocap.lift.motion`` as a BVH hierarchy.

Joints are named after the contract joints, plus the helper joints ``waist`` and
``collar`` (see ``mocap.lift.motion``). Lengths are in centimetres: OFFSETs are the
motion's fixed bone offsets, the root (pelvis) has 6 channels (its world position,
then its rotation) and every other joint 3 rotation channels, all in the order
Z, X, Y (intrinsic, degrees, as in the CMU files). Leaves end in a zero End Site.
"""

from __future__ import annotations

import io
import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.lift.motion import BONES, PARENTS, Motion

CM_PER_M = 100.0
_ORDER = "ZXY"
_ROTATION_CHANNELS = " ".join(f"{axis}rotation" for axis in _ORDER)


def bvh_text(motion: Motion) -> str:
    """The whole BVH file (centimetres, one frame per motion frame): HIERARCHY then MOTION."""
    lines = ["HIERARCHY"] + _joint_lines(0, motion.offsets * CM_PER_M, 0)
    lines += ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {1.0 / motion.fps:.8f}"]
    out = io.StringIO()
    np.savetxt(out, _channel_values(motion), fmt="%.6f")
    return "\n".join(lines) + "\n" + out.getvalue()


def _joint_lines(bone: int, offsets_cm: np.ndarray, depth: int) -> list[str]:
    """The HIERARCHY lines of one joint and, recursively, its children."""
    pad = "  " * depth
    head = "ROOT" if PARENTS[bone] < 0 else "JOINT"
    channels = (f"6 Xposition Yposition Zposition {_ROTATION_CHANNELS}" if PARENTS[bone] < 0
                else f"3 {_ROTATION_CHANNELS}")
    lines = [f"{pad}{head} {BONES[bone]}", f"{pad}{{",
             f"{pad}  OFFSET {' '.join(f'{v:.6f}' for v in offsets_cm[bone] + 0.0)}",
             f"{pad}  CHANNELS {channels}"]
    children = np.flatnonzero(PARENTS == bone)
    for child in children:
        lines += _joint_lines(child, offsets_cm, depth + 1)
    if not len(children):
        lines += [f"{pad}  End Site", f"{pad}  {{", f"{pad}    OFFSET 0 0 0", f"{pad}  }}"]
    return lines + [f"{pad}}}"]


def _channel_values(motion: Motion) -> np.ndarray:
    """(F, 6 + 3 * (len(BONES) - 1)) channel values in hierarchy (depth-first) order."""
    rot = Rotation.from_quat(motion.rotations.reshape(-1, 4))
    with warnings.catch_warnings():
        # at gimbal lock scipy still returns angles that give the same rotation
        warnings.filterwarnings("ignore", message="Gimbal lock")
        euler = rot.as_euler(_ORDER, degrees=True).reshape(motion.n_frames, len(BONES), 3)
    # BONES are listed depth-first, the order of the HIERARCHY and of its channels
    return np.concatenate([motion.root * CM_PER_M, euler.reshape(motion.n_frames, -1)], axis=1)
