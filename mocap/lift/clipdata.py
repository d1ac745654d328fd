"""What the clip-level 3D solve reads (``ClipArrays``), how much each of its terms may be off
(``Weights``), and the body it poses: bone classes of one length per clip (left = right), the
clip's lengths, the per-frame start pose and a pose's depths flipped to given signs.

Poses here are model units (body.LENGTH), x right, y up, z toward the camera, about each frame's
observed 2D pelvis; ``to_contract`` gives the contract's metres about the 3D pelvis."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap.body import (
    CHEST_FRACTION,
    HIP_HALF_SPAN,
    JOINT_INDEX,
    JOINTS,
    LENGTH,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    SHOULDER_DROP,
    SHOULDER_HALF_SPAN,
    segment_kind,
)
from mocap.camera import Pinhole
from mocap.lift.taylor import UNIT_M, lift_pose, runs

# seconds: Gaussian sigma of the projected bone lengths over time before the person model's depths
# are added to them
LENGTH_SMOOTH_S = 0.08
# below this |cos yaw| the hip and shoulder widths are not read off the image
LEAST_WIDTH = 0.5  # of the body model's hip and shoulder widths: a fit that sees none reads no less
FRONTAL_SPREAD = 0.5

_J = JOINT_INDEX
PELVIS = _J["pelvis"]
N_JOINTS = len(JOINTS)

_TORSO = float(LENGTH[SEGMENT_INDEX["torso"]])
# bone classes, one length each per clip: the body model's (mocap.body) where nothing tells
CLASS_LENGTH: dict[str, float] = {
    "spine": CHEST_FRACTION * _TORSO,
    "upper_spine": (1 - CHEST_FRACTION) * _TORSO,
    "torso": _TORSO,
    "head": float(LENGTH[SEGMENT_INDEX["head"]]),
    "collar": float(np.hypot(SHOULDER_HALF_SPAN, SHOULDER_DROP)),
    "shoulders": 2 * SHOULDER_HALF_SPAN,
    "hip": HIP_HALF_SPAN,
    **{k: float(LENGTH[SEGMENT_INDEX[k + "_l"]]) for k in ("upper_arm", "lower_arm", "upper_leg", "lower_leg")},
}
CLASSES: tuple[str, ...] = tuple(CLASS_LENGTH)
_LIMB_BONES = (("shoulder", "elbow", "upper_arm"), ("elbow", "wrist", "lower_arm"))
_LIMB_BONES += (("hip", "knee", "upper_leg"), ("knee", "ankle", "lower_leg"))
# (proximal joint, distal joint, class): the 10 segments among them
BONES: tuple[tuple[str, str, str], ...] = (
    ("pelvis", "chest", "spine"),
    ("chest", "neck", "upper_spine"),
    ("pelvis", "neck", "torso"),
    ("neck", "head_top", "head"),
    ("neck", "shoulder_l", "collar"),
    ("neck", "shoulder_r", "collar"),
    ("shoulder_r", "shoulder_l", "shoulders"),
    ("pelvis", "hip_l", "hip"),
    ("pelvis", "hip_r", "hip"),
    *((f"{a}_{s}", f"{b}_{s}", kind) for s in "lr" for a, b, kind in _LIMB_BONES),
)
BONE_FROM = np.array([_J[a] for a, _, _ in BONES])
BONE_TO = np.array([_J[b] for _, b, _ in BONES])
BONE_CLASS = np.array([CLASSES.index(k) for _, _, k in BONES])
TRUNK_CLASSES = ("spine", "upper_spine", "torso", "collar", "shoulders", "hip")
TRUNK_BONE = np.array([k in TRUNK_CLASSES for _, _, k in BONES])
SEGMENT_CLASS = np.array([CLASSES.index(segment_kind(s)) for s in SEGMENT_NAMES])
# hinges (proximal, middle, distal, axis from, axis to, bend): knees bend so that
# (thigh x shank) . (hip_l - hip_r) >= 0, elbows so that (upper x lower) . (shoulder_l - shoulder_r) <= 0
HINGES = tuple((f"hip_{s}", f"knee_{s}", f"ankle_{s}", "hip_l", "hip_r", 1.0) for s in "lr") + tuple(
    (f"shoulder_{s}", f"elbow_{s}", f"wrist_{s}", "shoulder_l", "shoulder_r", -1.0) for s in "lr"
)


@dataclass(frozen=True)
class Weights:
    """Each term's allowed error, in body heights unless said (any image size alike); ``hinge_*`` on
    the dimensionless (a x b) . axis / (|a| |b| |axis|)."""

    sigma_2d: float = 0.03  # 2D joint at confidence 1
    sigma_placed: float = 0.005  # a joint the user placed (an override)
    sigma_bone: float = 0.005  # limb bone length
    sigma_trunk: float = 0.012  # trunk distances (the spine bends a little)
    accel: float = 15.0  # m/s^2: a joint's typical acceleration about the pelvis
    sigma_depth: float = 0.05  # the person model's |dZ|
    sigma_yaw: float = 0.4  # of the hip and shoulder widths: their depths from the yaw
    sigma_length: float = 0.1  # relative: the clip's lengths about their first estimate
    sigma_held: float = 0.0005  # the user's held signs (one-sided)
    sigma_guess: float = 0.05  # a guessed sign where the person model gives no depth
    sign_margin: float = 0.1  # |dZ| / length a held or guessed sign asks for
    hinge_knee: float = 0.05  # knees bend one way
    hinge_elbow: float = 0.2  # elbows too, looser (the upper arm's twist is not modelled)
    loss_scale: float = 2.0  # sigmas where the robust (soft-L1) rows turn from square to linear


# ClipArrays' per-frame arrays
PER_FRAME = ("joints2d", "px_per_unit", "yaw", "signs", "depths", "held", "confidence", "placed")


@dataclass(frozen=True, eq=False)
class ClipArrays:
    """What the solve reads, per frame: ``joints2d`` (F, 16, 2) anatomical pixels; ``px_per_unit``
    (F,); ``yaw`` (F,) degrees; ``signs`` (F, 10) +1 toward, -1 away (the first guess); ``lengths``
    (10,) the lift's segment lengths (model units, the unit of ``depths``); ``depths`` (F, 10) a
    person model's |dZ| or NaN; ``held`` (F, 10) the user's signs or 0; ``confidence`` (F, 16) in
    [0, 1]; ``placed`` (F, 16) bool, joints the user placed; ``fps``; ``camera`` the pinhole the video
    was filmed with, where its focal length is known (None: scaled orthography, as the paper); the solve
    sees through it where ``depths`` are given: without them the lengths are read off the 2D alone, and a
    pinhole lets the 2D's noise move joints in depth (its depth cue is a few units' shift of the 2D)."""

    joints2d: np.ndarray
    px_per_unit: np.ndarray
    yaw: np.ndarray
    signs: np.ndarray
    lengths: np.ndarray
    depths: np.ndarray | None = None
    held: np.ndarray | None = None
    confidence: np.ndarray | None = None
    placed: np.ndarray | None = None
    fps: float = 25.0
    camera: Pinhole | None = None

    @classmethod
    def of(cls, inputs, fps: float, confidence=None, placed=None, camera: Pinhole | None = None) -> "ClipArrays":
        """From a ``mocap.lift.inputs.Inputs`` (read by attribute)."""
        return cls(
            inputs.joints2d,
            inputs.px_per_unit,
            inputs.yaw,
            inputs.signs,
            inputs.lengths,
            inputs.depths,
            inputs.held,
            confidence,
            placed,
            fps,
            camera,
        )

    def frames(self, stretch: slice) -> "ClipArrays":
        """The arrays of frames ``stretch`` alone."""
        cut = {name: None if (a := getattr(self, name)) is None else a[stretch] for name in PER_FRAME}
        return replace(self, **cut)

    @property
    def person(self) -> np.ndarray:
        """(F,) bool: frames with every joint and the scale."""
        return np.isfinite(self.joints2d).all(axis=(1, 2)) & np.isfinite(self.px_per_unit)

    def held_signs(self) -> np.ndarray:
        """(F, 10) the user's signs where held, 0 elsewhere."""
        return np.zeros(np.shape(self.signs), int) if self.held is None else np.asarray(self.held, int)

    def held_or_guessed(self) -> np.ndarray:
        """(F, 10) the user's signs where held, else the first guess."""
        return self.signs if self.held is None else np.where(self.held != 0, self.held, self.signs)

    def changed_frames(self, before: "ClipArrays", names: tuple[str, ...] = PER_FRAME) -> np.ndarray | None:
        """(F,) bool: frames whose arrays ``names`` differ from ``before``'s; None when the person frames
        differ (the lengths are the solution's and are not compared)."""
        person = self.person
        if len(person) != len(before.person) or not np.array_equal(person, before.person):
            return None
        changed = np.zeros(len(person), bool)
        for name in names:
            a, b = getattr(self, name), getattr(before, name)
            if (a is None) != (b is None):
                return None
            if a is not None:
                same = (a == b) | (np.isnan(a) & np.isnan(b)) if a.dtype.kind == "f" else a == b
                changed |= ~same.reshape(len(person), -1).all(axis=1)
        return changed & person


