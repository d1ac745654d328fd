"""The legs of the 2D fit (section 3.3, Fig. 3b-c): lower-leg angles by contour
analysis (Algorithm 2) with the knee-crossing test (Algorithm 5), upper legs by
Algorithm 1 with the lower legs attached, ratios by Algorithm 6. Beyond the paper:
both ways of joining lower to upper legs are scored so that a wrong crossing verdict
is undone, thighs crossing in the image are given back their own knees unless the
crossing explains clearly more, and the legs come as a few hypotheses scored
together (``leg_hypotheses``), among which ``mocap.silhouette.legchain`` chooses
over time.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mocap.body import (JOINT_INDEX, LENGTH, LIMB_JOINTS, SEGMENT_INDEX, SIDES, Pose2D,
                        forward_kinematics_2d, image_angle, limb)
from mocap.silhouette.contour import find_angle, lower_leg_curves, lower_legs_cross
from mocap.silhouette.raster import Canvas, pose_quads, poses_quads, sweep_scorer
from mocap.silhouette.search import (RATIO_RANGE, TRACK_HALF_RANGE, Knob, around, span,
                                     refine_limb, search_angle)

LEG = {side: limb("leg", side).segments for side in SIDES}
LEGS = LEG["l"] + LEG["r"]
UPPER_LEGS, LOWER_LEGS = tuple(zip(LEG["l"], LEG["r"]))
# Wider than Table 1's walking limits (240-300) so that runs and crouches can be
# fitted (a deep squat's thighs are level or above); frames outside Table 1 are
# flagged for review instead of forced inside.
THIGH_RANGE = (175.0, 365.0)
THIGH_TRACK_HALF_RANGE = 40.0    # degrees searched around a previous thigh, which swings fastest
CROSSED_GAIN = 0.02              # S by which crossed thighs must explain more to be kept
CROSSED_TURN = 30.0              # degrees less thigh turn since the last frame that keeps a crossing
UNCROSS_SPREAD = 0.3             # torso spread below which (near profile) thighs may cross
DISTINCT_PX = 1.0                # leg hypotheses whose joints all lie this close are one


def fit_legs(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> Pose2D:
    """Lower legs by contour analysis (Algorithm 2) and knee crossing (Algorithm 5),
    upper legs by Algorithm 1 with the lower legs attached (Fig. 3b-c), each lower
    leg refined by Algorithm 1, then ratios (Algorithm 6)."""
    curves, runs = lower_leg_curves(canvas.sil, forward_kinematics_2d(pose), pose.scale)
    crossed = lower_legs_cross(runs)
    for side, other in (("l", "r"), ("r", "l")):
        default = (prev or pose).angle[SEGMENT_INDEX[LEG[side][1]]]
        pose = Knob("angle", (LEG[side][1],)).apply(
            pose, find_angle(curves[other if crossed else side], default))
    for side in SIDES:
        pose = search_thigh(canvas, pose, side, prev)
    pose = _uncrossed_thighs(canvas, _best_leg_pairing(canvas, pose), prev)
    for side in SIDES:
        pose = refine_limb(pose, LEG[side], canvas, TRACK_HALF_RANGE)
    return pose


def search_thigh(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None) -> Pose2D:
    """One upper leg by Algorithm 1 with its lower leg attached (Fig. 3b-c), near the
    previous frame's when there is one."""
    thigh = LEG[side][0]
    return search_angle(canvas, pose, (thigh,), LEG[side],
                        *around(prev, thigh, *THIGH_RANGE, 270.0, THIGH_TRACK_HALF_RANGE))


