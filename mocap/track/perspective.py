"""The 3D skeleton under perspective projection: the tracking paper's reconstruction
(Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000, section "Reconstruction
of 3D human motion skeleton", Eq. 6-11).

1. **Calibration** (Eq. 6-9, ``calibrate``): the body's rotation and translation
   relative to the camera on frame 0, by Newton's method on the perpendicular
   distances E of the marked lines' end points to the model's projected lines: the
   key triangle (both shoulders and the chest) of the model (body.py, a 1.75 m body)
   and, beyond the paper, the triangle of the hips and the chest with the shoulder
   span as a seventh unknown (see ``calibrate``).
2. **Later frames** (Eq. 10-11, ``key_depths``): the key joints' depths solve "each
   key joint on its ray, the key triangle's sides keep their lengths", by
   Gauss-Newton from the previous frame's depths; beyond the paper, kept to the side
   the user's orientation names (``frame_key_depths``).
3. **Centre to fringe** (mocap.track.rays): every other joint on its pixel's viewing ray at
   its bone length from a joint already placed.

Bone lengths are measured from the tracked 2D over the clip (``measured_lengths``)
at the metric scale that the model's key triangle gives; the key triangle and the
hips keep the model's proportions (with the shoulder span found by the calibration).

The focal length is not measured (three points cannot give it): ``focal_px``
defaults to the frame's width, a 53-degree horizontal field of view, an ordinary
lens. A wrong focal length mostly changes the body's distance, hardly its shape, once
the body is a few body heights away.

Internally points are in the pinhole frame (X right, Y down, Z the depth along the
optical axis); ``to_contract`` turns them into CONTRACT.md's frame.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS, SEGMENT_INDEX, SEGMENT_JOINTS
from mocap.errors import MocapError
from mocap.smoothest import DEPTH_SMOOTH_S
from mocap.track.marks import turned_apart
from mocap.track.rays import (LIMBS, choose_limb, limb_candidates, limb_penalty, ray_roots,
                        signs_allowed, toward_signs)

UNIT_M = body.BODY_HEIGHT_M / body.BODY_HEIGHT
KEY_JOINTS = ("shoulder_l", "shoulder_r", "chest")
KEY = np.array([JOINT_INDEX[j] for j in KEY_JOINTS])
KEY_LINES = ((0, 1), (0, 2), (1, 2))
CALIBRATION_LINES = tuple((JOINT_INDEX[a], JOINT_INDEX[b]) for a, b in (
    ("shoulder_l", "shoulder_r"), ("shoulder_l", "chest"), ("shoulder_r", "chest"),
    ("hip_l", "hip_r"), ("hip_l", "chest"), ("hip_r", "chest")))
SPAN_RANGE = (0.2, 0.5)         # metres: shoulder spans the calibration may find
MAX_CALIBRATION_ERROR = 0.03    # of the marked body's size: a worse fit is refused
# bones from the centre to the fringe: (known joint, joint placed from it)
BONES = tuple((JOINT_INDEX[a], JOINT_INDEX[b]) for a, b in (
    ("chest", "neck"), ("neck", "head_top"), ("chest", "pelvis"),
    ("pelvis", "hip_l"), ("pelvis", "hip_r"),
    ("shoulder_l", "elbow_l"), ("elbow_l", "wrist_l"),
    ("shoulder_r", "elbow_r"), ("elbow_r", "wrist_r"),
    ("hip_l", "knee_l"), ("knee_l", "ankle_l"), ("hip_r", "knee_r"), ("knee_r", "ankle_r")))
BONE_INDEX = {bone: n for n, bone in enumerate(BONES)}
BONE_PAIRS = ((0,), (1,), (2,), (5, 7), (6, 8), (9, 11), (10, 12))   # measured, left/right pooled
# of each pair's seen lengths over the clip (measured_lengths): the median; the head's and the
# torso's lower quartile, the shins' upper quartile
LENGTH_PERCENTILES = (50, 25, 25, 50, 50, 50, 75)
HIP_BONES = (3, 4)              # pelvis to hips: the model's, not measured
TORSO_BONES = 5                 # the first five bones move with the key triangle
SEGMENT_OF = {(int(a), int(b)): k for k, (a, b) in enumerate(SEGMENT_JOINTS)}
# trunk joints whose root choice decides a segment's sign: joint -> (segment, its other
# end, already placed; whether the joint is the segment's distal end)
TRUNK_SIGNS = {JOINT_INDEX["head_top"]: (SEGMENT_INDEX["head"], JOINT_INDEX["neck"], True),
               JOINT_INDEX["pelvis"]: (SEGMENT_INDEX["torso"], JOINT_INDEX["neck"], False)}
NEWTON_STEPS = 30
# of the way from its ray-sphere root to its limb's swing plane (toward_swing_planes) that an
# elbow or wrist, a knee or ankle is moved; the cosines between the joint's line of sight
# and the plane's normal from which on the move is made in part and in full (the plane
# seen edge-on tells no depth)
SWING_PLANE_WEIGHT = {False: 0.3, True: 0.5}   # arm, leg
SWING_PLANE_SIGHT = (0.3, 0.6)
SIDE_MARGIN_DEG = 15.0          # a trunk turned less than this from facing the camera
                                # (or from facing away) shows no side
# body frame -> pinhole frame for a performer facing the camera (left to image right,
# up to image up, forward toward the camera)
FACING_CAMERA = np.diag([1.0, -1.0, -1.0])
# the side a body is turned to ("left", "right", None: unsaid): one for every frame, or each frame's
Turns = str | Sequence[str | None] | None


def model_skeleton() -> np.ndarray:
    """(16, 3) the body model standing, arms and legs hanging, in metres in the body
    frame: x the performer's left, y up, z forward, origin at the pelvis."""
    length = dict(zip(body.SEGMENT_NAMES, body.LENGTH))
    torso = length["torso"]
    at = {"pelvis": (0, 0), "neck": (0, torso), "chest": (0, body.CHEST_FRACTION * torso),
          "head_top": (0, torso + length["head"])}
    for side, sign in (("l", 1.0), ("r", -1.0)):
        shoulder = (sign * body.SHOULDER_HALF_SPAN, torso - body.SHOULDER_DROP)
        hip = (sign * body.HIP_HALF_SPAN, 0.0)
        at[f"shoulder_{side}"], at[f"hip_{side}"] = shoulder, hip
        at[f"elbow_{side}"] = (shoulder[0], shoulder[1] - length["upper_arm_l"])
        at[f"wrist_{side}"] = (shoulder[0], at[f"elbow_{side}"][1] - length["lower_arm_l"])
        at[f"knee_{side}"] = (hip[0], -length["upper_leg_l"])
        at[f"ankle_{side}"] = (hip[0], -length["upper_leg_l"] - length["lower_leg_l"])
    return np.array([[*at[j], 0.0] for j in JOINTS], dtype=float) * UNIT_M