def clip_bone_lengths(clip: ClipArrays) -> np.ndarray:
    """(len(CLASSES),) model units. Torso, head and limbs: the lift's segment lengths (``clip.lengths``,
    a pair's mean; the spine split at CHEST_FRACTION), at least what the person model's depths imply
    (median of sqrt(seen^2 + dZ^2), the seen lengths smoothed over LENGTH_SMOOTH_S); hip and shoulder
    widths: their projection over |cos yaw| where the body is turned less than 60 degrees from the
    camera or its back; the collar from the shoulders and the neck's height above them; the body
    model's where nothing tells."""
    person = clip.person
    out = np.array([CLASS_LENGTH[c] for c in CLASSES])
    if not person.any():
        return out
    j = clip.joints2d[person] / clip.px_per_unit[person, None, None]
    seen = np.linalg.norm(j[:, BONE_TO] - j[:, BONE_FROM], axis=-1)  # (F, B)
    sigma = LENGTH_SMOOTH_S * clip.fps
    seen = np.concatenate([gaussian_filter1d(seen[r], sigma, axis=0, mode="nearest") for r in runs(person[person])])
    depth = np.full(seen.shape, np.nan)
    if clip.depths is not None:
        bone_of = {(a, b): k for k, (a, b) in enumerate(zip(BONE_FROM, BONE_TO))}
        for k, (a, b) in enumerate(SEGMENT_JOINTS):
            depth[:, bone_of[a, b]] = clip.depths[person, k]
    lift = np.asarray(clip.lengths, float)
    for name in ("torso", "head", "upper_arm", "lower_arm", "upper_leg", "lower_leg"):
        out[CLASSES.index(name)] = lift[[k for k, s in enumerate(SEGMENT_NAMES) if segment_kind(s) == name]].mean()
    out[CLASSES.index("spine")] = CHEST_FRACTION * out[CLASSES.index("torso")]
    out[CLASSES.index("upper_spine")] = (1 - CHEST_FRACTION) * out[CLASSES.index("torso")]
    for k, name in enumerate(CLASSES):
        cols = BONE_CLASS == k
        if name in TRUNK_CLASSES and name not in ("spine", "upper_spine", "torso"):
            continue
        with_depth = np.hypot(seen[:, cols], depth[:, cols]).ravel()
        if np.isfinite(with_depth).sum() > 5:
            out[k] = max(out[k], float(np.nanmedian(with_depth)))
    facing = np.abs(np.cos(np.radians(clip.yaw[person])))
    frontal = np.isfinite(facing) & (facing > FRONTAL_SPREAD)
    if frontal.any():
        for name, (a, b), half in (("hip", ("hip_r", "hip_l"), 0.5), ("shoulders", ("shoulder_r", "shoulder_l"), 1.0)):
            width = half * float(np.median(np.abs(j[frontal, _J[b], 0] - j[frontal, _J[a], 0]) / facing[frontal]))
            out[CLASSES.index(name)] = max(width, LEAST_WIDTH * CLASS_LENGTH[name])
    drop = np.median(j[:, [_J["shoulder_l"], _J["shoulder_r"]], 1].mean(axis=1) - j[:, _J["neck"], 1])
    out[CLASSES.index("collar")] = float(np.hypot(out[CLASSES.index("shoulders")] / 2, max(drop, 0.0)))
    return out


