"""Drawing the 2D model as a mask, and the similarity S of the paper (Eq. 1-3).

Segments are drawn as filled rectangles as wide as their cylinder and as long as
their projection, with OpenCV's sub-pixel polygon fill. The search algorithms score
candidates against a :class:`Canvas` that keeps the silhouette and the part of the
model already fitted, so each candidate costs one small polygon fill and two counts.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from mocap.body import (FOOT_LENGTH, LENGTH, SEGMENT_INDEX, SEGMENT_JOINTS, SEGMENT_NAMES, WIDTH,
                        Pose2D, forward_kinematics_2d, torso_width)
from mocap.edges import EDGE_WEIGHT, Edges

_SHIFT = 4                      # sub-pixel bits for cv2 polygon fill
_ONE = 1 << _SHIFT
_TORSO = SEGMENT_INDEX["torso"]
_HAS_FOOT = np.isin(np.arange(len(SEGMENT_NAMES)), [SEGMENT_INDEX["lower_leg_l"], SEGMENT_INDEX["lower_leg_r"]])
# The hand (not in the paper's 10 cylinders nor the contract's joints): drawn as the
# lower arm's continuation beyond the wrist, this long in model units at the lower
# arm's foreshortening. Without it the fit puts the wrist at the silhouette's end, in
# the hand. Rendered and real bodies show 9-15 units of hand past the wrist joint
# (a hand is 19 units to the fingertips, less its curl).
HAND_LENGTH = 13.0
_HAND_REACH = np.zeros(len(SEGMENT_NAMES))       # of the lower arm's drawn length
_HAND_REACH[[SEGMENT_INDEX["lower_arm_l"], SEGMENT_INDEX["lower_arm_r"]]] = HAND_LENGTH / LENGTH[
    SEGMENT_INDEX["lower_arm_l"]]


def segment_quads(starts: np.ndarray, ends: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Corners (..., 4, 2) of rectangles of the given widths from starts to ends."""
    d = ends - starts
    half = widths / (2 * np.maximum(np.sqrt((d * d).sum(-1)), 1e-9))
    h = np.empty_like(d)
    h[..., 0] = -d[..., 1] * half
    h[..., 1] = d[..., 0] * half
    out = np.empty(d.shape[:-1] + (4, 2))
    out[..., 0, :] = starts + h
    out[..., 1, :] = ends + h
    out[..., 2, :] = ends - h
    out[..., 3, :] = starts - h
    return out


def joint_quads(joints: np.ndarray, scale: float, segments=None, spread=1.0) -> np.ndarray:
    """Rectangles (..., k, 4, 2) of the segments (indices) of posed joints (..., 16, 2);
    the torso is as wide as ``spread`` (shape (...,)) makes it look, each lower leg
    goes on past the ankle by the foot (body.FOOT_LENGTH), which silhouettes show, and
    each lower arm into the hand (HAND_LENGTH)."""
    idx = np.arange(len(SEGMENT_NAMES)) if segments is None else np.asarray(segments)
    ends = joints[..., SEGMENT_JOINTS[idx], :]
    foot, hand = _HAS_FOOT[idx], _HAND_REACH[idx]
    if foot.any() or hand.any():
        ends = ends.copy()
    if foot.any():
        shin = ends[..., foot, 1, :] - ends[..., foot, 0, :]
        length = np.maximum(np.linalg.norm(shin, axis=-1, keepdims=True), 1e-9)
        ends[..., foot, 1, :] += shin / length * (FOOT_LENGTH * scale)
    if hand.any():
        ends[..., 1, :] += (ends[..., 1, :] - ends[..., 0, :]) * hand[:, None]
    widths = np.empty(ends.shape[:-2])
    widths[...] = WIDTH[idx] * scale
    torso = idx == _TORSO
    if torso.any():
        widths[..., torso] = (torso_width(spread) * scale)[..., None]
    return segment_quads(ends[..., 0, :], ends[..., 1, :], widths)


