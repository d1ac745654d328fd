"""Drawing the 2D model as a mask (segments as filled rectangles as wide as their cylinder, as long as their
projection), and the similarity S of the paper (Eq. 1-3), scored on a :class:`Canvas`."""

from __future__ import annotations

import functools
import math

import cv2
import numpy as np

from mocap.body import (
    BODY_HEIGHT,
    FOOT_LENGTH,
    LENGTH,
    SEGMENT_INDEX,
    SEGMENT_JOINTS,
    SEGMENT_NAMES,
    WIDTH,
    torso_width,
)
from mocap.image.edges import EDGE_WEIGHT, Edges
from mocap.silhouette.model2d import KINEMATIC_MATRIX, Pose2D, joints_of_basis, kinematic_basis

LANDMARK_WEIGHT = 0.6  # S that a confident landmark far from its joint takes away
LANDMARK_SIGMA = 0.05  # of the body height: a landmark's distance that costs half of it
_SHIFT = 4  # sub-pixel bits for cv2 polygon fill
_ONE = 1 << _SHIFT
_PERPENDICULAR = np.array([-1.0, 1.0])  # (dx, dy) reversed times this: the normal (-dy, dx)
_CORNER_END = np.array([0, 1, 1, 0])  # a rectangle's corners: at which end of the segment,
_CORNER_SIDE = np.array([1.0, 1.0, -1.0, -1.0])  # and on which side of it
_TORSO = SEGMENT_INDEX["torso"]
_HAS_FOOT = np.isin(np.arange(len(SEGMENT_NAMES)), [SEGMENT_INDEX["lower_leg_l"], SEGMENT_INDEX["lower_leg_r"]])
# The hand (not in the paper's 10 cylinders nor the contract's joints): the lower arm's
# continuation past the wrist, this long in model units at its foreshortening; without it
# the fit puts the wrist at the silhouette's end, in the hand.
HAND_LENGTH = 13.0
_HAND_REACH = np.zeros(len(SEGMENT_NAMES))  # of the lower arm's drawn length
_HAND_REACH[[SEGMENT_INDEX["lower_arm_l"], SEGMENT_INDEX["lower_arm_r"]]] = (
    HAND_LENGTH / LENGTH[SEGMENT_INDEX["lower_arm_l"]]
)
_ALL_SEGMENTS = tuple(range(len(SEGMENT_NAMES)))
# rows of ``_corner_basis``: model2d.kinematic_basis's 12, then the segments' directions and normals
_DIRECTIONS, _NORMALS, _BASIS_ROWS = 12, 12 + len(SEGMENT_NAMES), 12 + 2 * len(SEGMENT_NAMES)


def segment_quads(starts: np.ndarray, ends: np.ndarray, widths: np.ndarray) -> np.ndarray:
    """Corners (..., 4, 2) of rectangles of the given widths from starts to ends."""
    return _rectangles(np.stack([starts, ends], axis=-2), widths)


def _rectangles(ends: np.ndarray, widths) -> np.ndarray:
    """Corners (..., 4, 2) of rectangles of ``widths`` along segments whose ends are (..., 2, 2)."""
    d = ends[..., 1, :] - ends[..., 0, :]
    half = widths / (2 * np.maximum(np.sqrt(d[..., 0] * d[..., 0] + d[..., 1] * d[..., 1]), 1e-9))
    h = d[..., ::-1] * (half[..., None] * _PERPENDICULAR)
    return ends[..., _CORNER_END, :] + h[..., None, :] * _CORNER_SIDE[:, None]


@functools.lru_cache(maxsize=64)
def _corner_weights(segments: tuple[int, ...], scale: float) -> np.ndarray:
    """Weights (4k, _BASIS_ROWS) giving some segments' rectangle corners from ``_corner_basis``: each the
    proximal or distal joint (on into the hand, past the ankle by the foot) plus or minus the half width normal."""
    idx = np.array(segments, int)
    start, end = KINEMATIC_MATRIX[SEGMENT_JOINTS[idx, 0]], KINEMATIC_MATRIX[SEGMENT_JOINTS[idx, 1]]
    end = end + _HAND_REACH[idx, None] * (end - start)
    k, rows = len(idx), np.arange(len(idx))
    weights = np.zeros((k, 4, _BASIS_ROWS))
    weights[:, :, :_DIRECTIONS] = np.stack([start, end, end, start], axis=1)
    foot = np.where(_HAS_FOOT[idx], FOOT_LENGTH * scale, 0.0)
    weights[rows[:, None], [1, 2], _DIRECTIONS + idx[:, None]] = foot[:, None]
    half = np.where(idx == _TORSO, 1.0, WIDTH[idx] * scale / 2)
    weights[rows, :, _NORMALS + idx] = half[:, None] * _CORNER_SIDE
    return weights.reshape(4 * k, _BASIS_ROWS)