def leg_hypotheses(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> list[Pose2D]:
    """Beyond the paper: distinct leg fits, best first by S of both legs together.

    ``fit_legs`` searches the two legs one at a time, so both can take the same leg
    of the silhouette (in profile, where the legs pass each other, the other leg is
    left unexplained). So each leg is also fitted again beside the other
    (``refit_leg_beside``); near profile, each fit also enters with its legs'
    names exchanged, since there the two legs look alike and only their motion over
    time tells which is which (``mocap.silhouette.legchain`` chooses)."""
    first = fit_legs(canvas, pose, prev)
    poses = [first] + [refit_leg_beside(canvas, first, side, prev) for side in SIDES]
    if pose.spread < UNCROSS_SPREAD:
        poses += [_exchange_legs(p) for p in poses]
    poses = _distinct(poses)
    order = np.argsort(-leg_scores(canvas, poses), kind="stable")
    return [poses[i] for i in order]


def refit_leg_beside(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None) -> Pose2D:
    """One leg's angles fitted again with the other leg taken as fitted, so that it
    explains what the other leaves unexplained: the thigh by Algorithm 1 from the
    previous frame's lower leg angle, then the lower leg. Its lengths stay: where the
    other leg explains everything, Algorithm 6 beside it would shrink this one."""
    other = LEG["r" if side == "l" else "l"]
    beside = canvas.fork(pose_quads(pose, other))
    lower = LEG[side][1]
    pose = Knob("angle", (lower,)).apply(pose, (prev or pose).angle[SEGMENT_INDEX[lower]])
    pose = search_thigh(beside, pose, side, prev)
    return search_angle(beside, pose, (lower,), (lower,),
                        *span(pose.angle[SEGMENT_INDEX[lower]], TRACK_HALF_RANGE))


def leg_scores(canvas: Canvas, poses: list[Pose2D]) -> np.ndarray:
    """S (Eq. 1-3) of both legs of each pose, on the partial silhouette they outline together."""
    scores, _ = sweep_scorer(canvas, poses_quads(poses, LEGS))
    return scores


def _distinct(poses: list[Pose2D]) -> list[Pose2D]:
    """The poses less those whose leg joints all lie within DISTINCT_PX of an earlier one's."""
    legs = [JOINT_INDEX[f"{j}_{s}"] for j in LIMB_JOINTS["leg"] for s in SIDES]
    out, seen = [], []
    for pose in poses:
        joints = forward_kinematics_2d(pose)[legs]
        if all(np.abs(joints - other).max() > DISTINCT_PX for other in seen):
            out.append(pose)
            seen.append(joints)
    return out


def _segments_cross(a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray) -> bool:
    """Whether the segments a-b and c-d (2D points) intersect."""
    def turn(p, q, r):
        return np.sign((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]))
    return turn(a, b, c) * turn(a, b, d) < 0 and turn(c, d, a) * turn(c, d, b) < 0


def _uncrossed_thighs(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> Pose2D:
    """Beyond the paper: two thighs searched one at a time can cross in the image,
    each hip reaching for the other's knee, where the legs overlap and either way
    explains the same silhouette. Then the knees are given back to their own hips,
    each lower leg staying under its knee, unless the crossed pair explains clearly
    more (CROSSED_GAIN) or continues the previous frame's thighs clearly better
    (CROSSED_TURN: a leg swinging past the other, as in a walk seen turned, crosses
    for real)."""
    j = forward_kinematics_2d(pose)
    hips = [j[JOINT_INDEX["hip_l"]], j[JOINT_INDEX["hip_r"]]]
    knees = [j[JOINT_INDEX["knee_l"]], j[JOINT_INDEX["knee_r"]]]
    if pose.spread < UNCROSS_SPREAD or not _segments_cross(hips[0], knees[0], hips[1], knees[1]):
        return pose
    angle, ratio = pose.angle.copy(), pose.ratio.copy()
    for hip, knee, side in ((hips[0], knees[1], "l"), (hips[1], knees[0], "r")):
        k = SEGMENT_INDEX[LEG[side][0]]
        d = knee - hip
        angle[k] = image_angle(d) % 360.0
        ratio[k] = np.clip(np.hypot(*d) / (LENGTH[k] * pose.scale), *RATIO_RANGE)
    uncrossed = _swap_segments(replace(pose, angle=angle, ratio=ratio), [LOWER_LEGS])
    if prev is not None and _thigh_turn(pose, prev) + CROSSED_TURN < _thigh_turn(uncrossed, prev):
        return pose
    scores = leg_scores(canvas, [pose, uncrossed])
    return pose if scores[0] > scores[1] + CROSSED_GAIN else uncrossed


def _thigh_turn(pose: Pose2D, prev: Pose2D) -> float:
    """Degrees both thighs turned since ``prev``."""
    k = [SEGMENT_INDEX[s] for s in UPPER_LEGS]
    return float(np.sum(np.abs((pose.angle[k] - prev.angle[k] + 180.0) % 360.0 - 180.0)))


def _swap_segments(pose: Pose2D, pairs: list[tuple[str, str]]) -> Pose2D:
    """The pose with the angles and ratios of each pair of segments exchanged."""
    angle, ratio = pose.angle.copy(), pose.ratio.copy()
    for a, b in pairs:
        i, j = SEGMENT_INDEX[a], SEGMENT_INDEX[b]
        angle[[i, j]], ratio[[i, j]] = angle[[j, i]], ratio[[j, i]]
    return replace(pose, angle=angle, ratio=ratio)


def _exchange_legs(pose: Pose2D) -> Pose2D:
    """The pose with its two legs' names exchanged."""
    return _swap_segments(pose, [UPPER_LEGS, LOWER_LEGS])


def _best_leg_pairing(canvas: Canvas, pose: Pose2D) -> Pose2D:
    """Score both ways of joining the lower legs to the knees; keep the better
    (a check on Algorithm 5's verdict, which scan lines alone can get wrong)."""
    swapped = _swap_segments(pose, [LOWER_LEGS])
    scores = leg_scores(canvas, [pose, swapped])
    return swapped if scores[1] > scores[0] else pose
