"""The exported skeleton: the bone names and hierarchy animation tools expect (Mixamo's, most BVH
libraries': Hips, Spine, Spine1, Neck, Head, Left/Right Shoulder, Arm, ForeArm, Hand, UpLeg, Leg,
Foot, ToeBase), its T-pose rest (facing +z, y up, left at +x, arms out) and the rotations posing it
as the contract body. Offsets: metres, parent's frame, symmetric; ``*_End`` End Sites never rotate."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from mocap.body import BODY_HEIGHT, BODY_HEIGHT_M, JOINTS

UNIT_M = BODY_HEIGHT_M / BODY_HEIGHT
# Proportions of the parts the contract body lacks, model units (of 175; anthropometric
# tables: hand 0.108 of body height, ankle height 0.039, ankle to ball of foot 0.1 of it
# forward, toes 0.04)
HAND, ANKLE_HEIGHT, BALL_FORWARD, TOES = 19.0, 7.0, 14.0, 6.0
SPINE_AT = 0.2  # Spine: this fraction of the way from the pelvis to the chest
HEAD_AT = 0.4  # Head (the skull's base): this fraction from the neck to the head top

_SIDES = {"Left": "l", "Right": "r"}
_X = {"l": np.array([1.0, 0.0, 0.0]), "r": np.array([-1.0, 0.0, 0.0])}
_UP, _DOWN = np.array([0.0, 1.0, 0.0]), np.array([0.0, -1.0, 0.0])


def _tree() -> list[tuple[str, str | None]]:
    """(bone, parent) depth-first: a parent before its subtree (a BVH HIERARCHY's order)."""
    out: list[tuple[str, str | None]] = [("Hips", None)]
    for side in _SIDES:
        chain = [f"{side}UpLeg", f"{side}Leg", f"{side}Foot", f"{side}ToeBase", f"{side}Toe_End"]
        out += list(zip(chain, ["Hips"] + chain[:-1]))
    spine = ["Spine", "Spine1", "Neck", "Head", "Head_End"]
    out += list(zip(spine, ["Hips"] + spine[:-1]))
    for side in _SIDES:
        chain = [f"{side}Shoulder", f"{side}Arm", f"{side}ForeArm", f"{side}Hand", f"{side}Hand_End"]
        out += list(zip(chain, ["Spine1"] + chain[:-1]))
    return out


BONES: tuple[str, ...] = tuple(b for b, _ in _tree())
BONE_INDEX = {b: i for i, b in enumerate(BONES)}
PARENTS = np.array([BONE_INDEX[p] if p else -1 for _, p in _tree()])
END_SITE = np.array([b.endswith("_End") for b in BONES])
_CONTRACT = {"pelvis": "Hips", "chest": "Spine1", "neck": "Neck", "head_top": "Head_End"} | {
    f"{j}_{s}": f"{side}{bone}"
    for side, s in _SIDES.items()
    for j, bone in (
        ("shoulder", "Arm"),
        ("elbow", "ForeArm"),
        ("wrist", "Hand"),
        ("hip", "UpLeg"),
        ("knee", "Leg"),
        ("ankle", "Foot"),
    )
}
# where each contract joint is among the bones
JOINT_BONES = np.array([BONE_INDEX[_CONTRACT[j]] for j in JOINTS])

# frame bones: (axis 0 = x / 1 = y that points exactly from bone to a point, that
# point, the two points whose direction the other axis leans toward)
_FRAMES = {
    "Hips": (0, "hip_l", ("pelvis", "chest")),
    "Spine": (1, "chest", ("hip_r", "hip_l")),
    "Spine1": (1, "neck", ("shoulder_r", "shoulder_l")),
}
# swing bones: the point the bone turns toward, and its rest direction
_SWINGS = {"Neck": ("head_top", _UP)} | {
    f"{side}{bone}": (f"{target}_{s}", rest)
    for side, s in _SIDES.items()
    for bone, target, rest in (
        ("Shoulder", "shoulder", _X[s]),
        ("Arm", "elbow", _X[s]),
        ("ForeArm", "wrist", _X[s]),
        ("UpLeg", "knee", _DOWN),
        ("Leg", "ankle", _DOWN),
    )
}
_FEET = ("LeftFoot", "RightFoot")
# bones placed by the proportions alone (in the bone's parent's frame, model units)
_FIXED = (
    {f"{side}ToeBase": np.array([0.0, -ANKLE_HEIGHT, BALL_FORWARD]) for side in _SIDES}
    | {f"{side}Toe_End": np.array([0.0, 0.0, TOES]) for side in _SIDES}
    | {f"{side}Hand_End": _X[s] * HAND for side, s in _SIDES.items()}
)
# bones that lie along their parent's rest direction (the parent points at them)
_ALONG = {"Spine1", "Neck", "Head", "Head_End"} | {
    f"{side}{bone}" for side in _SIDES for bone in ("Arm", "ForeArm", "Hand", "Leg", "Foot")
}


def rest_direction(bone: str) -> np.ndarray:
    """The direction a bone points in the T-pose rest (toward its child)."""
    if bone in _SWINGS:
        return _SWINGS[bone][1]
    side = next((s for name, s in _SIDES.items() if bone.startswith(name)), None)
    return _X[side] if side and "Hand" in bone else _UP


def landmarks(joints: np.ndarray) -> dict[str, np.ndarray]:
    """Every bone's place (K, 3) and the contract joints' from pelvis-relative contract joints
    (K, 16, 3); hands, feet and toes absent (the proportions place them)."""
    at = {j: joints[:, i] for i, j in enumerate(JOINTS)}
    at |= {bone: at[j] for j, bone in _CONTRACT.items()}
    at["Spine"] = at["pelvis"] + SPINE_AT * (at["chest"] - at["pelvis"])
    at["Head"] = at["neck"] + HEAD_AT * (at["head_top"] - at["neck"])
    at["LeftShoulder"] = at["RightShoulder"] = (at["shoulder_l"] + at["shoulder_r"]) / 2
    return at


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Normalise along the last axis; (near) zero vectors become ``fallback``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), fallback)


