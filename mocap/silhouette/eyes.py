"""What a person model's eyes (mocap.person) give the silhouette method: the silhouette where
background subtraction cannot see (``fused_mask``), and landmarks as targets of the 2D fit's
searches (``fit_targets``), as SMPLify fits a body model to learned keypoints. Landmarks name
anatomical sides, the fit image sides (section 3.3): ``image_sided`` renames them."""

from __future__ import annotations

from dataclasses import dataclass, replace

import cv2
import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, SEGMENT_INDEX, SEGMENTS, Pose2D, model_joints
from mocap.person import SURE, Landmarks

PERSON_LEVEL = 0.5          # a person-mask probability from which a pixel is the performer
EDGE_BAND = 0.01            # of the person mask's height: the band outside it where background
                            # subtraction may add pixels (its edges follow the frame's)
APART = 0.04                # of the body height: shoulders or hips this far apart in x
                            # tell the image-left limb from the image-right one
_J = JOINT_INDEX
_PAIRS = {"arm": ("shoulder", "elbow", "wrist"), "leg": ("hip", "knee", "ankle")}
_LIMB_SEGMENTS = {"arm": ("upper_arm", "lower_arm"), "leg": ("upper_leg", "lower_leg")}


def fused_mask(classical: np.ndarray, person: np.ndarray, held: np.ndarray | None
               ) -> tuple[np.ndarray, np.ndarray] | None:
    """The silhouette (uint8 0/255) from ``classical`` (0/255) and the person model's probabilities
    ``person``, and the pixels only the person model gave (bool); None where its mask is empty. The
    person mask (it sees a body part that never moves) is grown by background subtraction's pixels
    in an EDGE_BAND around it where the scene was seen (not ``held``), to follow the frame's edges."""
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


@dataclass(frozen=True)
class Targets:
    """Landmarks as the fit's searches read them: ``points`` (16, 2) in the fitted silhouette's
    pixels, named by image side, with the model's pelvis and hips (body.reported_joints puts them
    lower); ``weight`` (16,) their confidences."""

    points: np.ndarray
    weight: np.ndarray


def fit_targets(landmarks: Landmarks | None, origin: np.ndarray, step: float, px_per_unit: float,
                prev: Pose2D | None) -> Targets | None:
    """A frame's landmarks (processing pixels) in the pixels of its crop normalised for the fit
    (``origin``, ``step``: passes.normalise), image-sided; None without landmarks."""
    if landmarks is None:
        return None
    points = (landmarks.joints2d + 0.5 - origin) / step - 0.5
    points, weight = image_sided(points, landmarks.confidence, prev, px_per_unit)
    return Targets(model_joints(points, px_per_unit), weight)


def image_sided(points: np.ndarray, weight: np.ndarray, prev: Pose2D | None, px_per_unit: float
                ) -> tuple[np.ndarray, np.ndarray]:
    """Landmarks (16, 2) and weights with each limb pair named by image side as the fit names it: the
    image-left shoulder (hip) is '_l' where the two lie APART, else the pairing nearer ``prev``'s
    segment angles, so the fit keeps following the same limbs."""
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
    """How far (degrees, summed) a limb pair's segment angles lie from the previous
    fit's, the landmarks' sides exchanged or not."""
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
    """The pose whose angles centre the searches (``prev`` of mocap.silhouette.fit2d):
    the previous fit's with each segment whose two landmarks are SURE turned as they
    lie; with no previous fit, the landmarks' pose where they are sure of every segment."""
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
