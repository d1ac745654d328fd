"""The 10-cylinder body model of the silhouette paper (section 3.1, Table 1); names as in CONTRACT.md.

Lengths and widths are model units of a 175-unit body; Table 1's "radii" are read as widths.
2D: pixels, x right, y down; a segment's *angle* is the image direction from its proximal to its
distal joint, degrees counter-clockwise with y up (90 up, 270 down), as in Table 1's joint limits.
In the 2D fit "left" is image left (section 3.3); anatomical sides are decided in the 3D lift.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

JOINTS: tuple[str, ...] = (
    "head_top",
    "neck",
    "chest",
    "pelvis",
    "shoulder_l",
    "elbow_l",
    "wrist_l",
    "shoulder_r",
    "elbow_r",
    "wrist_r",
    "hip_l",
    "knee_l",
    "ankle_l",
    "hip_r",
    "knee_r",
    "ankle_r",
)
JOINT_INDEX: dict[str, int] = {name: i for i, name in enumerate(JOINTS)}

# segment -> (proximal joint, distal joint), in the contract's order
SEGMENTS: dict[str, tuple[str, str]] = {
    "torso": ("pelvis", "neck"),
    "head": ("neck", "head_top"),
    "upper_arm_l": ("shoulder_l", "elbow_l"),
    "lower_arm_l": ("elbow_l", "wrist_l"),
    "upper_arm_r": ("shoulder_r", "elbow_r"),
    "lower_arm_r": ("elbow_r", "wrist_r"),
    "upper_leg_l": ("hip_l", "knee_l"),
    "lower_leg_l": ("knee_l", "ankle_l"),
    "upper_leg_r": ("hip_r", "knee_r"),
    "lower_leg_r": ("knee_r", "ankle_r"),
}
SEGMENT_NAMES: tuple[str, ...] = tuple(SEGMENTS)
SEGMENT_INDEX: dict[str, int] = {name: i for i, name in enumerate(SEGMENT_NAMES)}

BODY_HEIGHT = 175.0
STANDING_PERCENTILE = 90  # of a clip's head-to-feet heights: its standing height (bends are shorter)
BODY_HEIGHT_M = 1.75

# Table 1's lengths, but the arm is 31 + 27 (Table 1: 25 + 35, its lower arm reaching into
# the hand): people's elbows sit lower and their arms end at the wrist.
_KIND_LENGTH = {"head": 25.0, "torso": 52.0, "upper_arm": 31.0, "lower_arm": 27.0, "upper_leg": 46.0, "lower_leg": 52.0}
_KIND_WIDTH = {"head": 20.0, "torso": 40.0, "upper_arm": 10.0, "lower_arm": 10.0, "upper_leg": 20.0, "lower_leg": 20.0}


def segment_kind(segment: str) -> str:
    """'upper_arm_l' -> 'upper_arm'; 'torso' -> 'torso'."""
    return segment[:-2] if segment.endswith(("_l", "_r")) else segment


SIDE_WORDS = {"l": "left", "r": "right"}  # the performer's own sides


def sided_label(name: str) -> str:
    """A joint's or segment's name for people: 'upper_arm_l' -> 'left upper arm'; 'torso' -> 'torso'."""
    if name.endswith(("_l", "_r")):
        return f"{SIDE_WORDS[name[-1]]} {name[:-2].replace('_', ' ')}"
    return name.replace("_", " ")


def segment_label(segment: str) -> str:
    """A segment's name for people, as the app's buttons and the review's reasons say it: 'left upper arm'."""
    return sided_label(segment)


LENGTH = np.array([_KIND_LENGTH[segment_kind(s)] for s in SEGMENT_NAMES])
WIDTH = np.array([_KIND_WIDTH[segment_kind(s)] for s in SEGMENT_NAMES])

# The torso's cross-section is an ellipse 40 wide and this deep, so its seen width tells how far
# the body is turned (section 3.4's "horizontal foreshortening of the torso"); other segments are round.
TORSO_DEPTH = 22.0

