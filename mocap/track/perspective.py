"""The 3D skeleton under perspective projection: the tracking paper's reconstruction
(Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000, section "Reconstruction
of 3D human motion skeleton", Eq. 6-11).

1. **Calibration** (Eq. 6-9, mocap.track.calibration): the body's rotation and
   translation relative to the camera on frame 0 from the marked key triangle (both
   shoulders and the chest) and, beyond the paper, the hips.
2. **Later frames** (Eq. 10-11, mocap.track.keydepths): the key joints' depths solve
   "each key joint on its ray, the key triangle's sides keep their lengths", by
   Gauss-Newton from the previous frame's depths, kept to the side the user's
   orientation names.
3. **Centre to fringe** (here and mocap.track.rays): every other joint on its pixel's
   viewing ray at its bone length from a joint already placed.

Bone lengths are measured from the tracked 2D over the clip (``measured_lengths``)
at the metric scale that the model's key triangle gives; the key triangle and the
hips keep the model's proportions (with the shoulder span found by the calibration).

Internally points are in the pinhole frame (X right, Y down, Z the depth along the
optical axis); ``to_contract`` turns them into CONTRACT.md's frame.
"""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS, SEGMENT_JOINTS
from mocap.smoothest import DEPTH_SMOOTH_S, two_state_path
from mocap.track.calibration import KEY, MODEL, UNIT_M, Pinhole
from mocap.track.keydepths import Turns, body_axes, key_joints, mirror_images, turned_against
from mocap.track.rays import (LIMBS, choose_limb, limb_candidates, limb_penalty, ray_roots,
                              signs_allowed, toward_signs)

# bones from the centre to the fringe: (known joint, joint placed from it)
BONES = tuple((JOINT_INDEX[a], JOINT_INDEX[b]) for a, b in body.bones_from(tuple(JOINTS[k] for k in KEY)))
BONE_INDEX = {bone: n for n, bone in enumerate(BONES)}
TORSO_BONES = len(BONES) - 2 * len(body.LIMBS)   # the first bones move with the key triangle
# pelvis to hips: the model's, not measured
HIP_BONES = tuple(n for n, (_, b) in enumerate(BONES[:TORSO_BONES])
                  if JOINTS[b] in {one.joints[0] for one in body.LIMBS})
# of each bone's seen lengths over the clip (measured_lengths), by the joint it places (the
# side left out): the median; the head's and the torso's lower quartile, the shins' upper, the
# forearms' 60th percentile
LENGTH_PERCENTILES = {"head_top": 25, "pelvis": 25, "ankle": 75, "wrist": 60}
# the least a forearm's measured length is of its upper arm's (``measured_lengths``):
# 0.78 in anthropometric tables (0.146 and 0.186 of the stature), 0.70 to 1.02 in the
# motion capture at hand
FOREARM_PER_UPPER_ARM = 0.7
SEGMENT_OF = {(int(a), int(b)): k for k, (a, b) in enumerate(SEGMENT_JOINTS)}
# degrees the head's top leans forward of the neck in the trunk that guides the trunk's
# depth choices (``guide_trunk``)
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
    """Trunk joints whose root choice decides a segment's sign: joint -> (segment, its
    other end, already placed; whether the joint is the segment's distal end)."""
    placed, out = set(KEY.tolist()), {}
    for _, b in BONES[:TORSO_BONES]:
        for k, (proximal, distal) in enumerate(SEGMENT_JOINTS.tolist()):
            other = distal if b == proximal else proximal
            if b in (proximal, distal) and other in placed:
                out[b] = (k, other, b == distal)
        placed.add(b)
    return out


def guide_trunk() -> np.ndarray:
    """(16, 3) the model skeleton (calibration.MODEL) with its head's top leant
    HEAD_TILT_DEG forward about the neck: the rigid trunk whose joints tell which of
    the two roots on its ray a trunk joint takes (``trunk_joints``).

    The neck joint sits at the back of the neck and the top of the head above the
    ears, so the head leans forward of the trunk's axis: 10-39 degrees (median over
    each clip's frames) in every motion capture at hand, 20-30 in most. An upright
    guide leaves the two roots of a head seen turned toward or away from the camera
    equally near and took the one leaning back as often as not. PA-MPJPE from the
    exact 2D: benchmarks/bench_track.py 35.8 -> 35.2 mm, the shared perspective clips
    48.4 -> 48.2 and 50.4 -> 47.1 mm (head top 87 -> 48 mm; 15 degrees: 35.1, 48.3,
    50.4; 30: 35.3, 48.5, 46.1)."""
    out = MODEL.copy()
    neck, top = JOINT_INDEX["neck"], JOINT_INDEX["head_top"]
    tilt = np.radians(HEAD_TILT_DEG)
    length = np.linalg.norm(MODEL[top] - MODEL[neck])
    out[top] = out[neck] + length * np.array([0.0, np.cos(tilt), np.sin(tilt)])
    return out


