"""The 3D skeleton under perspective projection (Pan, Zhuang and Liu 2000, section "Reconstruction of 3D human motion
skeleton"): calibration (Eq. 6-9), key-triangle depths (Eq. 10-11), then every other joint centre to fringe on its
viewing ray (mocap.track.rays). Points are in the pinhole frame (X right, Y down, Z depth, metres)."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS, SEGMENT_JOINTS
from mocap.camera import FLIP_YZ, Pinhole
from mocap.smoothest import DEPTH_SMOOTH_S, two_state_path
from mocap.track.calibration import KEY, MODEL, UNIT_M
from mocap.track.keydepths import Turns, body_axes, key_joints, mirror_images, turned_against
from mocap.track.rays import LIMBS, choose_limb, limb_candidates, limb_penalty, ray_roots, signs_allowed, toward_signs

# bones from the centre to the fringe: (known joint, joint placed from it)
BONES = tuple((JOINT_INDEX[a], JOINT_INDEX[b]) for a, b in body.bones_from(tuple(JOINTS[k] for k in KEY)))
BONE_INDEX = {bone: n for n, bone in enumerate(BONES)}
TORSO_BONES = len(BONES) - 2 * len(body.LIMBS)  # the first bones move with the key triangle
# pelvis to hips: the model's, not measured
HIP_BONES = tuple(
    n for n, (_, b) in enumerate(BONES[:TORSO_BONES]) if JOINTS[b] in {one.joints[0] for one in body.LIMBS}
)
# percentile of a bone's seen lengths (measured_lengths) by the joint it places, else the median: head and torso
# the lower quartile (a length read long becomes a lean), the shins the upper (tracked best and upright, so they show
# their whole length), the forearms the 60th (the hands work in front, foreshortening them)
LENGTH_PERCENTILES = {"head_top": 25, "pelvis": 25, "ankle": 75, "wrist": 60}
# the least a forearm's measured length is of its upper arm's: a forearm never seen at its length reads short
FOREARM_PER_UPPER_ARM = 0.7
SEGMENT_OF = {(int(a), int(b)): k for k, (a, b) in enumerate(SEGMENT_JOINTS)}
# degrees the head's top leans forward of the neck in the guide trunk (``guide_trunk``)
HEAD_TILT_DEG = 20.0


def _pooled_bones() -> tuple[tuple[int, ...], ...]:
    """The measured bones (all but HIP_BONES), each with its mirror image where it has one."""
    out = []
    for n, (a, b) in enumerate(BONES):
        twin = BONE_INDEX[body.MIRROR_JOINTS[a], body.MIRROR_JOINTS[b]]
        if n not in HIP_BONES and twin >= n:
            out.append((n,) if twin == n else (n, twin))
    return tuple(out)


def _trunk_signs() -> dict[int, tuple[int, int, bool]]:
    """Trunk joint -> (segment, its placed other end, whether the joint is distal), for joints fixing a sign."""
    placed, out = set(KEY.tolist()), {}
    for _, b in BONES[:TORSO_BONES]:
        for k, (proximal, distal) in enumerate(SEGMENT_JOINTS.tolist()):
            other = distal if b == proximal else proximal
            if b in (proximal, distal) and other in placed:
                out[b] = (k, other, b == distal)
        placed.add(b)
    return out


def guide_trunk() -> np.ndarray:
    """(16, 3) the model skeleton with its head top leant HEAD_TILT_DEG forward about the neck, as real heads lean:
    the rigid trunk that picks each trunk joint's root (``trunk_joints``)."""
    out = MODEL.copy()
    neck, top = JOINT_INDEX["neck"], JOINT_INDEX["head_top"]
    tilt = np.radians(HEAD_TILT_DEG)
    length = np.linalg.norm(MODEL[top] - MODEL[neck])
    out[top] = out[neck] + length * np.array([0.0, np.cos(tilt), np.sin(tilt)])
    return out


GUIDE = guide_trunk()
BONE_PAIRS = _pooled_bones()  # measured, left/right pooled
# (upper arm, forearm) bones of each arm
ARM_BONES = tuple(
    (BONE_INDEX[JOINT_INDEX[a], JOINT_INDEX[b]], BONE_INDEX[JOINT_INDEX[b], JOINT_INDEX[c]])
    for a, b, c in (one.joints for one in body.LIMBS if one.kind == "arm")
)
TRUNK_SIGNS = _trunk_signs()
# share of the way to the swing plane a limb joint moves (toward_swing_planes); sight-normal cosines from which
# the move is made in part and in full (a plane seen edge-on tells no depth)
SWING_PLANE_WEIGHT = {False: 0.3, True: 0.5}  # arm, leg
SWING_PLANE_SIGHT = (0.3, 0.6)
# joint-limit penalty per metre between the key triangle's mirror images that switching costs (``sided_key``)
MIRROR_SWITCH_COST = 20.0