def depth_scale(clip: ClipArrays, bones: np.ndarray) -> float:
    """The factor from ``clip.depths``' units (the lift's ``clip.lengths``) to ``bones``'."""
    ratio = bones[SEGMENT_CLASS] / np.maximum(np.asarray(clip.lengths, float), 1e-9)
    return float(np.median(ratio))


def start_pose(clip: ClipArrays, bones: np.ndarray) -> np.ndarray:
    """(F, 16, 3) each frame's own lift (Eq. 4-5) at the clip's lengths ``bones`` and the held or
    guessed signs, the person model's depths where it has them; NaN without a person."""
    out = np.full(clip.joints2d.shape[:2] + (3,), np.nan)
    spans = (bones[CLASSES.index("shoulders")] / 2, bones[CLASSES.index("hip")])
    scale = depth_scale(clip, bones)
    signs = clip.held_or_guessed()
    for i in np.flatnonzero(clip.person):
        seen = None if clip.depths is None else clip.depths[i] * scale
        yaw = clip.yaw[i] if np.isfinite(clip.yaw[i]) else 0.0
        pose = lift_pose(clip.joints2d[i], clip.px_per_unit[i], yaw, signs[i], bones[SEGMENT_CLASS], spans, seen)
        out[i] = pose / UNIT_M
    return out