# Where the limbs attach, in model units from the torso axis (not in Table 1):
# arms hang beside the 40-wide torso, legs side by side under it.
SHOULDER_HALF_SPAN = 18.0
HIP_HALF_SPAN = 10.0
# shoulder joints this far below the neck (the torso's top), as in people and mocap skeletons
SHOULDER_DROP = 6.0
# Hip joints this far (model units) below where Table 1's thighs attach, along the trunk, as in
# people; the fit keeps Table 1 and moves the joints it reports (``reported_joints``).
HIP_BELOW_THIGH_TOPS = 4.0
# The sole below the ankle (ankle height): the 2D fit continues each lower leg this far so that
# the ankle is not put at the silhouette's sole; no contract joint names it.
FOOT_LENGTH = 7.0
# chest: the point on the pelvis->neck axis at this fraction (apex of the key triangle)
CHEST_FRACTION = 0.6

# Table 1 (c): joint limits as absolute image angles in degrees.
ANGLE_LIMITS: dict[str, tuple[float, float]] = {
    "torso": (45.0, 135.0),  # waist
    "head": (45.0, 135.0),  # neck
    "upper_leg_l": (240.0, 300.0),
    "upper_leg_r": (240.0, 300.0),
}

# -- the skeleton as data (VideoPose3D style: a parents array, left and right joints) --

# Every joint's parent (the contract's joints; the pelvis is the root).
JOINT_PARENT: dict[str, str | None] = {
    "head_top": "neck",
    "neck": "chest",
    "chest": "pelvis",
    "pelvis": None,
    "shoulder_l": "chest",
    "elbow_l": "shoulder_l",
    "wrist_l": "elbow_l",
    "shoulder_r": "chest",
    "elbow_r": "shoulder_r",
    "wrist_r": "elbow_r",
    "hip_l": "pelvis",
    "knee_l": "hip_l",
    "ankle_l": "knee_l",
    "hip_r": "pelvis",
    "knee_r": "hip_r",
    "ankle_r": "knee_r",
}
JOINT_PARENTS = np.array([JOINT_INDEX[JOINT_PARENT[j]] if JOINT_PARENT[j] else -1 for j in JOINTS])
SIDES = ("l", "r")
SIDE_SIGN = {"l": 1.0, "r": -1.0}  # the performer's left is +x in the body frame
JOINTS_LEFT: tuple[int, ...] = tuple(i for i, j in enumerate(JOINTS) if j.endswith("_l"))
JOINTS_RIGHT: tuple[int, ...] = tuple(i for i, j in enumerate(JOINTS) if j.endswith("_r"))
# Anatomical pairs swapped when mirroring left and right.
LEFT_RIGHT_PAIRS: tuple[tuple[str, str], ...] = tuple((JOINTS[i], JOINTS[i][:-1] + "r") for i in JOINTS_LEFT)
MIRROR_JOINTS = np.arange(len(JOINTS))
MIRROR_JOINTS[list(JOINTS_LEFT)], MIRROR_JOINTS[list(JOINTS_RIGHT)] = JOINTS_RIGHT, JOINTS_LEFT
SEGMENT_OF_BONE: dict[tuple[str, str], str] = {ends: s for s, ends in SEGMENTS.items()}


class Limb(NamedTuple):
    """An arm or a leg: three joints, root (shoulder or hip) to end, and its two segments."""

    kind: str  # "arm" or "leg"
    side: str  # "l" or "r"
    joints: tuple[str, str, str]
    segments: tuple[str, str]


def _limbs() -> tuple[Limb, ...]:
    """Every limb, per side in joint order: two bones down from a sided joint with an unsided parent."""
    out = []
    for side in SIDES:
        for root in JOINTS:
            if root.endswith("_" + side) and not JOINT_PARENT[root].endswith(("_l", "_r")):
                middle = next(j for j in JOINTS if JOINT_PARENT[j] == root)
                end = next(j for j in JOINTS if JOINT_PARENT[j] == middle)
                segments = (SEGMENT_OF_BONE[root, middle], SEGMENT_OF_BONE[middle, end])
                kind = segment_kind(segments[0]).split("_")[1]
                out.append(Limb(kind, side, (root, middle, end), segments))
    return tuple(out)


LIMBS = _limbs()


