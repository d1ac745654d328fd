"""BVH export of a Motion: the skeleton of ``mocap.lift.skeleton`` (bone names most tools map by
themselves; End Sites at head top, finger and toe tips), OFFSETs in centimetres from its T-pose rest.
The root (Hips) has 6 channels (position in the exports' world, floor at y = 0, then rotation), every
other joint 3; rotations in Z, X, Y order (intrinsic, degrees, as in the CMU files)."""

from __future__ import annotations

import io
import warnings

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.lift.motion import Motion
from mocap.lift.skeleton import BONES, END_SITE, PARENTS

CM_PER_M = 100.0
_ORDER = "ZXY"
_ROTATION_CHANNELS = " ".join(f"{axis}rotation" for axis in _ORDER)
_JOINTS = np.flatnonzero(~END_SITE)  # the bones with channels, depth-first


def bvh_text(motion: Motion) -> str:
    """The whole BVH file (centimetres, one frame per motion frame): HIERARCHY then MOTION."""
    lines = ["HIERARCHY"] + _joint_lines(0, motion.offsets * CM_PER_M, 0)
    lines += ["MOTION", f"Frames: {motion.n_frames}", f"Frame Time: {1.0 / motion.fps:.8f}"]
    out = io.StringIO()
    np.savetxt(out, _channel_values(motion), fmt="%.6f")
    return "\n".join(lines) + "\n" + out.getvalue()


def _offset(offset_cm: np.ndarray) -> str:
    return "OFFSET " + " ".join(f"{v:.6f}" for v in offset_cm + 0.0)  # no "-0.000000"


def _joint_lines(bone: int, offsets_cm: np.ndarray, depth: int) -> list[str]:
    """The HIERARCHY lines of one joint and, recursively, its children."""
    pad = "  " * depth
    if END_SITE[bone]:
        return [f"{pad}End Site", f"{pad}{{", f"{pad}  {_offset(offsets_cm[bone])}", f"{pad}}}"]
    head = "ROOT" if PARENTS[bone] < 0 else "JOINT"
    channels = (
        f"6 Xposition Yposition Zposition {_ROTATION_CHANNELS}" if PARENTS[bone] < 0 else f"3 {_ROTATION_CHANNELS}"
    )
    lines = [
        f"{pad}{head} {BONES[bone]}",
        f"{pad}{{",
        f"{pad}  {_offset(offsets_cm[bone])}",
        f"{pad}  CHANNELS {channels}",
    ]
    for child in np.flatnonzero(PARENTS == bone):
        lines += _joint_lines(child, offsets_cm, depth + 1)
    return lines + [f"{pad}}}"]


def _channel_values(motion: Motion) -> np.ndarray:
    """(F, 6 + 3 * (joints - 1)) channel values in hierarchy (depth-first) order."""
    rot = Rotation.from_quat(motion.rotations[:, _JOINTS].reshape(-1, 4))
    with warnings.catch_warnings():
        # at gimbal lock scipy still returns angles that give the same rotation
        warnings.filterwarnings("ignore", message="Gimbal lock")
        euler = rot.as_euler(_ORDER, degrees=True).reshape(motion.n_frames, -1)
    # BONES are listed depth-first, the order of the HIERARCHY and of its channels
    return np.concatenate([motion.world_root * CM_PER_M, euler], axis=1)
