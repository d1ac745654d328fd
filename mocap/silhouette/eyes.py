"""What a person model (mocap.person) gives the silhouette method: the silhouette where background subtraction
cannot see (``fused_mask``), and landmarks the 2D fit's searches draw toward (``fit_targets``), renamed from
anatomical to image sides (section 3.3: ``image_sided``); where the landmarks only guess at the body's ends,
the silhouette places them (``crowned``: the head's top, ``soled``: the ankles)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from mocap.body import BODY_HEIGHT, FOOT_LENGTH, JOINT_INDEX, LENGTH, SEGMENT_INDEX, SEGMENTS, model_joints
from mocap.person import SURE, Landmarks
from mocap.silhouette.model2d import Pose2D

PERSON_LEVEL = 0.5  # a person-mask probability from which a pixel is the performer
EDGE_BAND = 0.01  # of the person mask's height: the band outside it where background
# subtraction may add pixels (its edges follow the frame's)
HEAD_REACH = 2.0  # of the landmarks' neck -> head top: how far along it the silhouette's crown is looked for
SOLE_REACH = 3.0  # ankle heights below the ankle: how far along the lower leg its sole is looked for
APART = 0.04  # of the body height: shoulders or hips this far apart in x
# tell the image-left limb from the image-right one
_J = JOINT_INDEX
_PAIRS = {"arm": ("shoulder", "elbow", "wrist"), "leg": ("hip", "knee", "ankle")}
_LIMB_SEGMENTS = {"arm": ("upper_arm", "lower_arm"), "leg": ("upper_leg", "lower_leg")}


def fused_mask(
    classical: np.ndarray, person: np.ndarray, held: np.ndarray | None
) -> tuple[np.ndarray, np.ndarray] | None:
    """The silhouette (uint8 0/255): the person model's mask (probabilities ``person``) grown by the
    ``classical`` (0/255) pixels in an EDGE_BAND around it, not ``held``; and the pixels only the model gave
    (bool). None where its mask is empty."""
    inside = person >= PERSON_LEVEL
    rows = np.flatnonzero(inside.any(axis=1))
    if not len(rows):
        return None
    found = classical > 0
    r = max(1, int(round(EDGE_BAND * (rows[-1] - rows[0] + 1))))
    disk = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * r + 1, 2 * r + 1))
    grown = cv2.dilate(inside.astype(np.uint8), disk) > 0
    if held is not None:
        grown &= ~held
    mask = inside | (grown & found)
    return np.where(mask, 255, 0).astype(np.uint8), inside & ~found


def crowned(landmarks: Landmarks, mask: np.ndarray) -> Landmarks:
    """``landmarks`` with the head's top where the silhouette ``mask`` (uint8, 0/255) ends along the neck -> head
    top line, searched from the line's middle (about the ears) out to HEAD_REACH times its length. A person
    model has no point on the crown: its head top is the ears' line extended by a body's proportions, which
    heads and hair do not keep; the silhouette shows the crown itself. Kept as given where the middle is not on
    the silhouette or the silhouette runs on past the reach (a hand over the head) or out of the frame."""
    neck, top = (landmarks.joints2d[_J[j]] for j in ("neck", "head_top"))
    end = silhouette_end(mask, neck, top, 0.5, HEAD_REACH)
    return landmarks if end is None else moved(landmarks, "head_top", end)


def soled(landmarks: Landmarks, mask: np.ndarray) -> Landmarks:
    """``landmarks`` with each ankle FOOT_LENGTH above where the silhouette ``mask`` ends along its knee -> ankle
    line (the sole under a standing foot), in the landmarks' own scale (``seen_scale``): the ankle is where
    people's ankles are over their soles, whatever a shoe makes of its outline. Searched from the ankle out to
    SOLE_REACH ankle heights; an ankle is kept where it is off the silhouette or the silhouette runs on (a foot
    along the shin, another leg below, the frame's edge)."""
    out, foot = landmarks, FOOT_LENGTH * seen_scale(landmarks.joints2d)
    for side in "lr":
        knee, ankle = (landmarks.joints2d[_J[f"{j}_{side}"]] for j in ("knee", "ankle"))
        shin = max(float(np.hypot(*(ankle - knee))), 1e-9)
        end = silhouette_end(mask, knee, ankle, 1.0, 1.0 + SOLE_REACH * foot / shin)
        if end is not None:
            out = moved(out, f"ankle_{side}", end - foot / shin * (ankle - knee))
    return out


def seen_scale(joints: np.ndarray) -> float:
    """Pixels per model unit of 2D joints (16, 2): the largest of the trunk's and the legs' seen lengths over
    the model's, since turning a segment from the image plane only shortens it."""
    segments = ("torso", "upper_leg_l", "upper_leg_r", "lower_leg_l", "lower_leg_r")
    seen = [np.hypot(*(joints[_J[SEGMENTS[s][1]]] - joints[_J[SEGMENTS[s][0]]])) for s in segments]
    return float(max(length / LENGTH[SEGMENT_INDEX[s]] for s, length in zip(segments, seen)))


def silhouette_end(
    mask: np.ndarray, start: np.ndarray, through: np.ndarray, first: float, last: float
) -> np.ndarray | None:
    """The last pixel of ``mask`` (uint8, 0/255) on the line from ``start`` through ``through``, walked pixel by
    pixel from ``first`` to ``last`` times their distance: None where the walk starts off the silhouette or
    never leaves it (past the frame's edge it may go on)."""
    length = float(np.hypot(*(through - start)))
    steps = np.arange(first * length, last * length, 1.0) / max(length, 1e-9)
    points = np.round(start + steps[:, None] * (through - start)).astype(int)
    h, w = mask.shape
    inside = (points[:, 0] >= 0) & (points[:, 0] < w) & (points[:, 1] >= 0) & (points[:, 1] < h)
    on = np.ones(len(points), bool)
    on[inside] = mask[points[inside, 1], points[inside, 0]] > 0
    if not len(on) or not on[0] or on.all():
        return None
    return points[np.argmin(on) - 1].astype(float)


def moved(landmarks: Landmarks, joint: str, to: np.ndarray) -> Landmarks:
    """``landmarks`` with one joint's 2D at ``to``."""
    joints = landmarks.joints2d.copy()
    joints[_J[joint]] = to
    return replace(landmarks, joints2d=joints)


@dataclass(frozen=True)
class Targets:
    """Landmarks as the searches read them: ``points`` (16, 2) in fitted-silhouette pixels, image-sided, the
    model's pelvis and hips (body.reported_joints puts them lower); ``weight`` (16,) their confidences."""

    points: np.ndarray
    weight: np.ndarray


def fit_targets(
    landmarks: Landmarks | None, origin: np.ndarray, step: float, px_per_unit: float, prev: Pose2D | None
) -> Targets | None:
    """A frame's landmarks in its normalised crop's pixels (``origin``, ``step``), image-sided, or None; a joint
    the model's two looks place apart (``Landmarks.doubtful``) weighs nothing: the fit answers there."""
    if landmarks is None:
        return None
    points = (landmarks.joints2d + 0.5 - origin) / step - 0.5
    weight = (
        landmarks.confidence if landmarks.doubtful is None else np.where(landmarks.doubtful, 0.0, landmarks.confidence)
    )
    points, weight = image_sided(points, weight, prev, px_per_unit)
    return Targets(model_joints(points, px_per_unit), weight)


def image_sided(
    points: np.ndarray, weight: np.ndarray, prev: Pose2D | None, px_per_unit: float
) -> tuple[np.ndarray, np.ndarray]:
    """Landmarks (16, 2) and weights with limb pairs named by image side: by the shoulders' (hips') x where they
    lie APART, else by the pairing nearer ``prev``'s angles."""
    points, weight = points.copy(), weight.copy()
    for limb, joints in _PAIRS.items():
        left = [_J[f"{j}_l"] for j in joints]
        right = [_J[f"{j}_r"] for j in joints]
        dx = points[left[0], 0] - points[right[0], 0]
        if abs(dx) >= APART * BODY_HEIGHT * px_per_unit:
            swap = dx > 0
        elif prev is not None:
            swap = _angle_cost(points, prev, limb, swapped=True) < _angle_cost(points, prev, limb, swapped=False)
        else:
            swap = False
        if swap:
            points[left + right] = points[right + left]
            weight[left + right] = weight[right + left]
    return points, weight


def _angle_cost(points: np.ndarray, prev: Pose2D, limb: str, swapped: bool) -> float:
    """Degrees (summed) a limb pair's segment angles lie from ``prev``'s, sides exchanged or not."""
    total = 0.0
    for kind in _LIMB_SEGMENTS[limb]:
        for side, other in (("l", "r"), ("r", "l")):
            seen = segment_angle(points, f"{kind}_{other if swapped else side}")
            total += abs((seen - prev.angle[SEGMENT_INDEX[f"{kind}_{side}"]] + 180.0) % 360.0 - 180.0)
    return total


def segment_angle(points: np.ndarray, segment: str) -> float:
    """A segment's image angle (Pose2D's: degrees counter-clockwise, y up) between its joints' points."""
    a, b = (points[_J[j]] for j in SEGMENTS[segment])
    return float(np.degrees(np.arctan2(a[1] - b[1], b[0] - a[0])) % 360.0)


def centred_on(prev: Pose2D | None, targets: Targets | None) -> Pose2D | None:
    """The pose centring the searches: ``prev`` with each segment whose landmarks are SURE turned as they lie;
    without ``prev``, the landmarks' pose if they are sure of every segment, else None."""
    if targets is None:
        return prev
    sure = {s: bool(targets.weight[[_J[a], _J[b]]].min() >= SURE) for s, (a, b) in SEGMENTS.items()}
    if prev is None and not all(sure.values()):
        return None
    angle = (prev.angle if prev is not None else np.zeros(len(SEGMENTS))).copy()
    for s, ok in sure.items():
        if ok:
            angle[SEGMENT_INDEX[s]] = segment_angle(targets.points, s)
    base = prev if prev is not None else Pose2D(pelvis=targets.points[_J["pelvis"]], scale=1.0)
    return replace(base, angle=angle)