# each kind of limb's joints, root to end, without their side: "arm" -> (shoulder, elbow, wrist)
LIMB_JOINTS: dict[str, tuple[str, ...]] = {
    one.kind: tuple(j.removesuffix("_" + one.side) for j in one.joints) for one in LIMBS
}
# the legs' joints by index: hips, knees, ankles, left and right in turn
LEG_JOINTS = [JOINT_INDEX[f"{j}_{s}"] for j in LIMB_JOINTS["leg"] for s in SIDES]


def limb(kind: str, side: str) -> Limb:
    """The ``kind`` ("arm" or "leg") limb of ``side`` ("l" or "r")."""
    return next(one for one in LIMBS if one.kind == kind and one.side == side)


def bones_from(known: tuple[str, ...]) -> tuple[tuple[str, str], ...]:
    """(placed joint, joint placed from it) for every contract joint not ``known``,
    through the contract tree: the trunk's first, depth first from the known joints
    (neighbours in joint order), then each limb's from its root, in joint order."""
    limb_joints = {j for one in LIMBS for j in one.joints[1:]}
    placed, out = set(known), []

    def visit(joint: str) -> None:
        for other in JOINTS:
            near = JOINT_PARENT[other] == joint or JOINT_PARENT[joint] == other
            if near and other not in placed and other not in limb_joints:
                placed.add(other)
                out.append((joint, other))
                visit(other)

    for joint in known:
        visit(joint)
    for one in sorted(LIMBS, key=lambda one: JOINT_INDEX[one.joints[0]]):
        out += [one.joints[:2], one.joints[1:]]
    return tuple(out)


# neck = pelvis + NECK_PER_SHOULDER * (shoulder midpoint - pelvis)
NECK_PER_SHOULDER = LENGTH[0] / (LENGTH[0] - SHOULDER_DROP)


def reported_joints(joints: np.ndarray, px_per_unit: float) -> np.ndarray:
    """(16, 2) fitted joints as reported: pelvis and hips moved HIP_BELOW_THIGH_TOPS units down the trunk."""
    return _hips_moved(joints, HIP_BELOW_THIGH_TOPS * px_per_unit)


def model_joints(reported: np.ndarray, px_per_unit: float) -> np.ndarray:
    """(16, 2) the inverse of ``reported_joints``: pelvis and hips moved back up the trunk."""
    return _hips_moved(reported, -HIP_BELOW_THIGH_TOPS * px_per_unit)


def _hips_moved(joints: np.ndarray, pixels: float) -> np.ndarray:
    """(16, 2) joints with the pelvis and hips moved ``pixels`` away from the neck."""
    out = np.array(joints, float)
    pelvis, neck = out[JOINT_INDEX["pelvis"]], out[JOINT_INDEX["neck"]]
    down = (pelvis - neck) / max(float(np.linalg.norm(pelvis - neck)), 1e-9)
    out[[JOINT_INDEX[j] for j in ("pelvis", "hip_l", "hip_r")]] += pixels * down
    return out


def torso_width(spread):
    """Seen torso width (model units) for a seen span fraction: W frontal, TORSO_DEPTH in profile."""
    w = WIDTH[SEGMENT_NAMES.index("torso")]
    return np.sqrt(TORSO_DEPTH**2 + (w**2 - TORSO_DEPTH**2) * np.asarray(spread) ** 2)


def spread_for_width(width):
    """The inverse of torso_width: the seen span fraction for a seen torso width."""
    w = WIDTH[SEGMENT_NAMES.index("torso")]
    return np.sqrt(np.clip((np.asarray(width) ** 2 - TORSO_DEPTH**2) / (w**2 - TORSO_DEPTH**2), 0, 1))


def semi_axes(body_height: float) -> np.ndarray:
    """(10, 2) lateral and front-to-back radii of every segment for a body this tall."""
    radii = np.repeat(WIDTH[:, None] / 2, 2, axis=1)
    radii[SEGMENT_NAMES.index("torso"), 1] = TORSO_DEPTH / 2
    return radii * body_height / BODY_HEIGHT


def direction(angle_deg):
    """Unit image vector(s) (x right, y down) for angle(s) measured with y up."""
    a = np.radians(angle_deg)
    return np.stack([np.cos(a), -np.sin(a)], axis=-1)


