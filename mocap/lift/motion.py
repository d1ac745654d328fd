"""Keyframe poses -> an animation of every frame: joint rotations, slerp, smoothing. Bones
(``mocap.lift.skeleton``) have fixed offsets and per-frame local rotations; limb bones and the neck
take the smallest swing from rest, so slerped limbs never twist. The root is the pelvis in the
camera's frame; the exports' world puts the floor at y = 0 below frame 0's pelvis."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation, Slerp

from mocap.body import JOINT_INDEX, JOINTS
from mocap.errors import MocapError
from mocap.lift.contacts import foot_contacts, foot_lock
from mocap.lift.skeleton import ANKLE_HEIGHT, JOINT_BONES, UNIT_M, clip_offsets, forward_kinematics, pose_rotations

# the floor: this low percentile of the lower ankle's height over the clip, less the
# ankle's height above the sole (a percentile, not the minimum: a fit's stray frame)
FLOOR_PERCENTILE = 5.0


@dataclass(frozen=True, eq=False)
class Motion:
    """An animation of the contract body (F frames, B = len(BONES)): ``joints3d`` (F, 16, 3) metres,
    pelvis origin; ``root`` (F, 3) the pelvis (camera frame where known); ``keyframes`` (F,) bool;
    ``rotations`` (F, B, 4) local quaternions x y z w, sign-continuous; ``offsets`` (B, 3) in the
    parent's frame; ``origin`` (3,) the exports' world origin (floor, below frame 0's pelvis);
    ``planted`` (F, 2) the contacts a foot lock held (None: found from the joints)."""

    fps: float
    joints3d: np.ndarray
    keyframes: np.ndarray
    root: np.ndarray
    rotations: np.ndarray
    offsets: np.ndarray
    origin: np.ndarray = field(default_factory=lambda: np.zeros(3))
    planted: np.ndarray | None = None

    @property
    def n_frames(self) -> int:
        """Number of frames F."""
        return len(self.joints3d)

    @property
    def times(self) -> np.ndarray:
        """(F,) seconds of every frame."""
        return np.arange(self.n_frames) / self.fps

    @property
    def rooted_joints(self) -> np.ndarray:
        """(F, 16, 3) joints in the root's frame: joints3d moved by the root."""
        return self.joints3d + self.root[:, None, :]

    @property
    def world_root(self) -> np.ndarray:
        """(F, 3) the pelvis in the exports' world: the root less the origin."""
        return self.root - self.origin

    @property
    def world_joints(self) -> np.ndarray:
        """(F, 16, 3) joints in the exports' world: joints3d moved by the world root."""
        return self.joints3d + self.world_root[:, None, :]

    @property
    def contacts(self) -> np.ndarray:
        """(F, 2) bool: the left and right foot planted (``mocap.lift.contacts``; a locked motion's:
        those it was locked on)."""
        return foot_contacts(self.world_joints, self.fps) if self.planted is None else self.planted

    def foot_locked(self) -> "Motion":
        """This motion with every planted foot kept in place through its contact (the body moved
        where a leg cannot reach its pin); its contacts are those."""
        contacts = self.contacts
        world, shift = foot_lock(self.world_joints, contacts, self.fps)
        root = self.root + shift
        locked = self.with_joints(world - (root - self.origin)[:, None, :])
        return replace(locked, root=root, planted=contacts)

    def with_joints(self, joints3d: np.ndarray) -> "Motion":
        """This motion posed as pelvis-relative joints (F, 16, 3) (same body, root, origin, keyframes)."""
        rotations, _ = pose_rotations(joints3d, self.offsets)
        rotations = _continuous(rotations)
        positions = forward_kinematics(self.offsets, rotations)
        return Motion(
            self.fps, positions[:, JOINT_BONES], self.keyframes, self.root, rotations, self.offsets, self.origin
        )


def build_motion(
    joints3d_keyframes: dict[int, np.ndarray],
    n_frames: int,
    fps: float,
    root: np.ndarray | None = None,
    smooth: float = 0.0,
) -> Motion:
    """A Motion of ``n_frames`` from keyframes' joints {frame: (16, 3)}: symmetric median offsets,
    rotations slerped between keyframes (held outside); ``root`` (n_frames, 3) pelvis track, NaN rows
    filled (None: keyframe pelvises); ``smooth`` > 0 a Gaussian sigma (frames), keyframes kept exact."""
    keys, joints = _check_keyframes(joints3d_keyframes, n_frames, fps, smooth)
    pelvis = joints[:, JOINT_INDEX["pelvis"]]
    offsets = clip_offsets(pose_rotations(joints - pelvis[:, None])[1])
    local, _ = pose_rotations(joints - pelvis[:, None], offsets)
    rotations = _continuous(_slerp_frames(keys, local, n_frames))
    track = _root_track(keys, pelvis, root, n_frames)
    if smooth > 0:
        rotations = _smooth_pinned(rotations, keys, smooth)
        rotations = _continuous(rotations / np.linalg.norm(rotations, axis=-1, keepdims=True))
        track = _smooth_pinned(track, keys, smooth)
    positions = forward_kinematics(offsets, rotations)
    is_key = np.zeros(n_frames, dtype=bool)
    is_key[keys] = True
    joints3d = positions[:, JOINT_BONES]
    return Motion(
        fps=float(fps),
        joints3d=joints3d,
        keyframes=is_key,
        root=track,
        rotations=rotations,
        offsets=offsets,
        origin=stage_origin(joints3d + track[:, None]),
    )


def _check_keyframes(joints3d_keyframes, n_frames, fps, smooth) -> tuple[np.ndarray, np.ndarray]:
    """Sorted keyframe indices (K,) and their joints (K, 16, 3); bad input -> MocapError."""
    if not n_frames >= 1 or not fps > 0 or not smooth >= 0:
        raise MocapError(f"motion needs n_frames >= 1, fps > 0 and smooth >= 0 (got {n_frames}, {fps}, {smooth})")
    keys = np.array(sorted(joints3d_keyframes), dtype=int)
    if not len(keys) or keys[0] < 0 or keys[-1] >= n_frames:
        raise MocapError(f"keyframes must be a non-empty set of frames in 0..{n_frames - 1}")
    joints = np.array([np.asarray(joints3d_keyframes[k], dtype=float) for k in keys])
    if joints.shape[1:] != (len(JOINTS), 3) or not np.isfinite(joints).all():
        raise MocapError(f"keyframe joints must be finite arrays of shape ({len(JOINTS)}, 3)")
    return keys, joints


def _slerp_frames(keys: np.ndarray, local: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames, B, 4) quaternions slerped between keyframes, held outside them."""
    if len(keys) == 1:
        return np.repeat(local, n_frames, axis=0)
    times = np.clip(np.arange(n_frames), keys[0], keys[-1])
    return np.stack(
        [Slerp(keys, Rotation.from_quat(local[:, b]))(times).as_quat() for b in range(local.shape[1])], axis=1
    )


def _continuous(quats: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so consecutive frames share a hemisphere (smoothing, glTF playback)."""
    flips = np.sign(np.sum(quats[1:] * quats[:-1], axis=-1))
    flips[flips == 0] = 1
    sign = np.concatenate([np.ones((1, quats.shape[1])), np.cumprod(flips, axis=0)])
    return quats * sign[..., None]


def _lerp_frames(keys: np.ndarray, values: np.ndarray, n_frames: int) -> np.ndarray:
    """(n_frames, ...) ``values`` at sorted frames ``keys``, linearly interpolated, held outside."""
    if len(keys) == 1:
        return np.repeat(values, n_frames, axis=0)
    t = np.arange(n_frames)
    i = np.clip(np.searchsorted(keys, t, side="right") - 1, 0, len(keys) - 2)
    w = np.clip((t - keys[i]) / (keys[i + 1] - keys[i]), 0.0, 1.0)
    w = w.reshape(-1, *[1] * (values.ndim - 1))
    return values[i] * (1 - w) + values[i + 1] * w


def _root_track(keys: np.ndarray, pelvis: np.ndarray, root: np.ndarray | None, n_frames: int) -> np.ndarray:
    """(n_frames, 3) pelvis track: ``root`` with NaN rows filled, or keyframe pelvises interpolated."""
    if root is None:
        return _lerp_frames(keys, pelvis, n_frames)
    root = np.asarray(root, dtype=float)
    known = np.flatnonzero(np.isfinite(root).all(axis=-1)) if root.shape == (n_frames, 3) else []
    if not len(known):
        raise MocapError(f"root must be an array of shape ({n_frames}, 3) with a finite row")
    return _lerp_frames(known, root[known], n_frames)


def _smooth_pinned(track: np.ndarray, keys: np.ndarray, sigma: float) -> np.ndarray:
    """Gaussian smoothing along axis 0, the keyframes' residual added back by a natural cubic spline."""
    from scipy.interpolate import CubicSpline  # here: only --smooth needs it

    smooth = gaussian_filter1d(track, sigma, axis=0, mode="nearest")
    residual = track[keys] - smooth[keys]
    if len(keys) == 1:
        return smooth + residual
    times = np.clip(np.arange(len(track)), keys[0], keys[-1])
    return smooth + CubicSpline(keys, residual, axis=0, bc_type="natural")(times)


def stage_origin(world: np.ndarray) -> np.ndarray:
    """(3,) the exports' origin for joints (F, 16, 3) in the root's frame: the floor below frame 0's pelvis."""
    ankles = world[:, [JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]], 1].min(axis=1)
    floor = np.percentile(ankles, FLOOR_PERCENTILE) - ANKLE_HEIGHT * UNIT_M
    pelvis = world[0, JOINT_INDEX["pelvis"]]
    return np.array([pelvis[0], floor, pelvis[2]])