def pose_quads(pose: Pose2D, segments=SEGMENT_NAMES) -> np.ndarray:
    """The rectangles (k, 4, 2) of the named segments of a 2D pose."""
    return joint_quads(forward_kinematics_2d(pose), pose.scale,
                       [SEGMENT_INDEX[s] for s in segments], pose.spread)


def fill_quads(mask: np.ndarray, quads: np.ndarray, offset=(0, 0)) -> np.ndarray:
    """Fill polygons (k, 4, 2) (canvas coordinates) into mask, shifted by -offset; value 1."""
    pts = np.round((np.asarray(quads, float).reshape(-1, 4, 2) - np.asarray(offset, float)) * _ONE)
    for quad in pts.astype(np.int32):
        cv2.fillConvexPoly(mask, quad, 1, lineType=cv2.LINE_8, shift=_SHIFT)
    return mask


def draw_model(pose: Pose2D, shape: tuple[int, int], segments=SEGMENT_NAMES) -> np.ndarray:
    """The model (or some of its segments) as a 0/1 uint8 mask of the given shape."""
    return fill_quads(np.zeros(shape, np.uint8), pose_quads(pose, segments))


def similarity_from_counts(sil_area, model_area, overlap) -> np.ndarray:
    """S = exp(-p - n)(1 - p) of Eq. 3, with p and n of Eq. 1-2 from pixel counts.

    p: silhouette pixels not covered by the model / union; n: model pixels outside
    the silhouette / union. Works elementwise on arrays of candidates.
    """
    sil_area = np.asarray(sil_area, dtype=float)
    union = np.maximum(sil_area + model_area - overlap, 1.0)
    p = (sil_area - overlap) / union
    n = (model_area - overlap) / union
    return np.exp(-p - n) * (1.0 - p)


def similarity(silhouette: np.ndarray, model: np.ndarray) -> float:
    """S(I1, I2) of Eq. 1-3 between two masks (nonzero = inside)."""
    sil, mod = silhouette > 0, model > 0
    return float(similarity_from_counts(np.count_nonzero(sil), np.count_nonzero(mod),
                                        np.count_nonzero(sil & mod)))