def _corner_basis(pelvis, scale: float, angle: np.ndarray, ratio: np.ndarray, spread, torso: bool) -> np.ndarray:
    """``model2d.kinematic_basis``'s 12 vectors, then each segment's unit direction (cos, -sin) and normal (sin,
    cos): (_BASIS_ROWS, B, 2); the torso's normal times its seen half width if ``torso``."""
    basis, cos, sin = kinematic_basis(pelvis, scale, angle, ratio, spread, rows=_BASIS_ROWS)
    basis[_DIRECTIONS:_NORMALS, :, 0] = basis[_NORMALS:, :, 1] = cos
    basis[_DIRECTIONS:_NORMALS, :, 1] = -sin
    basis[_NORMALS:, :, 0] = sin
    if torso:
        basis[_NORMALS + _TORSO] *= np.reshape(torso_width(spread) * (scale / 2), (-1, 1))
    return basis


def posed_quads(
    pelvis, scale: float, angle: np.ndarray, ratio: np.ndarray, spread, segments=None
) -> tuple[np.ndarray, np.ndarray]:
    """Rectangles (B, k, 4, 2) of the ``segments`` (indices) of B poses as ``model2d.forward_kinematics_2d_batch``
    takes them, and their joints (B, 16, 2): the torso as wide as ``spread`` shows it, lower legs on past the
    ankle by the foot (body.FOOT_LENGTH), lower arms into the hand (HAND_LENGTH)."""
    segments = _ALL_SEGMENTS if segments is None else tuple(segments)
    basis = _corner_basis(pelvis, scale, angle, ratio, spread, _TORSO in segments)
    weights = _corner_weights(segments, scale)
    quads = (weights @ basis.reshape(_BASIS_ROWS, -1)).reshape(-1, 4, len(angle), 2)
    return quads.transpose(2, 0, 1, 3), joints_of_basis(basis)


def pose_quads(pose: Pose2D, segments=SEGMENT_NAMES) -> np.ndarray:
    """The rectangles (k, 4, 2) of the named segments of a 2D pose."""
    return poses_quads([pose], segments)[0]


def poses_quads(poses: list[Pose2D], segments=SEGMENT_NAMES) -> np.ndarray:
    """The rectangles (P, k, 4, 2) of the named segments of 2D poses of one scale."""
    return posed_quads(
        np.array([p.pelvis for p in poses], float),
        poses[0].scale,
        np.array([p.angle for p in poses]),
        np.array([p.ratio for p in poses]),
        np.array([p.spread for p in poses]),
        [SEGMENT_INDEX[s] for s in segments],
    )[0]


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
    """S = exp(-p - n)(1 - p) (Eq. 1-3) from pixel counts, elementwise on arrays."""
    sil_area = float(sil_area)
    union = np.maximum(sil_area + model_area - overlap, 1.0)
    p = (sil_area - overlap) / union
    n = (model_area - overlap) / union
    return np.exp(-p - n) * (1.0 - p)


def similarity(silhouette: np.ndarray, model: np.ndarray) -> float:
    """S(I1, I2) of Eq. 1-3 between two masks (nonzero = inside)."""
    sil, mod = silhouette > 0, model > 0
    return float(similarity_from_counts(np.count_nonzero(sil), np.count_nonzero(mod), np.count_nonzero(sil & mod)))