def bone_lengths(joints3d: np.ndarray) -> np.ndarray:
    """(..., 13) the lengths of BONES in 3D joints (..., 16, 3)."""
    bones = np.array(BONES)
    return np.linalg.norm(joints3d[..., bones[:, 1], :] - joints3d[..., bones[:, 0], :], axis=-1)


def measured_lengths(
    joints2d: np.ndarray, depth: np.ndarray, camera: Pinhole, seen: np.ndarray | None = None
) -> np.ndarray:
    """(13,) bone lengths (m): a percentile (LENGTH_PERCENTILES) of each bone's image length at the body's ``depth``
    (F,), sides pooled, over frames ``seen`` (F,) bool (default all), at the model triangle's scale; hip bones the
    model's. Beyond the paper's anatomical lengths: a bone taken too long gets depth it does not have."""
    if seen is not None and seen.any():
        joints2d, depth = joints2d[seen], depth[seen]
    ends = joints2d[:, np.array(BONES)]  # (F, 13, 2, 2)
    seen = np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1) * depth[:, None] / camera.focal
    out = np.empty(len(BONES))
    out[list(HIP_BONES)] = body.HIP_HALF_SPAN * UNIT_M
    for group in BONE_PAIRS:
        placed = JOINTS[BONES[group[0]][1]]
        percentile = LENGTH_PERCENTILES.get(placed.removesuffix("_l").removesuffix("_r"), 50)
        out[list(group)] = np.percentile(seen[:, list(group)], percentile)
    for upper, fore in ARM_BONES:
        out[fore] = max(out[fore], FOREARM_PER_UPPER_ARM * out[upper])
    return out


def trunk_joints(key: np.ndarray, rays: np.ndarray, lengths: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) key and trunk joints, each on its ray at the root nearer the guide trunk (``guide_trunk``) carried
    by the key triangle, or the other root where ``fixed`` (F, 10) (+1 toward, -1 away, 0 unsaid) demands it."""
    joints = np.zeros(rays.shape)
    joints[:, KEY] = key
    axes = body_axes(key)
    frames = np.arange(len(key))
    for (a, b), length in list(zip(BONES, lengths))[:TORSO_BONES]:
        roots = ray_roots(joints[:, a], rays[:, b], length)  # (F, 2, 3)
        guess = joints[:, a] + axes @ (GUIDE[b] - GUIDE[a])
        miss = np.linalg.norm(roots - guess[:, None], axis=-1)
        allowed = np.ones(miss.shape, bool)
        if fixed is not None and b in TRUNK_SIGNS:
            segment, other, distal = TRUNK_SIGNS[b]
            depths = np.stack([roots[..., 2], np.repeat(joints[:, other, None, 2], 2, axis=1)], -1)
            signs = toward_signs(depths if not distal else depths[..., ::-1])
            allowed = signs_allowed(signs, fixed[:, [segment]])
        joints[:, b] = roots[frames, np.where(allowed, miss, np.inf).argmin(axis=1)]
    return joints


def add_limbs(joints: np.ndarray, rays: np.ndarray, lengths: np.ndarray, fixed: np.ndarray | None = None) -> np.ndarray:
    """Elbows, wrists, knees and ankles placed on their rays (rays.choose_limb), kept to ``fixed`` (F, 10)."""
    axes = body_axes(joints[:, KEY])
    frames = np.arange(len(joints))
    for root, middle, end, leg, side in LIMBS:
        pair = (BONE_INDEX[root, middle], BONE_INDEX[middle, end])
        cands = limb_candidates(joints[:, root], rays[:, [middle, end]], tuple(lengths[list(pair)]))
        allowed = None
        if fixed is not None:
            depths = np.concatenate(
                [np.repeat(joints[:, root, None, None, 2], 4, axis=1), cands[..., 2]], axis=2
            )  # (F, 4, 3)
            said = fixed[:, [SEGMENT_OF[root, middle], SEGMENT_OF[middle, end]]]
            allowed = signs_allowed(toward_signs(depths), said)
        pick = choose_limb(
            cands - joints[:, root, None, None], limb_penalty(joints[:, root], cands, axes, leg, side), allowed
        )
        joints[:, middle], joints[:, end] = cands[frames, pick, 0], cands[frames, pick, 1]
    return joints


def reconstruct(
    joints2d: np.ndarray,
    camera: Pinhole,
    turns: Turns = None,
    lengths: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> np.ndarray:
    """(F, 16, 3) pinhole-frame joints (metres) of 2D joints (F, 16, 2): the key joints turned to ``turns`` on the
    side the limbs take (``sided_key``), then the rest (``place_joints``, bones measured over ``seen``)."""
    key = sided_key(joints2d, key_joints(joints2d, camera, turns), camera, turns, lengths, seen)
    return place_joints(joints2d, key, camera, lengths, seen=seen)


def sided_key(
    joints2d: np.ndarray,
    key: np.ndarray,
    camera: Pinhole,
    turns: Turns = None,
    lengths: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> np.ndarray:
    """(F, 3, 3) per frame ``key`` or its mirror, whichever the limbs take better (two-state path, switches costing
    MIRROR_SWITCH_COST per metre), never a mirror clearly against ``turns``: Eq. 10-11 alone keep a wrong turn."""
    if lengths is None:
        lengths = measured_lengths(joints2d, key[:, :, 2].mean(axis=1), camera, seen)
    mirror = mirror_images(key)
    rays = camera.rays(joints2d)
    costs = np.stack([limits_under(k, rays, lengths) for k in (key, mirror)], axis=1)
    held = [turns] * len(key) if turns is None or isinstance(turns, str) else list(turns)
    against = np.array([turned_against(m, t) and not turned_against(k, t) for k, m, t in zip(key, mirror, held)])
    costs[against, 1] = np.inf
    apart = np.linalg.norm(key - mirror, axis=-1).max(axis=1)
    path = two_state_path(costs, MIRROR_SWITCH_COST * np.maximum(apart[1:], apart[:-1]))
    return np.where(path[:, None, None] == 1, mirror, key)


def limits_under(key: np.ndarray, rays: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(F,) summed least joint-limit penalty of the limbs, trunk from ``key`` (F, 3, 3) on ``rays`` (F, 16, 3)."""
    joints = trunk_joints(key, rays, lengths)
    axes = body_axes(key)
    out = np.zeros(len(key))
    for root, middle, end, leg, side in LIMBS:
        pair = (BONE_INDEX[root, middle], BONE_INDEX[middle, end])
        cands = limb_candidates(joints[:, root], rays[:, [middle, end]], tuple(lengths[list(pair)]))
        out += limb_penalty(joints[:, root], cands, axes, leg, side).min(axis=1)
    return out


