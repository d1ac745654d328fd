"""The torso and head of the 2D fit (section 3.3, Fig. 3a): where the body stands, how far it is turned (the
torso's horizontal foreshortening, section 3.4), their angles by Algorithm 1 and ratios by Algorithm 6."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mocap.body import BODY_HEIGHT, FOOT_LENGTH, LENGTH, SEGMENT_INDEX, spread_for_width
from mocap.image.percentile import percentile
from mocap.silhouette.contour import row_runs
from mocap.silhouette.model2d import Pose2D
from mocap.silhouette.raster import Canvas
from mocap.silhouette.search import RATIO_SWEEP_STEP, Knob, Search, around, search, search_angle, search_ratio

TORSO_HEAD = ("torso", "head")
WAIST_RANGE = (45.0, 135.0)  # Table 1
# A crouching body's trunk (bent over, or leaning over folded legs) may lean further
# than Table 1's waist, down to this far above level (as in a deep squat).
CROUCH_RANGE = (15.0, 165.0)
# Of the height a crouching body lacks, the share the trunk takes up by leaning: the
# legs fold the rest (under an upright trunk the pelvis would be at the feet).
CROUCH_TRUNK_SHARE = 0.5
# Below this share of the standing height a body is crouching (a walk's or a run's
# longest strides lower the hips less).
CROUCH_SPAN = 0.9
NECK_RANGE = (45.0, 135.0)  # Table 1
SILHOUETTE_BLEED_PX = 1.0  # silhouettes come out this much wider than the body
# A head (round from any side) is this wide (model units) this far under its crown;
# a raised forearm or hand is narrower.
HEAD_ROW_WIDTH = 14.0
HEAD_ROW_DEPTH = 3.0
UPRIGHT_SPAN = (0.94, 1.05)  # silhouette height / standing height of an upright body
RAISED_PX = 1  # fit pixels of silhouette over the head: none raised


def initial_pose(silhouette: np.ndarray, scale: float) -> Pose2D:
    """Torso location from Table 1: the pelvis head+torso under the head's top, x mid-silhouette there."""
    rows = np.flatnonzero(silhouette.any(axis=1))
    top, bottom = head_top_row(silhouette, scale), int(rows[-1])
    head = LENGTH[SEGMENT_INDEX["head"]] * scale
    pelvis_y = min(top + head + LENGTH[SEGMENT_INDEX["torso"]] * scale, bottom)
    xs = np.nonzero(silhouette[int(top + head) : int(pelvis_y) + 1])[1]
    x = float(np.median(xs)) if len(xs) else float(np.median(np.nonzero(silhouette)[1]))
    return Pose2D(pelvis=np.array([x, pelvis_y]), scale=scale)


def head_top_row(silhouette: np.ndarray, scale: float) -> int:
    """The silhouette's top row or, above raised arms, HEAD_ROW_DEPTH above the first head-wide row."""
    rows, starts, ends = row_runs(silhouette)
    if len(rows) == 0:
        return 0
    wide = rows[(ends - starts) >= HEAD_ROW_WIDTH * scale]
    if len(wide) == 0:
        return int(rows[0])
    return max(int(rows[0]), int(round(wide[0] - HEAD_ROW_DEPTH * scale)))


def fit_torso_head(canvas: Canvas, pose: Pose2D, prev: Pose2D | None, spread: float | None = None) -> Pose2D:
    """Torso angle (Algorithm 1, head along it: Fig. 3a), x, spread (unless given), head angle, ratios."""
    pose = place_torso(canvas, pose, prev)
    pose = fit_spread(canvas, pose) if spread is None else replace(pose, spread=spread)
    lo, hi, c = around(prev, "head", *NECK_RANGE, pose.angle[SEGMENT_INDEX["torso"]])
    pose = search_angle(canvas, pose, ("head",), TORSO_HEAD, lo, hi, c)
    pose = search_ratio(canvas, pose, "torso", TORSO_HEAD)
    return search_ratio(canvas, pose, "head", ("head",))


