"""Keyframe poses -> an animation of every frame: joint rotations, slerp, smoothing.

The skeleton is data (VideoPose3D style): ``BONES`` and ``PARENTS`` describe a tree
rooted at the pelvis whose every bone has a fixed ``offset`` from its parent (in the
parent's frame, metres) and a rotation per frame relative to its parent. The rest
pose (all rotations identity) is the model standing, facing +z, left = +x. Besides
the 16 contract joints the tree holds two helper joints, so that one rotation per
bone can reproduce any pose of the contract body exactly:

* ``waist`` sits at the pelvis and turns the torso against the hips (the paper's
  waist joint, Table 1): the pelvis' own frame follows the hip line.
* ``collar`` sits at the shoulders' midpoint and tilts the shoulder line against
  the torso axis; ``chest`` twists the shoulders about that axis.

A frame bone (pelvis, waist, chest, collar) gets a full orientation from two body
directions; a limb bone (and the neck) gets the smallest rotation ("swing") that
turns its rest direction (down for limbs, up for the head) onto its bone. Slerp
between two swings about the same rest direction is again a swing, so interpolated
limbs never pick up a twist.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation, Slerp

from mocap.body import JOINT_INDEX, JOINTS
from mocap.errors import MocapError

# depth-first (a parent before its subtree), the order of a BVH HIERARCHY
BONES: tuple[str, ...] = (
    "pelvis", "hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r",
    "waist", "chest", "neck", "head_top", "collar",
    "shoulder_l", "elbow_l", "wrist_l", "shoulder_r", "elbow_r", "wrist_r",
)
_PARENT_NAMES = {
    "hip_l": "pelvis", "knee_l": "hip_l", "ankle_l": "knee_l",
    "hip_r": "pelvis", "knee_r": "hip_r", "ankle_r": "knee_r",
    "waist": "pelvis", "chest": "waist", "neck": "chest", "head_top": "neck",
    "collar": "chest", "shoulder_l": "collar", "elbow_l": "shoulder_l", "wrist_l": "elbow_l",
    "shoulder_r": "collar", "elbow_r": "shoulder_r", "wrist_r": "elbow_r",
}
PARENTS = np.array([BONES.index(_PARENT_NAMES[b]) if b in _PARENT_NAMES else -1 for b in BONES])
# where each contract joint is among the bones
JOINT_BONES = np.array([BONES.index(j) for j in JOINTS])

_UP, _DOWN = np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])
_AXES = np.eye(3)
_TORSO_AXIS, _HIP_LINE = ("pelvis", "neck"), ("hip_r", "hip_l")
_SHOULDER_LINE = ("shoulder_r", "shoulder_l")
# frame bones: (axis 0 = x / 1 = y that points exactly along a body direction,
#               that direction, the direction the other axis leans toward)
_FRAMES = {
    "pelvis": (0, _HIP_LINE, _TORSO_AXIS),
    "waist": (1, _TORSO_AXIS, _HIP_LINE),
    "chest": (1, _TORSO_AXIS, _SHOULDER_LINE),
    "collar": (0, _SHOULDER_LINE, _TORSO_AXIS),
}
# swing bones: the joint the bone points at, and its rest direction
_SWINGS = {"neck": ("head_top", _UP)} | {
    f"{a}_{s}": (f"{b}_{s}", _DOWN) for s in "lr"
    for a, b in (("shoulder", "elbow"), ("elbow", "wrist"), ("hip", "knee"), ("knee", "ankle"))}
# helper joints lie at the midpoint of two contract joints
_HELPERS = {"waist": ("pelvis", "pelvis"), "collar": ("shoulder_l", "shoulder_r")}


@dataclass(frozen=True, eq=False)
class Motion:
    """An animation of the contract body, every frame.

    ``joints3d`` (F, 16, 3) metres, contract frame, origin at the pelvis;
    ``root`` (F, 3) world position of the pelvis; ``keyframes`` (F,) which frames
    were given; ``rotations`` (F, len(BONES), 4) each bone's rotation relative to its
    parent as quaternions (x, y, z, w), sign-continuous in time; ``offsets``
    (len(BONES), 3) each bone's fixed offset from its parent in the parent's frame.
    """

    fps: float
    joints3d: np.ndarray
    keyframes: np.ndarray
    root: np.ndarray
    rotations: np.ndarray
    offsets: np.ndarray

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return len(self.joints3d)

    @property
    def times(self) -> np.ndarray:
        """(F,) seconds of every frame."""
        return np.arange(self.n_frames) / self.fps

    @property
    def world_joints(self) -> np.ndarray:
        """(F, 16, 3) joints in the world: joints3d moved by the root trajectory."""
        return self.joints3d + self.root[:, None, :]


def build_motion(joints3d_keyframes: dict[int, np.ndarray], n_frames: int, fps: float,
                 root: np.ndarray | None = None, smooth: float = 0.0) -> Motion:
    """A Motion of ``n_frames`` frames from the 3D joints (16, 3) of some keyframes.

    Bone offsets are the median over the keyframes (so bones keep one length);
    every frame's rotations are slerped between the nearest keyframes and held
    before the first and after the last. ``root`` (n_frames, 3) is the pelvis track,
    NaN rows filled linearly; without it the keyframes' own pelvis positions are
    interpolated. ``smooth`` > 0 is a Gaussian sigma in frames applied to rotations
    and root, corrected so that keyframes stay exactly as given.
    """
    keys, joints = _check_keyframes(joints3d_keyframes, n_frames, fps, smooth)
    pelvis = joints[:, JOINT_INDEX["pelvis"]]
    local, offsets = keyframe_rotations(joints - pelvis[:, None])
    rotations = _continuous(_slerp_frames(keys, local, n_frames))
    track = _root_track(keys, pelvis, root, n_frames)
    if smooth > 0:
        rotations = _smooth_pinned(rotations, keys, smooth)
        rotations = _continuous(rotations / np.linalg.norm(rotations, axis=-1, keepdims=True))
        track = _smooth_pinned(track, keys, smooth)
    positions = forward_kinematics(offsets, rotations)
    is_key = np.zeros(n_frames, dtype=bool)
    is_key[keys] = True
    return Motion(fps=float(fps), joints3d=positions[:, JOINT_BONES], keyframes=is_key,
                  root=track, rotations=rotations, offsets=offsets)


def _check_keyframes(joints3d_keyframes, n_frames, fps, smooth) -> tuple[np.ndarray, np.ndarray]:
    """Sorted keyframe indices (K,) and their joints (K, 16, 3); bad input -> MocapError."""
    if not n_frames >= 1 or not fps > 0 or not smooth >= 0:
        raise MocapError(f"motion needs n_frames >= 1, fps > 0 and smooth >= 0 "
                         f"(got {n_frames}, {fps}, {smooth})")
    keys = np.array(sorted(joints3d_keyframes), dtype=int)
    if not len(keys) or keys[0] < 0 or keys[-1] >= n_frames:
        raise MocapError(f"keyframes must be a non-empty set of frames in 0..{n_frames - 1}")
    joints = np.array([np.asarray(joints3d_keyframes[k], dtype=float) for k in keys])
    if joints.shape[1:] != (len(JOINTS), 3) or not np.isfinite(joints).all():
        raise MocapError(f"keyframe joints must be finite arrays of shape ({len(JOINTS)}, 3)")
    return keys, joints


def keyframe_rotations(joints: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Local bone rotations (K, len(BONES), 4) and median offsets (len(BONES), 3)
    that pose the skeleton as the pelvis-relative joints (K, 16, 3)."""
    at = {**{j: joints[:, i] for i, j in enumerate(JOINTS)},
          **{h: (joints[:, JOINT_INDEX[a]] + joints[:, JOINT_INDEX[b]]) / 2
             for h, (a, b) in _HELPERS.items()}}
    glob: list[Rotation] = []
    local = np.empty((len(joints), len(BONES), 4))
    offsets = np.zeros((len(BONES), 3))
    for b, name in enumerate(BONES):
        parent = glob[PARENTS[b]] if PARENTS[b] >= 0 else Rotation.identity(len(joints))
        if name in _FRAMES:
            axis, exact, lean = _FRAMES[name]
            rot = parent.inv() * Rotation.from_matrix(
                _frame(at[exact[1]] - at[exact[0]], at[lean[1]] - at[lean[0]], axis))
        elif name in _SWINGS:
            target, rest = _SWINGS[name]
            rot = _swing(rest, parent.inv().apply(at[target] - at[name]))
        else:
            rot = Rotation.identity(len(joints))
        if PARENTS[b] >= 0:
            offsets[b] = _median_offset(parent.inv().apply(at[name] - at[BONES[PARENTS[b]]]))
        glob.append(parent * rot)
        local[:, b] = rot.as_quat()
    return local, offsets