def _draw_planes(candidates: np.ndarray, offset: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    """Each candidate's polygons (B, k, 4, 2) filled into its own 0/1 plane (B, H, W)."""
    pts = ((candidates - offset) * _ONE + 0.5).astype(np.int32, order="C")  # windows keep them >= 0
    planes = np.zeros((len(pts),) + shape, np.uint8)
    fill, line = cv2.fillConvexPoly, cv2.LINE_8
    for k in range(pts.shape[1]):  # segment by segment: less loop overhead
        for plane, quad in zip(planes, pts[:, k]):
            fill(plane, quad, 1, line, _SHIFT)  # one by one: fillPoly would make overlaps holes
    return planes


def sweep_scorer(canvas: "Canvas", sweep: np.ndarray, outline: list[int] | None = None):
    """S (B,) of candidates (B, k, 4, 2) on the partial silhouette they (or the ``outline`` ones) sweep less the
    fitted part, and a scorer of more. Pixels over the fitted part count neither way (else the longest arm over
    the trunk wins). One integer product: a pixel weighs 1 if free, plus 2**shift if in the target."""
    outline = slice(None) if outline is None else outline
    x0, y0, x1, y1 = bounding_window(sweep[outline], canvas.sil.shape)
    offset, shape = np.array([x0, y0], float), (y1 - y0, x1 - x0)
    if not shape[0] or not shape[1]:  # swept wholly outside the frame: explains nothing
        return np.zeros(len(sweep)), lambda candidates: np.zeros(len(candidates))
    planes = _draw_planes(sweep, offset, shape)
    free = canvas.free[y0:y1, x0:x1]
    target = np.bitwise_or.reduce(planes[outline], axis=0) & free & canvas.sil[y0:y1, x0:x1]
    sil_area = np.count_nonzero(target)
    # integers, not floats: a uint8-by-uint32 einsum is cheaper than float64 ones or BLAS
    shift, dtype = (16, np.uint32) if free.size < 1 << 16 else (32, np.uint64)
    weights = (free | target.astype(dtype) << dtype(shift)).ravel()
    low = dtype((1 << shift) - 1)

    def weigh(planes_: np.ndarray) -> np.ndarray:
        totals = np.einsum("bn,n->b", planes_.reshape(len(planes_), -1), weights)
        return similarity_from_counts(sil_area, totals & low, totals >> dtype(shift))

    return weigh(planes), lambda candidates: weigh(_draw_planes(candidates, offset, shape))


def bounding_window(quads: np.ndarray, shape: tuple[int, int], pad: float = 1.0) -> tuple[int, int, int, int]:
    """Integer box (x0, y0, x1, y1), clipped to shape, holding all given polygons."""
    xs, ys = quads.reshape(-1, 2).T.copy()  # cv2's minimum and maximum: cheaper than numpy's
    (ax, bx, _, _), (ay, by, _, _) = cv2.minMaxLoc(xs), cv2.minMaxLoc(ys)
    h, w = shape
    x0, y0 = min(max(math.floor(ax - pad), 0), w), min(max(math.floor(ay - pad), 0), h)
    return x0, y0, min(max(math.ceil(bx + pad) + 1, x0), w), min(max(math.ceil(by + pad) + 1, y0), h)


class Canvas:
    """A silhouette and the part of the model fitted so far. Searches score on the *partial silhouette*
    (Algorithms 1, 6): on the whole one a part spilling outside would win while others are unexplained."""

    def __init__(self, silhouette: np.ndarray, grey: np.ndarray | None = None, targets=None):
        self.sil = (silhouette > 0).astype(np.uint8)
        self.fixed = np.zeros_like(self.sil)
        self.free = np.ones_like(self.sil)  # 1 - fixed, which every search reads
        self.edges = None if grey is None else Edges.inside(grey, self.sil)
        self.by_edges = False
        self.targets = targets  # a person model's landmarks (mocap.silhouette.eyes.Targets)

    def fork(self, quads=(), keep: np.ndarray | None = None, by_edges: bool = False) -> "Canvas":
        """A copy with ``quads`` fitted too, silhouette only where ``keep``, following edges if ``by_edges``."""
        other = Canvas.__new__(Canvas)
        other.sil = self.sil if keep is None else self.sil & keep.astype(np.uint8)
        other.fixed, other.free = self.fixed.copy(), self.free
        other.edges, other.targets = self.edges, self.targets
        other.by_edges = by_edges and self.edges is not None
        if len(quads):
            other.commit(quads)
        return other

    def edge_scores(self, joints: np.ndarray, segments: list[int], scale: float) -> np.ndarray:
        """(B,) what the inner edges along segments of posed joints (B, 16, 2) add to S: EDGE_WEIGHT times their
        support (mocap.image.edges); 0 on a canvas not following edges."""
        if not self.by_edges:
            return np.zeros(len(joints))
        ends = joints[:, SEGMENT_JOINTS[segments]]
        return EDGE_WEIGHT * self.edges.support(ends[:, :, 0], ends[:, :, 1], WIDTH[segments] * scale)

    def landmark_scores(self, joints: np.ndarray, segments: list[int], scale: float) -> np.ndarray:
        """(B,) what the landmarks add to S for posed joints (B, 16, 2): -LANDMARK_WEIGHT times the
        confidence-weighted d^2 / (d^2 + sigma^2), sigma LANDMARK_SIGMA of the body height; 0 without landmarks."""
        if self.targets is None:
            return np.zeros(len(joints))
        idx = np.unique(SEGMENT_JOINTS[segments])
        d2 = ((joints[:, idx] - self.targets.points[idx]) ** 2).sum(-1)
        sigma2 = (LANDMARK_SIGMA * BODY_HEIGHT * scale) ** 2
        return -LANDMARK_WEIGHT * (self.targets.weight[idx] * d2 / (d2 + sigma2)).sum(-1)

    def commit(self, quads) -> None:
        """Make quads part of the fitted model."""
        fill_quads(self.fixed, quads)
        self.free = 1 - self.fixed

    def score_model(self) -> float:
        """S of Eq. 3 between the whole silhouette and the fitted model."""
        return similarity(self.sil, self.fixed)