SEGMENT_JOINTS = np.array([[JOINT_INDEX[a], JOINT_INDEX[b]] for a, b in SEGMENTS.values()])


def segment_endpoints(joints: np.ndarray) -> np.ndarray:
    """(..., 10, 2, D) proximal and distal joint of every segment."""
    return joints[..., SEGMENT_JOINTS, :]


def body_height(joints3d_rest: np.ndarray) -> float:
    """Standing height of a skeleton: head + torso + the mean leg (what the model's 175 units mean)."""
    seg = segment_endpoints(np.asarray(joints3d_rest, dtype=float))
    lengths = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=-1)
    by = dict(zip(SEGMENT_NAMES, lengths))
    legs = (by["upper_leg_l"] + by["lower_leg_l"] + by["upper_leg_r"] + by["lower_leg_r"]) / 2
    return float(by["head"] + by["torso"] + legs)


# -- geometry of a body that both methods read --------------------------------------

ORIENTATIONS: tuple[str, ...] = ("left", "right", "forward_left", "forward_right", "backward_left", "backward_right")
FORESHORTENING: tuple[str, ...] = ("toward", "away")
TOWARD, AWAY = 1, -1
ARM_REST = 0.15  # sine of the upper arms' rest angle out from the sagittal plane


def left_direction(joints: np.ndarray) -> np.ndarray:
    """(..., D) the body's right-to-left direction of joints (..., 16, D): the limbs'
    roots (shoulders, hips), each pair's left minus right, summed."""
    return sum(
        joints[..., JOINT_INDEX[f"{names[0]}_l"], :] - joints[..., JOINT_INDEX[f"{names[0]}_r"], :]
        for names in LIMB_JOINTS.values()
    )


def knee_facing(joints2d: np.ndarray) -> str:
    """ "right" or "left": the image side the knees of 2D joints (F, 16, 2) bend toward (forward)."""
    return "right" if sum(knee_bend(joints2d, side) for side in SIDES).sum() >= 0 else "left"


def knee_bend(joints2d: np.ndarray, side: str) -> np.ndarray:
    """(F,) image-x offset of a knee from its hip-ankle line (knees point forward)."""
    hip, knee, ankle = (joints2d[:, JOINT_INDEX[j]] for j in limb("leg", side).joints)
    along = ankle - hip
    t = np.clip(((knee - hip) * along).sum(-1) / np.maximum((along**2).sum(-1), 1e-9), 0, 1)
    return (knee - hip - t[:, None] * along)[:, 0]


def unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-9)


def limb_penalty(
    upper: np.ndarray, lower: np.ndarray, facing: np.ndarray, left: np.ndarray, side: float, leg: bool
) -> np.ndarray:
    """Joint-limit violation (>= 0) of limbs given as 3D upper/lower vectors (..., 3).

    Legs: thigh at most 30 degrees back, not across the midline, knee bending backward.
    Arms: upper arm not across the midline nor over 60 degrees back, elbow bending forward,
    not outward. Both prefer the sagittal plane (arms hang ARM_REST out from it)."""
    u, l = unit(upper), unit(lower)
    bend = l - (l * u).sum(-1, keepdims=True) * u
    uf, ul = (u * facing).sum(-1), side * (u * left).sum(-1)
    bf, bl = (bend * facing).sum(-1), side * (bend * left).sum(-1)
    if leg:
        ll = side * (l * left).sum(-1)
        return (
            np.maximum(0, -uf - 0.5)
            + np.maximum(0, -ul - 0.25)
            + 0.3 * np.maximum(0, ul - 0.5)
            + np.maximum(0, bf - 0.1)
            + 0.5 * np.maximum(0, np.abs(bl) - 0.3)
            + np.abs(ul)
            + np.abs(ll)
        )
    return (
        np.maximum(0, -ul)
        + 0.5 * np.maximum(0, ul - 0.3)
        + np.maximum(0, -uf - 0.87)
        + 0.5 * np.maximum(0, -bf - 0.1)
        + 0.5 * np.maximum(0, np.abs(bl) - np.maximum(bf, 0))
        + np.abs(ul - ARM_REST)
    )