def _median_offset(vectors: np.ndarray) -> np.ndarray:
    """The median (K, 3) -> (3,) of a bone's offsets, ignoring keyframes where the
    bone collapsed to zero length (a joint placed on its parent)."""
    real = np.linalg.norm(vectors, axis=-1) > 1e-9
    return np.median(vectors[real] if real.any() else vectors, axis=0)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Normalise along the last axis; (near) zero vectors become ``fallback``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), fallback)


def _frame(exact: np.ndarray, lean: np.ndarray, axis: int) -> np.ndarray:
    """(K, 3, 3) rotation matrices whose column ``axis`` (0 = x, 1 = y) points along
    ``exact`` and whose other x/y column lies in the plane of ``exact`` and ``lean``.
    Degenerate directions fall back to the rest pose's axes."""
    other = 1 - axis
    a = _unit(exact, _AXES[axis])
    rest_other = _unit(_AXES[other] - (a @ _AXES[other])[:, None] * a, _AXES[2])
    b = _unit(lean - (a * lean).sum(-1, keepdims=True) * a, rest_other)
    cols = [a, b] if axis == 0 else [b, a]
    return np.stack([*cols, np.cross(cols[0], cols[1])], axis=-1)


def _swing(rest: np.ndarray, direction: np.ndarray) -> Rotation:
    """The smallest rotations taking the unit ``rest`` onto ``direction`` (K, 3); a
    zero direction gives the identity, an opposite one a half turn about a normal."""
    d = _unit(direction, rest)
    cross = np.cross(rest, d)
    sin, cos = np.linalg.norm(cross, axis=-1), d @ rest
    perpendicular = _unit(np.cross(rest, _AXES[np.argmin(np.abs(rest))]), _AXES[0])
    axis = np.where((sin > 1e-12)[:, None], cross / np.maximum(sin, 1e-12)[:, None], perpendicular)
    return Rotation.from_rotvec(axis * np.arctan2(sin, cos)[:, None])