GUIDE = guide_trunk()
BONE_PAIRS = _pooled_bones()     # measured, left/right pooled
# (upper arm, forearm) bones of each arm
ARM_BONES = tuple((BONE_INDEX[JOINT_INDEX[a], JOINT_INDEX[b]], BONE_INDEX[JOINT_INDEX[b], JOINT_INDEX[c]])
                  for a, b, c in (one.joints for one in body.LIMBS if one.kind == "arm"))
TRUNK_SIGNS = _trunk_signs()
# of the way from its ray-sphere root to its limb's swing plane (toward_swing_planes) that an
# elbow or wrist, a knee or ankle is moved; the cosines between the joint's line of sight
# and the plane's normal from which on the move is made in part and in full (the plane
# seen edge-on tells no depth)
SWING_PLANE_WEIGHT = {False: 0.3, True: 0.5}   # arm, leg
SWING_PLANE_SIGHT = (0.3, 0.6)
# joint-limit penalty (rays.limb_penalty) per metre between the key triangle's two mirror
# images that turning from one to the other between frames costs (``sided_key``)
MIRROR_SWITCH_COST = 20.0


def bone_lengths(joints3d: np.ndarray) -> np.ndarray:
    """(..., 13) the lengths of BONES in 3D joints (..., 16, 3)."""
    bones = np.array(BONES)
    return np.linalg.norm(joints3d[..., bones[:, 1], :] - joints3d[..., bones[:, 0], :], axis=-1)


def measured_lengths(joints2d: np.ndarray, depth: np.ndarray, camera: Pinhole,
                     seen: np.ndarray | None = None) -> np.ndarray:
    """(13,) bone lengths (metres) measured over a clip: a percentile
    (LENGTH_PERCENTILES) of each bone's image length at the body's depth ``depth``
    (F,), both sides of a pair pooled, over the frames ``seen`` (F,) bool (default
    all; where none is, all); the metric scale is the model key triangle's.
    The hips keep the model's span: a body turned from the camera never shows it
    (turned 45 degrees the median reads it a third short, and each hip then sinks to
    the pelvis' depth), and hip spans differ little from body to body (see
    ``calibrate``).

    Beyond the paper, which takes lengths from anatomy: real bodies differ from the
    model (the forearms of the CMU skeletons are about 30% shorter), and a bone taken
    too long gets depth it does not have. A bone's image length reaches its length
    where it crosses the image plane, but 2D tracking errors inflate high percentiles
    more than a missed crossing deflates the median, which measured best on rendered
    motion capture (benchmarks/bench_track.py); the median errs short, toward flat.
    The head and the torso stand upright most of the time, where a length read long
    turns into a lean toward or away from the camera: theirs is the lower quartile,
    as the silhouette method's (mocap.lift.inputs.FIT_LENGTH_PERCENTILE; PA-MPJPE 74.1 ->
    73.4 mm). The shins are the other exception: tracked best (the ankles' blocks end
    on the feet) and upright through every stance, where they show their whole
    length, so their upper quartile measures them (PA-MPJPE 77.1 -> 75.3 mm on the
    tracked 2D, every clip better; the 90th percentile overshoots: 76.4). The
    forearms read long too, for the opposite reason: the hands work in front of the
    body, so a forearm is foreshortened more often than not, and the median read
    track_salsa's forearms 0.64 of their length where the upper arms read 0.75 of
    theirs. Their 60th percentile: benchmarks/bench_track_clips.py from the tracked
    2D, track_salsa 77.5 -> 76.3 mm, track_walk 72.3 -> 71.8, laugh_arms_up 68.7 ->
    66.7; bench_track.py 67.9 -> 67.9 (exact 2D 35.2 -> 34.6). The upper quartile
    reads them better from the exact 2D (34.3) but takes more of the tracked wrists'
    errors into depth (cmu_walk yaw 45: 65.4 -> 68.5; track_salsa 74.3). A forearm
    that the clip never shows at its length (track_salsa's right one points 50-60
    degrees away from the camera throughout) reads short at any percentile: it is
    taken at least FOREARM_PER_UPPER_ARM of the upper arm (track_salsa 76.3 -> 74.2
    mm, exact 2D 41.3 -> 38.8; the other clips and bench_track.py's within 0.1 mm;
    0.78, the tables' ratio, gives track_salsa 73.5 but cmu_01_01_jumps, whose
    forearms are 0.70 of its upper arms, 68.6 -> 69.5 mm from yaw 45). A frame
    where the tracking lost the body holds no bones at all, only what the blocks
    followed (``seen`` leaves it out)."""
    if seen is not None and seen.any():
        joints2d, depth = joints2d[seen], depth[seen]
    ends = joints2d[:, np.array(BONES)]                                     # (F, 13, 2, 2)
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