def bone_lengths(joints3d: np.ndarray) -> np.ndarray:
    """(..., 13) the lengths of BONES in 3D joints (..., 16, 3)."""
    bones = np.array(BONES)
    return np.linalg.norm(joints3d[..., bones[:, 1], :] - joints3d[..., bones[:, 0], :], axis=-1)


MODEL = model_skeleton()


@dataclass(frozen=True)
class Pinhole:
    """The camera: focal length and principal point in pixels."""

    focal: float
    cx: float
    cy: float

    def rays(self, pixels: np.ndarray) -> np.ndarray:
        """(..., 3) viewing rays (x, y, 1): the point at depth Z is Z times the ray (Eq. 10)."""
        p = np.asarray(pixels, float)
        return np.stack([(p[..., 0] - self.cx) / self.focal, (p[..., 1] - self.cy) / self.focal,
                         np.ones(p.shape[:-1])], axis=-1)

    def project(self, points: np.ndarray) -> np.ndarray:
        """(..., 2) pixels of pinhole-frame points (..., 3)."""
        z = points[..., 2:3]
        return np.array([self.cx, self.cy]) + self.focal * points[..., :2] / z

    def scaled(self, factor: float) -> "Pinhole":
        """The camera of the frames resized by ``factor``."""
        return Pinhole(self.focal * factor, self.cx * factor, self.cy * factor)


