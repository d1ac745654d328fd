"""The legs of the 2D fit (section 3.3, Fig. 3b-c): lower legs by contour analysis (Algorithm 2) with the
knee-crossing test (Algorithm 5), upper legs by Algorithm 1 with the lower legs attached, ratios by Algorithm 6.
Beyond the paper: pairings checked by S, crossed thighs uncrossed, raised knees' lower legs searched over every
bend, and a few leg hypotheses (``leg_hypotheses``) for ``legchain`` to choose among over time."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mocap.body import FOOT_LENGTH, JOINT_INDEX, LEG_JOINTS, LENGTH, SEGMENT_INDEX, SIDES, limb
from mocap.person import SURE
from mocap.silhouette.contour import find_angle, lower_leg_band, lower_leg_curves, lower_legs_cross
from mocap.silhouette.model2d import Pose2D, forward_kinematics_2d, image_angle
from mocap.silhouette.raster import Canvas, pose_quads, poses_quads, sweep_scorer
from mocap.silhouette.search import RATIO_RANGE, TRACK_HALF_RANGE, Knob, around, refine_limb, search_angle, span

LEG = {side: limb("leg", side).segments for side in SIDES}
LEGS = LEG["l"] + LEG["r"]
UPPER_LEGS, LOWER_LEGS = tuple(zip(LEG["l"], LEG["r"]))
# Wider than Table 1's walking limits (240-300) so that runs and crouches can be
# fitted (a deep squat's thighs are level or above); frames outside Table 1 are
# flagged for review instead of forced inside.
THIGH_RANGE = (175.0, 365.0)
THIGH_TRACK_HALF_RANGE = 40.0  # degrees searched around a previous thigh, which swings fastest
CROSSED_GAIN = 0.02  # S by which crossed thighs must explain more to be kept
CROSSED_TURN = 30.0  # degrees less thigh turn since the last frame that keeps a crossing
UNCROSS_SPREAD = 0.3  # torso spread below which (near profile) thighs may cross
KNEE_REACH = 150.0  # degrees a knee folds at most, seen in the image
RAISED_KNEE = 0.5  # of a thigh's length above Algorithm 2's rows: a raised knee
ONE_LEG_SHARE = 0.5  # of Algorithm 2's rows with two runs or more, below which they show one leg
FOOT_REACH = 1.5  # feet's lengths (FOOT_LENGTH) of silhouette past a raised ankle at most
THIGH_MATCH = 0.75  # of the other thigh's length in the image, below which a raised "thigh" is not one
DISTINCT_PX = 1.0  # leg hypotheses whose joints all lie this close are one


def fit_legs(canvas: Canvas, pose: Pose2D, prev: Pose2D | None, reading, raised: float) -> Pose2D:
    """Lower legs by Algorithms 2 and 5 (``reading``: ``contour.lower_leg_curves``'s), thighs by Algorithm 1 with
    them attached (Fig. 3b-c), lower legs refined by Algorithm 1, ratios by Algorithm 6; a knee raised above the
    row ``raised`` took the other leg's curve, so its lower leg is searched over every bend (``search_shin``)."""
    curves, runs = reading
    crossed = lower_legs_cross(runs)
    for side, other in (("l", "r"), ("r", "l")):
        default = (prev or pose).angle[SEGMENT_INDEX[LEG[side][1]]]
        pose = Knob("angle", (LEG[side][1],)).apply(pose, find_angle(curves[other if crossed else side], default))
    for side in SIDES:
        pose = search_thigh(canvas, pose, side, prev)
    pose = _uncrossed_thighs(canvas, _best_leg_pairing(canvas, pose), prev)
    for side in SIDES:
        if raised_leg(pose, side, raised):
            pose = search_shin(canvas.fork(pose_quads(pose, LEG[other_side(side)])), pose, side)
        pose = refine_limb(pose, LEG[side], canvas, TRACK_HALF_RANGE)
    return pose


def raised_knee_row(sil: np.ndarray, joints: np.ndarray, scale: float, runs) -> float:
    """The image row above which a knee is raised: RAISED_KNEE of a thigh above Algorithm 2's rows where fewer
    than ONE_LEG_SHARE of them show two runs; -inf where they show two. ``scale``: pixels per unit."""
    if not len(runs) or np.mean(np.asarray(runs) >= 2) >= ONE_LEG_SHARE:
        return -np.inf
    top = lower_leg_band(sil, joints, scale)[0]
    return top - RAISED_KNEE * LENGTH[SEGMENT_INDEX[LEG["l"][0]]] * scale


def raised_leg(pose: Pose2D, side: str, row: float) -> bool:
    """Whether a knee is above image ``row`` on a thigh THIGH_MATCH as long as the other (else a hand)."""
    up, other = SEGMENT_INDEX[LEG[side][0]], SEGMENT_INDEX[LEG[other_side(side)][0]]
    return bool(
        row > -np.inf
        and pose.ratio[up] >= THIGH_MATCH * pose.ratio[other]
        and forward_kinematics_2d(pose)[JOINT_INDEX[f"knee_{side}"], 1] < row
    )


def other_side(side: str) -> str:
    return "r" if side == "l" else "l"


def search_shin(canvas: Canvas, pose: Pose2D, side: str) -> Pose2D:
    """One lower leg by Algorithm 1 over every bend of its knee (within KNEE_REACH and THIGH_RANGE), kept if it
    ends the silhouette as a raised lower leg does (``ends_in_foot``), else the pose as it was."""
    t, at = (pose.angle[SEGMENT_INDEX[s]] for s in LEG[side])
    lo, hi = max(t - KNEE_REACH, THIGH_RANGE[0]), min(t + KNEE_REACH, THIGH_RANGE[1])
    at = 270.0 + (at - 270.0 + 180.0) % 360.0 - 180.0
    found = search_angle(canvas, pose, (LEG[side][1],), (LEG[side][1],), lo, hi, min(max(at, lo), hi))
    return found if ends_in_foot(canvas.sil, found, side) else pose


def ends_in_foot(sil: np.ndarray, pose: Pose2D, side: str) -> bool:
    """Whether one side's lower leg ends where the silhouette does: its ankle inside, and no more than FOOT_REACH
    feet of silhouette past it (else it was hung from a hand or laid along the other leg)."""
    j = forward_kinematics_2d(pose)
    knee, ankle = j[JOINT_INDEX[f"knee_{side}"]], j[JOINT_INDEX[f"ankle_{side}"]]
    step = (ankle - knee) / max(np.hypot(*(ankle - knee)), 1e-6)
    reach = np.arange(int(FOOT_REACH * FOOT_LENGTH * pose.scale) + 2)
    x, y = np.round(ankle + step * reach[:, None]).astype(int).T
    inside = (0 <= x) & (x < sil.shape[1]) & (0 <= y) & (y < sil.shape[0])
    inside[inside] = sil[y[inside], x[inside]] > 0
    return bool(inside[0] and not inside[1:].all())


def search_thigh(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None) -> Pose2D:
    """One upper leg by Algorithm 1 with its lower leg attached (Fig. 3b-c), near ``prev``'s if given."""
    thigh = LEG[side][0]
    return search_angle(
        canvas, pose, (thigh,), LEG[side], *around(prev, thigh, *THIGH_RANGE, 270.0, THIGH_TRACK_HALF_RANGE)
    )


def leg_hypotheses(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> list[Pose2D]:
    """Beyond the paper: distinct leg fits, best first by S of both legs together: ``fit_legs``, each leg
    refitted beside the other (both may take the same leg), and near profile each with the legs' names exchanged,
    which only their motion over time tells apart (``legchain``)."""
    joints = forward_kinematics_2d(pose)
    reading = lower_leg_curves(canvas.sil, joints, pose.scale)
    raised = raised_knee_row(canvas.sil, joints, pose.scale, reading[1])
    first = fit_legs(canvas, pose, prev, reading, raised)
    poses = [first]
    if not legs_marked(canvas):
        poses += [refit_leg_beside(canvas, first, side, prev, raised) for side in SIDES]
    if pose.spread < UNCROSS_SPREAD:
        poses += [_exchange_legs(p) for p in poses]
    poses = _distinct(poses)
    order = np.argsort(-leg_scores(canvas, poses), kind="stable")
    return [poses[i] for i in order]


def legs_marked(canvas: Canvas) -> bool:
    """Whether a person model's landmarks mark both legs (hips, knees and ankles each at least SURE)."""
    marks = canvas.targets
    return marks is not None and marks.weight[LEG_JOINTS].min() >= SURE


def refit_leg_beside(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None, raised: float) -> Pose2D:
    """One leg refitted with the other taken as fitted: the thigh by Algorithm 1 from ``prev``'s lower-leg angle,
    then the lower leg; lengths stay (beside the other leg, Algorithm 6 would shrink it)."""
    beside = canvas.fork(pose_quads(pose, LEG[other_side(side)]))
    lower = LEG[side][1]
    pose = Knob("angle", (lower,)).apply(pose, (prev or pose).angle[SEGMENT_INDEX[lower]])
    pose = search_thigh(beside, pose, side, prev)
    if raised_leg(pose, side, raised):
        return search_shin(beside, pose, side)
    return search_angle(beside, pose, (lower,), (lower,), *span(pose.angle[SEGMENT_INDEX[lower]], TRACK_HALF_RANGE))


def leg_scores(canvas: Canvas, poses: list[Pose2D]) -> np.ndarray:
    """S (Eq. 1-3) of both legs of each pose, on the partial silhouette they outline together."""
    scores, _ = sweep_scorer(canvas, poses_quads(poses, LEGS))
    return scores


def _distinct(poses: list[Pose2D]) -> list[Pose2D]:
    """The poses less those whose leg joints all lie within DISTINCT_PX of an earlier one's."""
    out, seen = [], []
    for pose in poses:
        joints = forward_kinematics_2d(pose)[LEG_JOINTS]
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
    """Beyond the paper: thighs crossing in the image get their own knees back (lower legs staying under them)
    unless crossed explains clearly more (CROSSED_GAIN) or continues ``prev`` better (CROSSED_TURN)."""
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
    """The better by S of both ways of joining lower legs to knees (checks Algorithm 5's verdict)."""
    swapped = _swap_segments(pose, [LOWER_LEGS])
    scores = leg_scores(canvas, [pose, swapped])
    return swapped if scores[1] > scores[0] else pose