def trunk_joints(key: np.ndarray, rays: np.ndarray, lengths: np.ndarray,
                 fixed: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) the key joints and the trunk's (neck, head top, pelvis, hips), each
    on its ray at the root nearer the model trunk (its head leant forward,
    ``guide_trunk``) carried rigidly by the key triangle, or at the other root
    where that gives the head or the torso the user's foreshortening ``fixed``
    (F, 10) (+1 toward, -1 away, 0 not said)."""
    joints = np.zeros(rays.shape)
    joints[:, KEY] = key
    axes = body_axes(key)
    frames = np.arange(len(key))
    for (a, b), length in list(zip(BONES, lengths))[:TORSO_BONES]:
        roots = ray_roots(joints[:, a], rays[:, b], length)                    # (F, 2, 3)
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


def add_limbs(joints: np.ndarray, rays: np.ndarray, lengths: np.ndarray,
              fixed: np.ndarray | None = None) -> np.ndarray:
    """Fill in elbows, wrists, knees and ankles on their rays (rays.choose_limb), with
    the user's foreshortening ``fixed`` (F, 10) where given."""
    axes = body_axes(joints[:, KEY])
    frames = np.arange(len(joints))
    for root, middle, end, leg, side in LIMBS:
        pair = (BONE_INDEX[root, middle], BONE_INDEX[middle, end])
        cands = limb_candidates(joints[:, root], rays[:, [middle, end]], tuple(lengths[list(pair)]))
        allowed = None
        if fixed is not None:
            depths = np.concatenate([np.repeat(joints[:, root, None, None, 2], 4, axis=1),
                                     cands[..., 2]], axis=2)                  # (F, 4, 3)
            said = fixed[:, [SEGMENT_OF[root, middle], SEGMENT_OF[middle, end]]]
            allowed = signs_allowed(toward_signs(depths), said)
        pick = choose_limb(cands - joints[:, root, None, None],
                           limb_penalty(joints[:, root], cands, axes, leg, side), allowed)
        joints[:, middle], joints[:, end] = cands[frames, pick, 0], cands[frames, pick, 1]
    return joints