def _draw_planes(candidates: np.ndarray, offset: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Each candidate's polygons (B, k, 4, 2) filled into its own 0/1 plane (B, H, W)."""
    pts = ((candidates - offset) * _ONE + 0.5).astype(np.int32)   # windows keep them >= 0
    planes = np.zeros((len(pts),) + shape, np.uint8)
    owners = np.repeat(np.arange(len(pts)), pts.shape[1]).tolist()
    for i, quad in zip(owners, pts.reshape(-1, 4, 2)):
        cv2.fillConvexPoly(planes[i], quad, 1, cv2.LINE_8, _SHIFT)   # one by one: fillPoly
    return planes                                                      # would make overlaps holes


def sweep_scorer(canvas: "Canvas", sweep: np.ndarray):
    """Score a sweep of candidates (B, k, 4, 2) on the partial silhouette it outlines;
    returns (their S (B,) of Eq. 1-3, a function scoring further candidates).

    The partial silhouette is the silhouette inside the swept area that the canvas's
    fitted part does not already explain. A candidate's pixels over the fitted part
    count neither way: the silhouette cannot tell where an arm in front of the trunk
    lies (the frame's edges can: ``Canvas.edge_scores``), and counting them as
    silhouette it covers would make the longest arm over the trunk win. Candidates
    are drawn into planes of one array and weighed in one product: a pixel weighs 1
    if free, plus ``base`` (more than the window's pixel count) if in the partial
    silhouette, so one sum tells both counts.
    """
    x0, y0, x1, y1 = bounding_window(sweep, canvas.sil.shape)
    offset, shape = np.array([x0, y0], float), (y1 - y0, x1 - x0)
    if not shape[0] or not shape[1]:            # swept wholly outside the frame: explains nothing
        return np.zeros(len(sweep)), lambda candidates: np.zeros(len(candidates))
    planes = _draw_planes(sweep, offset, shape)
    free = canvas.fixed[y0:y1, x0:x1] == 0
    sil = canvas.sil[y0:y1, x0:x1].astype(bool)
    target = free & planes.any(axis=0) & sil
    sil_area = np.count_nonzero(target)
    base = float(free.size + 1)
    weights = free.ravel() + base * target.ravel()

    def weigh(planes_: np.ndarray) -> np.ndarray:
        # einsum, not BLAS: a threaded product of many candidates costs several times more CPU
        totals = np.einsum("bn,n->b", planes_.reshape(len(planes_), -1), weights)
        overlap = np.floor(totals / base)
        return similarity_from_counts(sil_area, totals - base * overlap, overlap)
    return weigh(planes), lambda candidates: weigh(_draw_planes(candidates, offset, shape))


def bounding_window(quads: np.ndarray, shape: tuple[int, int], pad: float = 1.0) -> tuple[int, int, int, int]:
    """Integer box (x0, y0, x1, y1), clipped to shape, holding all given polygons."""
    pts = quads.reshape(-1, 2)
    (ax, ay), (bx, by) = pts.min(axis=0).tolist(), pts.max(axis=0).tolist()
    h, w = shape
    x0, y0 = min(max(math.floor(ax - pad), 0), w), min(max(math.floor(ay - pad), 0), h)
    return x0, y0, min(max(math.ceil(bx + pad) + 1, x0), w), min(max(math.ceil(by + pad) + 1, y0), h)


class Canvas:
    """A silhouette and the part of the model fitted so far.

    A search scores candidates on the *partial silhouette* of its segments (the
    paper's Algorithms 1 and 6): the silhouette pixels inside the area the
    candidates can sweep that the fitted part does not already explain. Scoring
    against the whole silhouette, or a box around the segment, would reward a part
    for spilling outside the silhouette while other parts are still unexplained
    (Eq. 1 divides by the union, so unexplained pixels elsewhere lower p).
    """

    def __init__(self, silhouette: np.ndarray, grey: np.ndarray | None = None):
        self.sil = (silhouette > 0).astype(np.uint8)
        self.fixed = np.zeros_like(self.sil)
        self.edges = None if grey is None else Edges.inside(grey, self.sil)
        self.by_edges = False

    def fork(self, quads=(), keep: np.ndarray | None = None, by_edges: bool = False) -> "Canvas":
        """A copy whose fitted part also holds quads, and whose silhouette is only
        the pixels where keep is true (for a part that may explain only those);
        ``by_edges``: the copy follows the frame's inner edges, where it has them
        (``edge_scores``)."""
        other = Canvas.__new__(Canvas)
        other.sil = self.sil if keep is None else self.sil & keep.astype(np.uint8)
        other.fixed = self.fixed.copy()
        other.edges = self.edges
        other.by_edges = by_edges and self.edges is not None
        if len(quads):
            other.commit(quads)
        return other

    def edge_scores(self, joints: np.ndarray, segments: list[int], scale: float) -> np.ndarray:
        """(B,) what the inner edges along the given segments of posed joints
        (B, 16, 2) add to S: EDGE_WEIGHT times their support (mocap.edges), 0 on a
        canvas that does not follow edges."""
        if not self.by_edges:
            return np.zeros(len(joints))
        ends = joints[:, SEGMENT_JOINTS[segments]]
        return EDGE_WEIGHT * self.edges.support(ends[:, :, 0], ends[:, :, 1], WIDTH[segments] * scale)

    def commit(self, quads) -> None:
        """Make quads part of the fitted model."""
        fill_quads(self.fixed, quads)

    def score_model(self) -> float:
        """S of Eq. 3 between the whole silhouette and the fitted model."""
        return similarity(self.sil, self.fixed)