def place_torso(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> Pose2D:
    """The torso's angle (Algorithm 1, head along it), the pelvis under the head at that lean, and the horizontal
    position; a crouching body's torso turns over CROUCH_RANGE about ``crouch_pelvis``."""
    pelvis = crouch_pelvis(canvas.sil, pose)
    crouching = pelvis is not None
    lo, hi, c = around(prev, "torso", *(CROUCH_RANGE if crouching else WAIST_RANGE), 90.0)
    pose = search_angle(canvas, replace(pose, pelvis=pelvis) if crouching else pose, TORSO_HEAD, TORSO_HEAD, lo, hi, c)
    return fit_pelvis_x(canvas, pose if crouching else under_the_head(canvas.sil, pose))


def crouch_pelvis(silhouette: np.ndarray, pose: Pose2D) -> np.ndarray | None:
    """The pelvis of a body shorter than CROUCH_SPAN of the standing height (None if upright): under the head's
    top by the upright trunk less up to CROUCH_TRUNK_SHARE of the height lacked, mid-silhouette."""
    bottom = np.flatnonzero(silhouette.any(axis=1))[-1]
    top, standing = head_top_row(silhouette, pose.scale), standing_px(pose.scale)
    short, allowed = standing - (bottom - top), (1.0 - CROUCH_SPAN) * standing
    if short <= allowed:
        return None
    y = min(top + trunk_reach(pose.scale) - CROUCH_TRUNK_SHARE * short * min(short / allowed - 1.0, 1.0), bottom)
    xs = np.flatnonzero(silhouette[int(round(y))])
    return np.array([float(np.median(xs)) if len(xs) else pose.pelvis[0], y])


def standing_px(scale: float) -> float:
    """Pixels from the head's top to the soles of an upright body."""
    return (BODY_HEIGHT + FOOT_LENGTH) * scale


def trunk_reach(scale: float) -> float:
    """Pixels from the head's top to the pelvis of an upright body (Table 1)."""
    return (LENGTH[SEGMENT_INDEX["head"]] + LENGTH[SEGMENT_INDEX["torso"]]) * scale


def under_the_head(silhouette: np.ndarray, pose: Pose2D) -> Pose2D:
    """The pelvis as far under the head's top as the torso and head reach at the torso's lean."""
    lean = np.sin(np.radians(pose.angle[SEGMENT_INDEX["torso"]]))
    bottom = np.flatnonzero(silhouette.any(axis=1))[-1]
    y = min(head_top_row(silhouette, pose.scale) + trunk_reach(pose.scale) * lean, bottom)
    return replace(pose, pelvis=np.array([pose.pelvis[0], y]))


def torso_spread(silhouette: np.ndarray, scale: float) -> float:
    """The torso's horizontal foreshortening on one frame (section 3.4) from its seen width: the narrowest
    quarter of widths across its middle rows, less SILHOUETTE_BLEED_PX, via ``body.spread_for_width``."""
    if not silhouette.any():
        return 1.0
    top = head_top_row(silhouette, scale)
    head, torso = LENGTH[SEGMENT_INDEX["head"]] * scale, LENGTH[SEGMENT_INDEX["torso"]] * scale
    band = silhouette[int(top + head + 0.25 * torso) : int(top + head + 0.75 * torso)] > 0
    rows, starts, ends = row_runs(band)
    if len(rows) == 0:
        return 1.0
    widest = np.zeros(band.shape[0])
    np.maximum.at(widest, rows, ends - starts)
    width = (percentile(widest[widest > 0], 25) - SILHOUETTE_BLEED_PX) / scale
    return float(spread_for_width(width))


def torso_width_readable(silhouette: np.ndarray, scale: float, body_px: float) -> bool:
    """Whether a frame's torso width can be trusted: upright (UPRIGHT_SPAN of ``body_px``), no arm up."""
    rows = np.flatnonzero(silhouette.any(axis=1))
    if len(rows) == 0:
        return False
    span = (rows[-1] - rows[0]) / body_px
    raised = head_top_row(silhouette, scale) - rows[0]
    return bool(UPRIGHT_SPAN[0] <= span <= UPRIGHT_SPAN[1] and raised <= RAISED_PX)


def fit_pelvis_x(canvas: Canvas, pose: Pose2D, reach: float = 12.0) -> Pose2D:
    """The torso's horizontal position by the same search (arms pull the silhouette's middle off)."""
    r = reach * pose.scale
    return search(pose, Search(canvas, Knob("x"), TORSO_HEAD, -r, r, 0.0, 0.5, 2.0))


def fit_spread(canvas: Canvas, pose: Pose2D) -> Pose2D:
    """The torso's horizontal foreshortening (0 profile .. 1 frontal) by Algorithm 6's search."""
    return search(pose, Search(canvas, Knob("spread"), TORSO_HEAD, 0.0, 1.0, pose.spread, 0.05, RATIO_SWEEP_STEP))