def to_contract(model: np.ndarray) -> np.ndarray:
    """(F, 16, 3) metres about the pelvis of model-unit poses (F, 16, 3)."""
    return (model - model[:, [PELVIS]]) * UNIT_M


def with_signs(model: np.ndarray, signs: np.ndarray) -> np.ndarray:
    """(F, 16, 3) ``model`` with each segment's depth step turned to ``signs`` (F, 10) (its |dZ|
    kept), the joints hanging from it moved along, the trunk first."""
    out = model.copy()
    for k, (_, distal) in enumerate(SEGMENT_JOINTS):
        dz = out[:, distal, 2] - out[:, SEGMENT_JOINTS[k, 0], 2]
        shift = np.where(np.sign(dz) * signs[:, k] < 0, -2.0 * dz, 0.0)
        for j, share in _hanging(distal):
            out[:, j, 2] += share * shift
    return out


def _hanging(joint: int) -> list[tuple[int, float]]:
    """(joint, share of a move of ``joint``) for ``joint`` and the joints below it: the chest moves
    with the neck by CHEST_FRACTION, the head and arms fully."""
    name = JOINTS[joint]
    if name == "neck":
        arms = [(_J[f"{p}_{s}"], 1.0) for s in "lr" for p in ("shoulder", "elbow", "wrist")]
        return [(joint, 1.0), (_J["chest"], CHEST_FRACTION), (_J["head_top"], 1.0)] + arms
    below = {"elbow": "wrist", "knee": "ankle"}
    base, _, side = name.partition("_")
    return [(joint, 1.0)] + ([(_J[f"{below[base]}_{side}"], 1.0)] if base in below else [])