def default_camera(width: int, height: int, focal_px: float | None = None) -> Pinhole:
    """The assumed camera of a video: ``focal_px`` or the frame's width, centred."""
    return Pinhole(float(focal_px or width), width / 2.0, height / 2.0)


# -- calibration (Eq. 6-9) --------------------------------------------------------------

@dataclass(frozen=True)
class Calibration:
    """The body's pose in the pinhole frame on frame 0 (the camera's, seen from the
    body): X' = R P + t (Eq. 6) with R the rotation vector (W_x, W_y, W_z) and t the
    translation (the paper's D_x, D_y, D_z, here a true 3D translation rather than
    image offsets), and the performer's shoulder span in metres."""

    rotvec: np.ndarray
    translation: np.ndarray
    span: float

    @classmethod
    def from_params(cls, params: np.ndarray) -> "Calibration":
        return cls(params[:3], params[3:6], float(params[6]))

    def model(self) -> np.ndarray:
        """(16, 3) the standing model with this shoulder span (body frame)."""
        out = MODEL.copy()
        out[[KEY[0], KEY[1]], 0] = self.span / 2, -self.span / 2
        return out

    def to_camera(self, points: np.ndarray) -> np.ndarray:
        """Body points (..., 3) in the pinhole frame (Eq. 6)."""
        return Rotation.from_rotvec(self.rotvec).apply(points) + self.translation

    def key_triangle(self) -> tuple[np.ndarray, np.ndarray]:
        """The key joints' depths (3,) on the calibrated frame and the key triangle's
        side lengths (3,) (KEY_LINES) that later frames keep (Eq. 10-11)."""
        triangle = self.model()[KEY]
        sides = np.array([np.linalg.norm(triangle[i] - triangle[j]) for i, j in KEY_LINES])
        return self.to_camera(triangle)[:, 2], sides

    @property
    def yaw(self) -> float:
        """The body's yaw in degrees (as lift.facing_yaw: 0 faces the camera, +90
        faces image right)."""
        forward = Rotation.from_rotvec(self.rotvec).apply([0.0, 0.0, 1.0])
        return float(np.degrees(np.arctan2(forward[0], -forward[2])))


def line_distances(params: np.ndarray, camera: Pinhole, marks: np.ndarray) -> np.ndarray:
    """E of Eq. 9: (12,) signed perpendicular distances of the two marked end points of
    each of the six CALIBRATION_LINES to the model's line projected by Eq. 6-7.

    The projected line is Eq. 8, -m/sqrt(m^2+1) u + 1/sqrt(m^2+1) v = d, written with
    its unit normal so that vertical lines (infinite slope m) need no special case.
    """
    cal = Calibration.from_params(params)
    seen = camera.project(cal.to_camera(cal.model()))
    out = []
    for i, j in CALIBRATION_LINES:
        direction = seen[j] - seen[i]
        normal = np.array([-direction[1], direction[0]]) / max(np.hypot(*direction), 1e-9)
        d = normal @ seen[i]
        out += [normal @ marks[i] - d, normal @ marks[j] - d]
    return np.array(out)


def newton(residual, params: np.ndarray, steps: int = NEWTON_STEPS,
           eps: float = 1e-6) -> np.ndarray:
    """Solve residual(params) = 0, in the least-squares sense when over-determined,
    by Newton / Gauss-Newton steps with a numerical Jacobian (Eq. 9: J delta = -E),
    halving a step that does not reduce |E|."""
    r = residual(params)
    for _ in range(steps):
        jac = np.column_stack([(residual(params + eps * e) - r) / eps
                               for e in np.eye(len(params))])
        delta = np.linalg.lstsq(jac, -r, rcond=None)[0]
        for _ in range(10):
            trial = residual(params + delta)
            if trial @ trial < r @ r:
                params, r = params + delta, trial
                break
            delta = delta / 2
        else:
            break
    return params