def _frame(exact: np.ndarray, lean: np.ndarray, axis: int) -> Rotation:
    """Rotations whose column ``axis`` (0 x, 1 y) points along ``exact`` (K, 3), the other x/y column in
    the plane of ``exact`` and ``lean``; degenerate directions fall back to the rest axes."""
    eye = np.eye(3)
    other = 1 - axis
    a = _unit(exact, eye[axis])
    rest_other = _unit(eye[other] - (a @ eye[other])[:, None] * a, eye[2])
    b = _unit(lean - (a * lean).sum(-1, keepdims=True) * a, rest_other)
    cols = [a, b] if axis == 0 else [b, a]
    return Rotation.from_matrix(np.stack([*cols, np.cross(cols[0], cols[1])], axis=-1))


def swing(rest: np.ndarray, direction: np.ndarray) -> Rotation:
    """The smallest rotations taking the unit ``rest`` onto ``direction`` (K, 3); a
    zero direction gives the identity, an opposite one a half turn about a normal."""
    d = _unit(direction, rest)
    cross = np.cross(rest, d)
    sin, cos = np.linalg.norm(cross, axis=-1), d @ rest
    perpendicular = _unit(np.cross(rest, np.eye(3)[np.argmin(np.abs(rest))]), np.eye(3)[0])
    axis = np.where((sin > 1e-12)[:, None], cross / np.maximum(sin, 1e-12)[:, None], perpendicular)
    return Rotation.from_rotvec(axis * np.arctan2(sin, cos)[:, None])


def heading(hips: Rotation) -> Rotation:
    """The turn about the vertical that faces +z where the hips face (their z axis
    laid level); a body lying face up or down keeps the rest heading."""
    forward = hips.apply([0.0, 0.0, 1.0]) * [1.0, 0.0, 1.0]
    forward = _unit(forward, np.array([0.0, 0.0, 1.0]))
    return Rotation.from_rotvec(np.arctan2(forward[:, 0], forward[:, 2])[:, None] * _UP)