def reconstruct(joints2d: np.ndarray, camera: Pinhole, turns: Turns = None,
                lengths: np.ndarray | None = None, seen: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) joints in the pinhole frame (metres) from 2D joints (F, 16, 2): the
    key joints turned to ``turns`` (``key_joints``) on the side the limbs take
    (``sided_key``), then the others (``place_joints``, the bones measured over the
    frames ``seen``)."""
    key = sided_key(joints2d, key_joints(joints2d, camera, turns), camera, turns, lengths, seen)
    return place_joints(joints2d, key, camera, lengths, seen=seen)


def sided_key(joints2d: np.ndarray, key: np.ndarray, camera: Pinhole, turns: Turns = None,
              lengths: np.ndarray | None = None, seen: np.ndarray | None = None) -> np.ndarray:
    """(F, 3, 3) on every frame the key joints ``key`` (F, 3, 3) or their mirror image
    (keydepths.mirror_images), whichever the limbs take better: a two-state path
    over the clip where each frame costs the limbs' joint-limit penalty under its
    trunk (``limits_under``) and a turn from one to the other costs
    MIRROR_SWITCH_COST per metre that the two lie apart; a mirror image turned
    clearly against the side ``turns`` holds there is not taken.

    Beyond the paper: Eq. 10-11 follow the triangle from frame to frame, and a body
    turned the other way from the start (frame 0 of salsa_spin faces the camera)
    or turning through the frontal view, where the two images meet, stays turned
    the wrong way: every knee and elbow then bends backwards. PA-MPJPE from the
    exact 2D with no orientation said (the session guesses frame 0's side alone):
    salsa_spin 83.7 -> 69.6 mm; the other clips of benchmarks/bench_track_clips.py
    unchanged, and every clip there with frame 0's orientation held over the clip,
    as its marks say it."""
    if lengths is None:
        lengths = measured_lengths(joints2d, key[:, :, 2].mean(axis=1), camera, seen)
    mirror = mirror_images(key)
    rays = camera.rays(joints2d)
    costs = np.stack([limits_under(k, rays, lengths) for k in (key, mirror)], axis=1)
    held = [turns] * len(key) if turns is None or isinstance(turns, str) else list(turns)
    against = np.array([turned_against(m, t) and not turned_against(k, t)
                        for k, m, t in zip(key, mirror, held)])
    costs[against, 1] = np.inf
    apart = np.linalg.norm(key - mirror, axis=-1).max(axis=1)
    path = two_state_path(costs, MIRROR_SWITCH_COST * np.maximum(apart[1:], apart[:-1]))
    return np.where(path[:, None, None] == 1, mirror, key)


def limits_under(key: np.ndarray, rays: np.ndarray, lengths: np.ndarray) -> np.ndarray:
    """(F,) the least joint-limit penalty (rays.limb_penalty) of every limb's four root
    choices, summed over the limbs, with the trunk placed from key joints (F, 3, 3)
    (``trunk_joints``) on the joints' ``rays`` (F, 16, 3) at bone ``lengths``."""
    joints = trunk_joints(key, rays, lengths)
    axes = body_axes(key)
    out = np.zeros(len(key))
    for root, middle, end, leg, side in LIMBS:
        pair = (BONE_INDEX[root, middle], BONE_INDEX[middle, end])
        cands = limb_candidates(joints[:, root], rays[:, [middle, end]], tuple(lengths[list(pair)]))
        out += limb_penalty(joints[:, root], cands, axes, leg, side).min(axis=1)
    return out


def place_joints(joints2d: np.ndarray, key: np.ndarray, camera: Pinhole,
                 lengths: np.ndarray | None = None, fixed: np.ndarray | None = None,
                 seen: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) every joint from the key joints ``key`` (F, 3, 3) centre to fringe at
    their bone ``lengths`` (default: ``measured_lengths`` over the frames ``seen``,
    default all), each limb's and the
    trunk's depth choices kept to the user's foreshortening ``fixed`` (F, 10) where
    given (+1 toward, -1 away, 0 not said)."""
    if lengths is None:
        lengths = measured_lengths(joints2d, key[:, :, 2].mean(axis=1), camera, seen)
    rays = camera.rays(joints2d)
    joints = add_limbs(trunk_joints(key, rays, lengths, fixed), rays, lengths, fixed)
    return toward_swing_planes(joints, rays, lengths, fixed)


def toward_swing_planes(joints: np.ndarray, rays: np.ndarray, lengths: np.ndarray,
                        fixed: np.ndarray | None = None) -> np.ndarray:
    """Every elbow and wrist, knee and ankle of ``joints`` (F, 16, 3) moved along its
    ray part of the way (SWING_PLANE_WEIGHT) to where the ray meets its limb's swing
    plane: the plane through the limb's root (shoulder or hip) square to the body's
    left-right axis (the key triangle's), in which arms and legs mostly swing. No
    move where the plane is seen nearly edge-on (SWING_PLANE_SIGHT) or the user
    fixed the segment's foreshortening (``fixed``).

    Beyond the paper: a ray-sphere root's depth, sqrt(l^2 - d^2) from the parent,
    swings by decimetres with a few pixels of 2D error where a bone lies near the
    image plane (d near l), and a wrong root choice puts it at the mirror image;
    the plane's point moves with the pixels only as the body's turn from the camera
    divides them. The blend errs less than either. PA-MPJPE of the tracking
    benchmark (benchmarks/bench_track.py): 70.4 -> 64.8 mm (the legs alone: 66.6;
    the plane's point alone: 71.8; a least squares of both misfits along the ray:
    68.7; no move where the plane's point is nearer the other root: 67.2); from the
    exact 2D 35.1 -> 35.5. The price: a limb raised sideways is drawn toward its
    swing plane (the arms of the benchmark's clips turned 45 degrees out of it, from
    the exact 2D: 86.7 -> 95.1 mm) unless the user fixes its foreshortening."""
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
    """(F,) depths at which ``rays`` (F, 3) meet the planes through ``point`` (F, 3)
    with ``normal`` (F, 3)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return (normal * point).sum(-1) / (normal * rays).sum(-1)


def steady_depths(points: np.ndarray, fps: float) -> np.ndarray:
    """Pinhole-frame joints (F, 16, 3), each moved along its viewing ray to its depth
    smoothed over time (a Gaussian of inputs.DEPTH_SMOOTH_S, as the silhouette
    method's lifted depths): the ray-sphere roots carry the 2D tracking's jitter
    into depth, which real motion does not have."""
    z = gaussian_filter1d(points[..., 2], DEPTH_SMOOTH_S * fps, axis=0, mode="nearest")
    return points * (z / points[..., 2])[..., None]


def to_contract(points: np.ndarray) -> np.ndarray:
    """Pinhole-frame joints (..., 16, 3) -> CONTRACT.md's frame: metres, origin at the
    pelvis, x to the image right, y up, z toward the camera."""
    out = points * np.array([1.0, -1.0, -1.0])
    return out - out[..., JOINT_INDEX["pelvis"]:JOINT_INDEX["pelvis"] + 1, :]