def initial_params(marks: np.ndarray, camera: Pinhole) -> list[np.ndarray]:
    """Start values (7,) for the calibration: the model upright at the depth where its
    chest-to-pelvis length matches the marks, turned by either of the two yaws whose
    cosine the marked hip span gives (left hip on the image right: facing the camera),
    with the shoulder span that the marked shoulders then show."""
    j = JOINT_INDEX

    def seen(a: str, b: str) -> np.ndarray:
        return marks[j[a]] - marks[j[b]]
    depth = camera.focal * np.linalg.norm(MODEL[j["chest"]] - MODEL[j["pelvis"]]) / max(
        np.hypot(*seen("chest", "pelvis")), 1e-6)
    hips = 2 * body.HIP_HALF_SPAN * UNIT_M * camera.focal / depth
    cos = np.clip(seen("hip_l", "hip_r")[0] / hips, -1.0, 1.0)
    span = np.clip(abs(seen("shoulder_l", "shoulder_r")[0]) * depth / camera.focal
                   / max(abs(cos), 0.3), *SPAN_RANGE)
    out = []
    for yaw in (np.arccos(cos), -np.arccos(cos)):
        rotation = Rotation.from_matrix(FACING_CAMERA @ Rotation.from_euler("y", yaw).as_matrix())
        centre = camera.rays(marks[j["chest"]]) * depth
        out.append(np.r_[rotation.as_rotvec(), centre - rotation.apply(MODEL[j["chest"]]), span])
    return out


def spanned_fit(marks: np.ndarray, camera: Pinhole, start: np.ndarray) -> np.ndarray:
    """The calibration's parameters (7,) fitted to the marks (16, 2) from ``start``
    (Eq. 9 by Newton's method), the shoulder span kept within SPAN_RANGE: where the
    free fit leaves it, the fit again with the span held at the range's nearer end.

    Seen nearly from the side, the shoulders' image span hardly depends on the span,
    and the free fit's reads anything from 0.14 to 0.51 m from exact projections of
    motion capture 10 degrees from profile (benchmarks/bench_track.py's motions),
    while the pose it fits is sound."""
    free = newton(lambda p: line_distances(p, camera, marks), start)
    if SPAN_RANGE[0] <= free[6] <= SPAN_RANGE[1]:
        return free
    span = float(np.clip(free[6], *SPAN_RANGE))
    return np.r_[newton(lambda p: line_distances(np.r_[p, span], camera, marks), start[:6]), span]


def calibrate(marks: np.ndarray, camera: Pinhole, turn: str | None = None) -> Calibration:
    """The body's pose relative to the camera on frame 0 from its 16 marked joints
    (16, 2), by Newton's method on Eq. 9 over the key triangle's three lines (both
    shoulders and the chest) and, beyond the paper, the three lines of the triangle of
    the hips and the chest (12 equations, 7 unknowns: Gauss-Newton).

    Beyond the paper, the shoulder span is a seventh unknown: real shoulder spans
    differ by +-25% (0.26 to 0.44 m in the CMU skeletons) and the key triangle alone
    reads such a difference as a turn of the body; the hips (a steadier 0.18 to 0.21 m)
    fix the turn. Two upright poses fit equally, turned to either side; ``turn``
    "left" or "right" (the side of CONTRACT.md's orientation, e.g. the "right" of
    forward_right) picks one, else the one with the smaller residual.
    """
    fits = [spanned_fit(marks, camera, p0) for p0 in initial_params(marks, camera)]
    error = [np.abs(line_distances(p, camera, marks)).max() for p in fits]
    if min(error) > MAX_CALIBRATION_ERROR * np.ptp(marks, axis=0).max():
        raise MocapError("cannot calibrate the camera from the marked shoulders, chest and "
                         "hips: they fit no view of a human trunk" + (
                             "; the shoulders and the hips are marked turned opposite ways: "
                             "swap shoulder_l and shoulder_r, or hip_l and hip_r"
                             if turned_apart(marks) else ""))
    if turn in ("left", "right"):
        wrong_side = [(Calibration.from_params(p).yaw > 0) != (turn == "right") for p in fits]
        error = [np.inf if wrong else e for e, wrong in zip(error, wrong_side)]
    return Calibration.from_params(fits[int(np.argmin(error))])