def _slerp_frames(keys: np.ndarray, local: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames, B, 4) quaternions slerped between keyframes, held outside them."""
    if len(keys) == 1:
        return np.repeat(local, n_frames, axis=0)
    times = np.clip(np.arange(n_frames), keys[0], keys[-1])
    return np.stack([Slerp(keys, Rotation.from_quat(local[:, b]))(times).as_quat()
                     for b in range(local.shape[1])], axis=1)


def _continuous(quats: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so that consecutive frames lie in one hemisphere
    (needed for smoothing them as vectors and for linear glTF playback)."""
    flips = np.sign(np.sum(quats[1:] * quats[:-1], axis=-1))
    flips[flips == 0] = 1
    sign = np.concatenate([np.ones((1, quats.shape[1])), np.cumprod(flips, axis=0)])
    return quats * sign[..., None]


def _lerp_frames(keys: np.ndarray, values: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames, ...) values given at sorted frames ``keys``, linearly
    interpolated between them and held outside."""
    if len(keys) == 1:
        return np.repeat(values, n_frames, axis=0)
    t = np.arange(n_frames)
    i = np.clip(np.searchsorted(keys, t, side="right") - 1, 0, len(keys) - 2)
    w = np.clip((t - keys[i]) / (keys[i + 1] - keys[i]), 0.0, 1.0)
    w = w.reshape(-1, *[1] * (values.ndim - 1))
    return values[i] * (1 - w) + values[i + 1] * w


def _root_track(keys: np.ndarray, pelvis: np.ndarray, root: np.ndarray | None,
                n_frames: int) -> np.ndarray:
    """(n_frames, 3) pelvis trajectory: ``root`` with NaN rows filled, or the keyframe
    pelvis positions interpolated."""
    if root is None:
        return _lerp_frames(keys, pelvis, n_frames)
    root = np.asarray(root, dtype=float)
    known = np.flatnonzero(np.isfinite(root).all(axis=-1)) if root.shape == (n_frames, 3) else []
    if not len(known):
        raise MocapError(f"root must be an array of shape ({n_frames}, 3) with a finite row")
    return _lerp_frames(known, root[known], n_frames)


def _smooth_pinned(track: np.ndarray, keys: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along time (axis 0) plus the difference at the keyframes
    interpolated by a natural cubic spline (held outside), so that keyframes keep
    their exact values and no corner comes back at them."""
    smooth = gaussian_filter1d(track, sigma, axis=0, mode="nearest")
    residual = track[keys] - smooth[keys]
    if len(keys) == 1:
        return smooth + residual
    times = np.clip(np.arange(len(track)), keys[0], keys[-1])
    return smooth + CubicSpline(keys, residual, axis=0, bc_type="natural")(times)


def forward_kinematics(offsets: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """(F, len(BONES), 3) bone positions relative to the pelvis from the offsets
    (len(BONES), 3) and local rotations (F, len(BONES), 4)."""
    n = len(rotations)
    glob: list[Rotation] = []
    pos = np.zeros((n, len(BONES), 3))
    for b in range(len(BONES)):
        local = Rotation.from_quat(rotations[:, b])
        p = PARENTS[b]
        if p < 0:
            glob.append(local)
        else:
            pos[:, b] = pos[:, p] + glob[p].apply(offsets[b])
            glob.append(glob[p] * local)
    return pos