def place_joints(
    joints2d: np.ndarray,
    key: np.ndarray,
    camera: Pinhole,
    lengths: np.ndarray | None = None,
    fixed: np.ndarray | None = None,
    seen: np.ndarray | None = None,
) -> np.ndarray:
    """(F, 16, 3) every joint from ``key`` (F, 3, 3) centre to fringe at bone ``lengths`` (default measured over
    ``seen``), depth choices kept to ``fixed`` (F, 10) (+1 toward, -1 away, 0 unsaid) where given."""
    if lengths is None:
        lengths = measured_lengths(joints2d, key[:, :, 2].mean(axis=1), camera, seen)
    rays = camera.rays(joints2d)
    joints = add_limbs(trunk_joints(key, rays, lengths, fixed), rays, lengths, fixed)
    return toward_swing_planes(joints, rays, lengths, fixed)


def toward_swing_planes(
    joints: np.ndarray, rays: np.ndarray, lengths: np.ndarray, fixed: np.ndarray | None = None
) -> np.ndarray:
    """Limb joints of ``joints`` (F, 16, 3) moved SWING_PLANE_WEIGHT of the way along their rays to the swing plane
    (through the root, square to the shoulders), unless edge-on or ``fixed``: ray-sphere depths swing with pixel
    errors near the image plane. Limbs raised sideways are drawn toward the plane."""
    left = body_axes(joints[:, KEY])[..., 0]
    for root, middle, end, leg, _ in LIMBS:
        for parent, joint in ((root, middle), (middle, end)):
            sight = np.abs((left * rays[:, joint]).sum(-1)) / np.linalg.norm(rays[:, joint], axis=-1)
            low, high = SWING_PLANE_SIGHT
            weight = SWING_PLANE_WEIGHT[leg] * np.clip((sight - low) / (high - low), 0.0, 1.0)
            if fixed is not None:
                weight = np.where(fixed[:, SEGMENT_OF[parent, joint]] != 0, 0.0, weight)
            depth = joints[:, joint, 2]
            plane = np.where(weight > 0, plane_depths(joints[:, root], left, rays[:, joint]), depth)
            joints[:, joint] = (depth + weight * (plane - depth))[:, None] * rays[:, joint]
    return joints


def plane_depths(point: np.ndarray, normal: np.ndarray, rays: np.ndarray) -> np.ndarray:
    """(F,) depths where ``rays`` (F, 3) meet the planes through ``point`` (F, 3) with ``normal`` (F, 3)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return (normal * point).sum(-1) / (normal * rays).sum(-1)


def steady_depths(points: np.ndarray, fps: float) -> np.ndarray:
    """Pinhole joints (F, 16, 3) moved along their rays to depths smoothed over DEPTH_SMOOTH_S, against 2D jitter."""
    z = gaussian_filter1d(points[..., 2], DEPTH_SMOOTH_S * fps, axis=0, mode="nearest")
    return points * (z / points[..., 2])[..., None]


def to_contract(points: np.ndarray) -> np.ndarray:
    """Pinhole joints (..., 16, 3) -> CONTRACT.md's frame: metres, pelvis origin, x right, y up, z to camera."""
    out = points * FLIP_YZ
    return out - out[..., JOINT_INDEX["pelvis"] : JOINT_INDEX["pelvis"] + 1, :]