# -- later frames (Eq. 10-11) and the other joints ------------------------------------------

def key_depths(rays: np.ndarray, depths: np.ndarray, sides: np.ndarray) -> np.ndarray:
    """Depths Z_i (3,) of the key joints on their rays (3, 3) of a new frame such that
    the key triangle keeps its side lengths ``sides`` (3,) (Eq. 11 with P_i = Z_i ray_i,
    Eq. 10), by Gauss-Newton from the previous frame's ``depths``. With 2D tracking
    errors the equations have no exact solution: the least-squares one is kept."""
    def residual(z):
        p = z[:, None] * rays
        return np.array([np.linalg.norm(p[i] - p[j]) for i, j in KEY_LINES]) - sides
    return newton(residual, np.asarray(depths, float))


def body_axes(key: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotations body -> pinhole frame given by key joints (..., 3, 3):
    x along the shoulders (right to left), y from the chest up to their middle,
    z = x cross y (forward)."""
    left = key[..., 0, :] - key[..., 1, :]
    left = left / np.linalg.norm(left, axis=-1, keepdims=True)
    up = (key[..., 0, :] + key[..., 1, :]) / 2 - key[..., 2, :]
    up = up - (up * left).sum(-1, keepdims=True) * left
    up = up / np.linalg.norm(up, axis=-1, keepdims=True)
    return np.stack([left, up, np.cross(left, up)], axis=-1)


def triangle_yaw(key: np.ndarray) -> np.ndarray:
    """The facing yaw in degrees (as Calibration.yaw) of key joints (..., 3, 3)."""
    forward = body_axes(key)[..., :, 2]
    return np.degrees(np.arctan2(forward[..., 0], -forward[..., 2]))


def turned_against(key: np.ndarray, turn: str | None) -> bool:
    """Whether key joints (3, 3) face clearly (SIDE_MARGIN_DEG) to the other side than
    ``turn`` ("left" or "right", None: either)."""
    yaw = float(triangle_yaw(key))
    clear = SIDE_MARGIN_DEG < abs(yaw) < 180.0 - SIDE_MARGIN_DEG
    return turn is not None and clear and (yaw > 0) != (turn == "right")


def frame_key_depths(rays: np.ndarray, depths: np.ndarray, sides: np.ndarray,
                     turn: str | None) -> np.ndarray:
    """A frame's key depths (3,) from the previous frame's (Eq. 10-11, ``key_depths``),
    on the side ``turn`` says.

    Beyond the paper: a trunk turning through the frontal view shows two mirror-image
    triangles alike, and the solution nearest the previous frame turns back where the
    body turns on (the 2D sides never quite agree with the calibrated ones). Where the
    triangle found faces the other side than the user's held orientation, the
    solution from its depths mirrored about their mean is taken instead if it faces
    the said side."""
    found = key_depths(rays, depths, sides)
    if not turned_against(found[:, None] * rays, turn):
        return found
    mirror = key_depths(rays, 2 * found.mean() - found, sides)
    return found if turned_against(mirror[:, None] * rays, turn) else mirror


def key_joints(joints2d: np.ndarray, camera: Pinhole, turns: Turns = None,
               before: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """(F, 3, 3) the key joints of every frame: calibration on frame 0 (Eq. 6-9), then
    each frame's depths from the previous frame's (Eq. 10-11, ``frame_key_depths``).

    ``turns``: the side ("left", "right" or None) of each frame's held orientation,
    or one side for every frame. ``before``: (2D joints, key joints) of an earlier
    call on the same clip with the same ``turns``; only the frames whose key joints
    moved in 2D are solved again (all of them when frame 0's did), each from the
    frame before it, as a full solve would start them."""
    rays = camera.rays(joints2d[:, KEY])
    held = [turns] * len(rays) if turns is None or isinstance(turns, str) else list(turns)
    depths, sides = calibrate(joints2d[0], camera, held[0]).key_triangle()
    redo = np.ones(len(rays), bool)
    if before is not None and before[0].shape == joints2d.shape:
        moved = (before[0][:, KEY] != joints2d[:, KEY]).any(axis=(1, 2))
        redo = redo if moved[0] else moved
    out = np.empty((len(rays), 3, 3))
    for f, (frame_rays, turn) in enumerate(zip(rays, held)):
        if redo[f]:
            depths = frame_key_depths(frame_rays, depths, sides, turn)
            out[f] = depths[:, None] * frame_rays
        else:
            out[f] = before[1][f]
            depths = out[f, :, 2]
    return out


def measured_lengths(joints2d: np.ndarray, depth: np.ndarray, camera: Pinhole) -> np.ndarray:
    """(13,) bone lengths (metres) measured over a clip: a percentile
    (LENGTH_PERCENTILES) of each bone's image length at the body's depth ``depth``
    (F,), both sides of a pair pooled; the metric scale is the model key triangle's.
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
    tracked 2D, every clip better; the 90th percentile overshoots: 76.4)."""
    ends = joints2d[:, np.array(BONES)]                                     # (F, 13, 2, 2)
    seen = np.linalg.norm(ends[:, :, 1] - ends[:, :, 0], axis=-1) * depth[:, None] / camera.focal
    out = np.empty(len(BONES))
    out[list(HIP_BONES)] = body.HIP_HALF_SPAN * UNIT_M
    for group, percentile in zip(BONE_PAIRS, LENGTH_PERCENTILES):
        out[list(group)] = np.percentile(seen[:, list(group)], percentile)
    return out


def trunk_joints(key: np.ndarray, rays: np.ndarray, lengths: np.ndarray,
                 fixed: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) the key joints and the trunk's (neck, head top, pelvis, hips), each
    on its ray at the root nearer the model trunk carried rigidly by the key
    triangle, or at the other root where that gives the head or the torso the
    user's foreshortening ``fixed`` (F, 10) (+1 toward, -1 away, 0 not said)."""
    joints = np.zeros(rays.shape)
    joints[:, KEY] = key
    axes = body_axes(key)
    frames = np.arange(len(key))
    for (a, b), length in list(zip(BONES, lengths))[:TORSO_BONES]:
        roots = ray_roots(joints[:, a], rays[:, b], length)                    # (F, 2, 3)
        guess = joints[:, a] + axes @ (MODEL[b] - MODEL[a])
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
                lengths: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) joints in the pinhole frame (metres) from 2D joints (F, 16, 2): the
    key joints turned to ``turns`` (``key_joints``), then the others (``place_joints``)."""
    return place_joints(joints2d, key_joints(joints2d, camera, turns), camera, lengths)


def place_joints(joints2d: np.ndarray, key: np.ndarray, camera: Pinhole,
                 lengths: np.ndarray | None = None, fixed: np.ndarray | None = None) -> np.ndarray:
    """(F, 16, 3) every joint from the key joints ``key`` (F, 3, 3) centre to fringe at
    their bone ``lengths`` (default: ``measured_lengths``), each limb's and the
    trunk's depth choices kept to the user's foreshortening ``fixed`` (F, 10) where
    given (+1 toward, -1 away, 0 not said)."""
    if lengths is None:
        lengths = measured_lengths(joints2d, key[:, :, 2].mean(axis=1), camera)
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