def global_rotation(bone: str, at: dict[str, np.ndarray], parent: Rotation, hips: Rotation | None) -> Rotation:
    """A bone's rotation in the world from the landmarks ``at`` and its parent's."""
    if bone in _FRAMES:
        axis, target, (a, b) = _FRAMES[bone]
        return _frame(at[target] - at[bone], at[b] - at[a], axis)
    if bone in _SWINGS:
        target, rest = _SWINGS[bone]
        return parent * swing(rest, parent.inv().apply(at[target] - at[bone]))
    if bone in _FEET:
        return heading(hips)
    return parent


def pose_rotations(joints: np.ndarray, offsets: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Local rotations (K, len(BONES), 4; x y z w) posing the skeleton as pelvis-relative contract
    joints (K, 16, 3), and each bone's vector in its parent's frame (K, len(BONES), 3; NaN for bones
    placed by proportion). With ``offsets`` each bone turns from where the fixed bones put it."""
    at = landmarks(joints)
    glob: list[Rotation] = []
    local = np.empty((len(joints), len(BONES), 4))
    vectors = np.full((len(joints), len(BONES), 3), np.nan)
    for b, name in enumerate(BONES):
        p = PARENTS[b]
        parent = glob[p] if p >= 0 else Rotation.identity(len(joints))
        if p >= 0 and name in at:
            vectors[:, b] = parent.inv().apply(at[name] - at[BONES[p]])
        if offsets is not None and p >= 0:
            at[name] = at[BONES[p]] + parent.apply(offsets[b])
        rot = global_rotation(name, at, parent, glob[0] if glob else None)
        glob.append(rot)
        local[:, b] = (parent.inv() * rot).as_quat()
    return local, vectors


def clip_offsets(vectors: np.ndarray) -> np.ndarray:
    """(len(BONES), 3) one symmetric set of offsets from keyframe vectors (K, len(BONES), 3): median
    length along the parent's rest direction where a bone continues it, else the median vector."""
    offsets = np.zeros((len(BONES), 3))
    for b, name in enumerate(BONES):
        p = PARENTS[b]
        if name in _FIXED:
            offsets[b] = _FIXED[name] * UNIT_M
        elif p >= 0:
            v = vectors[:, b]
            real = v[np.linalg.norm(v, axis=-1) > 1e-9]
            v = real if len(real) else v
            offsets[b] = (
                rest_direction(BONES[p]) * np.median(np.linalg.norm(v, axis=-1))
                if name in _ALONG
                else np.median(v, axis=0)
            )
    return symmetric(offsets)


def symmetric(offsets: np.ndarray) -> np.ndarray:
    """Offsets with each Left bone the mirror (x negated) of its Right twin, their mean; middle x = 0."""
    out = offsets.copy()
    mirror = np.array([-1.0, 1.0, 1.0])
    for b, name in enumerate(BONES):
        if name.startswith("Left"):
            r = BONE_INDEX["Right" + name[4:]]
            out[b] = (offsets[b] + offsets[r] * mirror) / 2
            out[r] = out[b] * mirror
        elif not name.startswith("Right"):
            out[b, 0] = 0.0
    return out


def forward_kinematics(offsets: np.ndarray, rotations: np.ndarray) -> np.ndarray:
    """(F, len(BONES), 3) positions relative to the Hips from offsets (len(BONES), 3) and
    local rotations (F, len(BONES), 4)."""
    glob: list[Rotation] = []
    pos = np.zeros((len(rotations), len(BONES), 3))
    for b in range(len(BONES)):
        local = Rotation.from_quat(rotations[:, b])
        p = PARENTS[b]
        if p < 0:
            glob.append(local)
        else:
            pos[:, b] = pos[:, p] + glob[p].apply(offsets[b])
            glob.append(glob[p] * local)
    return pos


def rest_positions(offsets: np.ndarray) -> np.ndarray:
    """(len(BONES), 3) the T-pose: every bone's position with every rotation identity."""
    return forward_kinematics(offsets, np.tile([0.0, 0.0, 0.0, 1.0], (1, len(BONES), 1)))[0]
