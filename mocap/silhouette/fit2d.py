"""Fitting the 2D cylinder model to a silhouette: the paper's Algorithms 1-6.

All functions work on a silhouette already normalised so that the body is a known
number of pixels tall (``pose.scale`` pixels per model unit); ``session`` does the
cropping and scaling. Left and right are image sides here (section 3.3).

Order of the fit (section 3.3): torso with head (Algorithm 1) and its position,
lower-leg angles by contour analysis (Algorithm 2) with the knee-crossing test
(Algorithm 5), upper legs by Algorithm 1 with the lower legs attached, arms by
contour analysis with elbow detection (Algorithms 2-4), and every segment's
foreshortening ratio (Algorithm 6). Beyond the paper: each search may be centred on
the previous frame's pose (temporal coherence, the paper's future work), contour
estimates are refined by Algorithm 1 on the similarity, and both ways of joining
lower to upper legs are scored so that a wrong crossing verdict is undone; arm
guesses whose elbow bends backward (the knees tell which way the performer faces)
are dropped; with the frame's grey levels, an arm over the trunk counts as inside
the silhouette and the edges inside the silhouette along its sides add to S
(mocap.edges), so that an arm in front of the trunk is found where it shows. The legs are fitted as a few hypotheses scored together
(``leg_hypotheses``), among which ``mocap.silhouette.legchain`` chooses over time.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from mocap.body import (BODY_HEIGHT, JOINT_INDEX, LENGTH, SEGMENT_INDEX, Pose2D,
                        forward_kinematics_2d, forward_kinematics_2d_batch, spread_for_width)
from mocap.silhouette.contour import (arm_curve, find_angle, find_elbow_corner, lower_leg_curves,
                           lower_legs_cross, row_runs)
from mocap.body import knee_bend
from mocap.silhouette.raster import Canvas, draw_model, joint_quads, pose_quads, similarity, sweep_scorer

TORSO_HEAD = ("torso", "head")
LEG = {"l": ("upper_leg_l", "lower_leg_l"), "r": ("upper_leg_r", "lower_leg_r")}
LEGS = LEG["l"] + LEG["r"]
UPPER_LEGS = ("upper_leg_l", "upper_leg_r")
LOWER_LEGS = ("lower_leg_l", "lower_leg_r")
ARM = {"l": ("upper_arm_l", "lower_arm_l"), "r": ("upper_arm_r", "lower_arm_r")}
WAIST_RANGE = (45.0, 135.0)      # Table 1
NECK_RANGE = (45.0, 135.0)       # Table 1
# Wider than Table 1's walking limits (240-300) so that runs and crouches can be
# fitted; frames outside Table 1 are flagged for review instead of forced inside.
THIGH_RANGE = (200.0, 340.0)
RATIO_RANGE = (0.15, 1.15)       # Algorithm 6 searches [0, 1]; real limbs differ from Table 1
TRACK_HALF_RANGE = 20.0          # degrees searched around a previous estimate
THIGH_TRACK_HALF_RANGE = 40.0    # the same for thighs, which swing fastest
ARM_REFINE_HALF_RANGE = 15.0     # degrees searched around an arm's best first guess
ANGLE_SWEEP_STEP = 5.0           # degrees between the poses that outline a search's reach
RATIO_SWEEP_STEP = 0.25          # the same for foreshortening ratios
SILHOUETTE_BLEED_PX = 1.0        # silhouettes come out this much wider than the body
CROSSED_GAIN = 0.02              # S by which crossed thighs must explain more to be kept
CROSSED_TURN = 30.0              # degrees less thigh turn since the last frame that keeps a crossing
UNCROSS_SPREAD = 0.3             # torso spread below which (near profile) thighs may cross
FIT_BODY_PX = 96.0               # body height of the normalised silhouette the fit works on
FIT_SCALE = FIT_BODY_PX / BODY_HEIGHT
KNEE_FACING = 0.01               # knee bend, of body height, that tells the facing side
ELBOW_BACK = 20.0                # degrees an elbow may seem to bend backward (fit noise)
ELBOW_SHOWS_SPREAD = 0.8         # torso spread below which the elbow's bend shows in the image
# (upper, lower) angles every 30 degrees all around the shoulder: arm guesses that the
# frame's edges may pick inside the silhouette
ARM_GRID = [(float(u), float(u + b)) for u in range(0, 360, 30) for b in range(-150, 151, 30)]
DISTINCT_PX = 1.0                # leg hypotheses whose joints all lie this close are one


@dataclass(frozen=True)
class Fit2D:
    """A fitted 2D pose, its joints (pixels of the fitted silhouette) and its S;
    ``alternatives``: the same fit with the other leg hypotheses, for a choice over
    time (``mocap.silhouette.legchain``)."""

    pose: Pose2D
    joints: np.ndarray
    score: float
    alternatives: tuple["Fit2D", ...] = ()


@dataclass(frozen=True)
class Knob:
    """One pose parameter a search turns: 'angle' or 'ratio' of some segments,
    the pelvis's 'x', or the shoulder/hip 'spread'."""

    field: str
    segments: tuple[str, ...] = ()

    def apply(self, pose: Pose2D, value: float) -> Pose2D:
        """The pose with the knob set to value (built directly: this runs per search)."""
        pelvis, angle, ratio, spread = pose.pelvis, pose.angle, pose.ratio, pose.spread
        if self.field == "angle":
            angle = angle.copy()
            angle[self.indices] = value
        elif self.field == "ratio":
            ratio = ratio.copy()
            ratio[self.indices] = value
        elif self.field == "x":
            pelvis = np.array([pelvis[0] + value, pelvis[1]])
        else:
            spread = float(value)
        return Pose2D(pelvis=pelvis, scale=pose.scale, angle=angle, ratio=ratio, spread=spread)

    def batch(self, pose: Pose2D, values: np.ndarray):
        """(pelvis, angle, ratio, spread) arrays of the pose with each value set."""
        n = len(values)
        pelvis = np.repeat(pose.pelvis[None], n, 0)
        angle, ratio = np.repeat(pose.angle[None], n, 0), np.repeat(pose.ratio[None], n, 0)
        spread = np.full(n, pose.spread)
        if self.field in ("angle", "ratio"):
            (angle if self.field == "angle" else ratio)[:, self.indices] = values[:, None]
        elif self.field == "x":
            pelvis[:, 0] += values
        else:
            spread = values
        return pelvis, angle, ratio, spread

    @property
    def indices(self) -> list[int]:
        return [SEGMENT_INDEX[s] for s in self.segments]


def coarse_to_fine(score, n: int, opening: list[int], opening_scores: np.ndarray, start: int,
                   interval: int) -> int:
    """The shared narrowing search of Algorithms 1 and 6 over n ordered values.

    The opening round (a division of the whole range, with the incumbent ``start``,
    already scored) picks the best; ``start`` wins ties, so a flat score keeps it
    (the paper starts from S = 0, which lets a flat score drift to the range's
    start). The interval of two divisions around the best (``interval`` values
    wide) is then divided at full resolution, which ends the narrowing. ``score``
    maps index arrays to S.
    """
    known = dict(zip(opening, opening_scores.tolist()))
    best = max(opening, key=lambda i: (known[i], i == start))
    near = [i for i in range(max(best - interval // 2, 0), min(best + interval // 2, n - 1) + 1)
            if i not in known]
    if not near:
        return best
    known.update(zip(near, score(np.array(near)).tolist()))
    top = max(near, key=known.__getitem__)
    return top if known[top] > known[best] else best


@dataclass(frozen=True)
class Search:
    """One knob to turn over [lo, hi] to ``resolution`` for the drawn segments, first
    divided every ``sweep_step`` (see ``search``)."""

    canvas: Canvas
    knob: Knob
    drawn: tuple[str, ...]
    lo: float
    hi: float
    center: float
    resolution: float
    sweep_step: float


def search(pose: Pose2D, job: Search) -> Pose2D:
    """Turn one knob of pose to maximise S of the drawn segments on their partial
    silhouette: Algorithm 1's (and 6's) narrowing with two levels of division.

    Every value of the grid is posed at once. The first level divides the range
    every ``sweep_step``; those poses also outline the partial silhouette (the
    region the range reaches). The second divides the two divisions around the
    best at full resolution.
    """
    n = max(3, int(round((job.hi - job.lo) / job.resolution)) + 1)
    step = (job.hi - job.lo) / (n - 1)
    values = job.lo + step * np.arange(n)
    pelvis, angle, ratio, spread = job.knob.batch(pose, values)
    joints = forward_kinematics_2d_batch(pelvis, pose.scale, angle, ratio, spread)
    quads = joint_quads(joints, pose.scale, [SEGMENT_INDEX[d] for d in job.drawn], spread)
    every = max(1, int(round(job.sweep_step / step)))
    start = min(max(int(round((job.center - job.lo) / step)), 0), n - 1)
    opening = sorted({*range(0, n, every), n - 1, start})
    drawn = [SEGMENT_INDEX[d] for d in job.drawn]
    first, score = sweep_scorer(job.canvas, quads[opening])
    first = first + job.canvas.edge_scores(joints[opening], drawn, pose.scale)
    best = coarse_to_fine(lambda i: score(quads[i]) + job.canvas.edge_scores(joints[i], drawn, pose.scale),
                          n, opening, first, start, 2 * every)
    return job.knob.apply(pose, float(values[best]))


def search_angle(canvas: Canvas, pose: Pose2D, segments, drawn, lo: float, hi: float,
                 center: float) -> Pose2D:
    """Algorithm 1: rotate segment(s) about the image normal to maximise S (to 1 degree)."""
    return search(pose, Search(canvas, Knob("angle", tuple(segments)), tuple(drawn), lo, hi,
                               center, 1.0, ANGLE_SWEEP_STEP))


def search_ratio(canvas: Canvas, pose: Pose2D, segment: str, drawn) -> Pose2D:
    """Algorithm 6: the foreshortening ratio maximising S (to one pixel of length)."""
    i = SEGMENT_INDEX[segment]
    return search(pose, Search(canvas, Knob("ratio", (segment,)), tuple(drawn), *RATIO_RANGE,
                               pose.ratio[i], 1.0 / max(LENGTH[i] * pose.scale, 1.0),
                               RATIO_SWEEP_STEP))


def refine_limb(pose: Pose2D, limb: tuple[str, str], canvas: Canvas, half_range: float) -> Pose2D:
    """A limb's distal angle within ``half_range`` (Algorithm 1), then its proximal
    and distal foreshortening ratios (Algorithm 6)."""
    upper, lower = limb
    pose = search_angle(canvas, pose, (lower,), (lower,),
                        *_span(pose.angle[SEGMENT_INDEX[lower]], half_range))
    pose = search_ratio(canvas, pose, upper, limb)
    return search_ratio(canvas, pose, lower, (lower,))


def _span(center: float, half: float) -> tuple[float, float, float]:
    return center - half, center + half, center


def _around(prev: Pose2D | None, segment: str, lo: float, hi: float, default: float,
            half: float = TRACK_HALF_RANGE):
    """(lo, hi, centre): within ``half`` of the previous frame's angle, else the whole range."""
    if prev is None:
        return lo, hi, default
    c = float(np.clip(prev.angle[SEGMENT_INDEX[segment]], lo, hi))
    return max(lo, c - half), min(hi, c + half), c


def fit_torso_head(canvas: Canvas, pose: Pose2D, prev: Pose2D | None,
                   spread: float | None = None) -> Pose2D:
    """Torso angle by Algorithm 1 with the head drawn along it (Fig. 3a), the torso's
    horizontal position and foreshortening (unless ``spread`` is given), the head
    angle, then both lengthwise ratios (Algorithm 6)."""
    pose = place_torso(canvas, pose, prev)
    pose = fit_spread(canvas, pose) if spread is None else replace(pose, spread=spread)
    lo, hi, c = _around(prev, "head", *NECK_RANGE, pose.angle[SEGMENT_INDEX["torso"]])
    pose = search_angle(canvas, pose, ("head",), TORSO_HEAD, lo, hi, c)
    pose = search_ratio(canvas, pose, "torso", TORSO_HEAD)
    return search_ratio(canvas, pose, "head", ("head",))


def place_torso(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> Pose2D:
    """The torso's angle (Algorithm 1, head drawn along it) and horizontal position."""
    lo, hi, c = _around(prev, "torso", *WAIST_RANGE, 90.0)
    pose = search_angle(canvas, pose, TORSO_HEAD, TORSO_HEAD, lo, hi, c)
    return fit_pelvis_x(canvas, pose)


def torso_spread(silhouette: np.ndarray, scale: float) -> float:
    """The torso's horizontal foreshortening on one frame (section 3.4), from its
    seen width: the narrowest quarter of the silhouette's widths across the torso's
    middle rows, less the pixel by which edges and the difference threshold widen a
    silhouette, converted by ``body.spread_for_width``. Arms in front of or behind the
    torso widen some rows and some frames, so callers also take a low percentile
    over neighbouring frames (the body turns slowly, arms swing)."""
    ys = np.flatnonzero(silhouette.any(axis=1))
    if len(ys) == 0:
        return 1.0
    head, torso = LENGTH[SEGMENT_INDEX["head"]] * scale, LENGTH[SEGMENT_INDEX["torso"]] * scale
    band = silhouette[int(ys[0] + head + 0.25 * torso): int(ys[0] + head + 0.75 * torso)] > 0
    rows, starts, ends = row_runs(band)
    if len(rows) == 0:
        return 1.0
    widest = np.zeros(band.shape[0])
    np.maximum.at(widest, rows, ends - starts)
    width = (np.percentile(widest[widest > 0], 25) - SILHOUETTE_BLEED_PX) / scale
    return float(spread_for_width(width))


def fit_pelvis_x(canvas: Canvas, pose: Pose2D, reach: float = 12.0) -> Pose2D:
    """The torso's horizontal position by the same search (the paper takes the
    silhouette's middle, which arms and a swinging leg pull off the torso)."""
    r = reach * pose.scale
    return search(pose, Search(canvas, Knob("x"), TORSO_HEAD, -r, r, 0.0, 0.5, 2.0))


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
    for side in "lr":
        pose = search_thigh(canvas, pose, side, prev)
    pose = _uncrossed_thighs(canvas, _best_leg_pairing(canvas, pose), prev)
    for side in "lr":
        pose = refine_limb(pose, LEG[side], canvas, TRACK_HALF_RANGE)
    return pose


def search_thigh(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None) -> Pose2D:
    """One upper leg by Algorithm 1 with its lower leg attached (Fig. 3b-c), near the
    previous frame's when there is one."""
    thigh = LEG[side][0]
    return search_angle(canvas, pose, (thigh,), LEG[side],
                        *_around(prev, thigh, *THIGH_RANGE, 270.0, THIGH_TRACK_HALF_RANGE))


def leg_hypotheses(canvas: Canvas, pose: Pose2D, prev: Pose2D | None) -> list[Pose2D]:
    """Beyond the paper: distinct leg fits, best first by S of both legs together.

    ``fit_legs`` searches the two legs one at a time, so both can take the same leg
    of the silhouette (in profile, where the legs pass each other, the other leg is
    left unexplained). So each leg is also fitted again beside the other
    (``refit_leg_beside``); near profile, each fit also enters with its legs'
    names exchanged, since there the two legs look alike and only their motion over
    time tells which is which (``mocap.silhouette.legchain`` chooses)."""
    first = fit_legs(canvas, pose, prev)
    poses = [first] + [refit_leg_beside(canvas, first, side, prev) for side in "lr"]
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
                        *_span(pose.angle[SEGMENT_INDEX[lower]], TRACK_HALF_RANGE))


def leg_scores(canvas: Canvas, poses: list[Pose2D]) -> np.ndarray:
    """S (Eq. 1-3) of both legs of each pose, on the partial silhouette they outline together."""
    scores, _ = sweep_scorer(canvas, np.stack([pose_quads(p, LEGS) for p in poses]))
    return scores


def _distinct(poses: list[Pose2D]) -> list[Pose2D]:
    """The poses less those whose leg joints all lie within DISTINCT_PX of an earlier one's."""
    legs = [JOINT_INDEX[f"{j}_{s}"] for j in ("hip", "knee", "ankle") for s in "lr"]
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


def fit_spread(canvas: Canvas, pose: Pose2D) -> Pose2D:
    """The torso's horizontal foreshortening (section 3.4): how much of the shoulder
    and hip span is seen, 0 in profile .. 1 frontal, from the torso's seen width,
    by Algorithm 6's search."""
    return search(pose, Search(canvas, Knob("spread"), TORSO_HEAD, 0.0, 1.0, pose.spread, 0.05,
                               RATIO_SWEEP_STEP))


def _contour_guess(points: np.ndarray, default: tuple[float, float]) -> tuple[float, float]:
    """Upper and lower arm angles from the arm curve (Algorithms 3-4)."""
    corner = find_elbow_corner(points)
    if corner < 0:
        a = find_angle(points, default[0])
        return a, a
    return find_angle(points[: corner + 1], default[0]), find_angle(points[corner:], default[1])


def image_angle(d: np.ndarray) -> float:
    """The model's angle (degrees, counter-clockwise from image right) of an image
    vector ``d`` (x right, y down)."""
    return float(np.degrees(np.arctan2(-d[1], d[0])))


def two_link_angles(start: np.ndarray, end: np.ndarray, l1: float, l2: float) -> list[tuple[float, float]]:
    """Angles of a two-segment limb from start whose tip reaches end (both elbow
    bends); a straight limb pointing at end when it is out of reach."""
    d = end - start
    dist = float(np.hypot(*d))
    toward = image_angle(d)
    if dist >= l1 + l2 or dist < 1e-6:
        return [(toward, toward)]
    alpha = float(np.degrees(np.arccos(np.clip((l1 ** 2 + dist ** 2 - l2 ** 2) / (2 * l1 * dist), -1, 1))))
    out = []
    for upper in (toward + alpha, toward - alpha):
        elbow = start + l1 * np.array([np.cos(np.radians(upper)), -np.sin(np.radians(upper))])
        e = end - elbow
        out.append((upper, image_angle(e)))
    return out


def arm_candidates(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None):
    """First guesses for one arm's (upper, lower) angles and foreshortening ratios:
    contour analysis (Algorithms 2-4), the arm reaching the curve's farthest point,
    hanging down, all at the model's lengths, the previous frame's arm as it was and,
    where the frame's edges can tell arms inside the silhouette apart, a grid of
    arms all around the shoulder (ARM_GRID). (An arm hidden in front of the trunk
    scores alike at any length, so a length carried over from frame to frame could
    only shrink.)"""
    upper, lower = (SEGMENT_INDEX[s] for s in ARM[side])
    guesses = [((270.0, 270.0), (1.0, 1.0))]
    if prev is not None:
        guesses.append(((prev.angle[upper], prev.angle[lower]), (prev.ratio[upper], prev.ratio[lower])))
    angles = [guesses[-1][0]]
    joints = forward_kinematics_2d(pose)
    points = arm_curve(canvas, joints, side, pose.scale)
    if len(points) >= 3:
        angles.append(_contour_guess(points, angles[0]))
        shoulder = joints[JOINT_INDEX[f"shoulder_{side}"]]
        tip = points[np.argmax(np.hypot(*(points - shoulder).T))]
        angles += two_link_angles(shoulder, tip, LENGTH[upper] * pose.scale, LENGTH[lower] * pose.scale)
    if canvas.by_edges:
        angles += ARM_GRID
    guesses += [(a, (1.0, 1.0)) for a in angles[1:]]
    return [(*a, *r) for a, r in guesses]


def image_side(shape: tuple[int, int], pose: Pose2D, side: str) -> np.ndarray:
    """Pixels on one image side ('l' or 'r') of the torso's axis: an arm explains only
    silhouette on its own side (section 3.3 names limbs by image side), so one arm
    cannot take the other's pixels."""
    joints = forward_kinematics_2d(pose)
    pelvis, neck = joints[JOINT_INDEX["pelvis"]], joints[JOINT_INDEX["neck"]]
    ys, xs = np.arange(shape[0])[:, None], np.arange(shape[1])[None, :]
    # positive on the image-right of the upward axis (image y points down)
    cross = (neck[0] - pelvis[0]) * (ys - pelvis[1]) - (neck[1] - pelvis[1]) * (xs - pelvis[0])
    return cross < 0 if side == "l" else cross > 0


def fit_arm(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None,
            facing: int = 0) -> Pose2D:
    """One arm, on its image side: the best-scoring first guess (among those whose
    elbow bends the way the performer faces, ``facing`` +1 image right, -1 left, 0
    unknown), refined by Algorithm 1 (upper arm with the lower arm attached, then the
    lower arm) and Algorithm 6."""
    own = canvas.fork(keep=image_side(canvas.sil.shape, pose, side), by_edges=True)
    pose = best_arm_guess(own, pose, side, prev, facing)
    upper = ARM[side][0]
    pose = search_angle(own, pose, (upper,), ARM[side],
                        *_span(pose.angle[SEGMENT_INDEX[upper]], ARM_REFINE_HALF_RANGE))
    return refine_limb(pose, ARM[side], own, ARM_REFINE_HALF_RANGE)


def best_arm_guess(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None,
                   facing: int = 0) -> Pose2D:
    """The arm_candidates guess with the highest S, among those that do not bend the
    elbow backward (``elbow_bends_back``) where that can be told."""
    guesses = np.array(arm_candidates(canvas, pose, side, prev))
    backward = elbow_bends_back(guesses[:, 1] - guesses[:, 0], pose.spread, facing)
    if not backward.all():
        guesses = guesses[~backward]
    both = Knob("angle", ARM[side])
    pelvis, angle, ratio, spread = both.batch(pose, guesses[:, 0])
    angle[:, both.indices[1]] = guesses[:, 1]
    ratio[:, both.indices] = guesses[:, 2:]
    joints = forward_kinematics_2d_batch(pelvis, pose.scale, angle, ratio, spread)
    scores, _ = sweep_scorer(canvas, joint_quads(joints, pose.scale, both.indices, spread))
    scores = scores + canvas.edge_scores(joints, both.indices, pose.scale)
    best = int(np.argmax(scores))
    return replace(pose, angle=angle[best], ratio=ratio[best])


def facing_of_knees(pose: Pose2D) -> int:
    """+1 if the knees of a 2D pose bend toward image right (knees bend forward, so
    the performer faces that way), -1 toward image left, 0 if both legs are straight
    (less than KNEE_FACING of body height from their hip-ankle lines)."""
    joints = forward_kinematics_2d(pose)[None]
    bend = sum(float(knee_bend(joints, side)[0]) for side in "lr") / (BODY_HEIGHT * pose.scale)
    return 0 if abs(bend) < KNEE_FACING else int(np.sign(bend))


def elbow_bends_back(bend: np.ndarray, spread: float, facing: int) -> np.ndarray:
    """Whether arms whose lower arm turns ``bend`` degrees (counter-clockwise, y up)
    from the upper arm bend the elbow backward by more than ELBOW_BACK: elbows flex
    toward the front, which the image shows when the body is seen near profile
    (torso spread below ELBOW_SHOWS_SPREAD) and the facing side is known."""
    if not facing or spread >= ELBOW_SHOWS_SPREAD:
        return np.zeros(np.shape(bend), bool)
    return facing * ((np.asarray(bend) + 180.0) % 360.0 - 180.0) < -ELBOW_BACK


def initial_pose(silhouette: np.ndarray, scale: float) -> Pose2D:
    """Torso location from Table 1 ratios: the head at the silhouette's top, the pelvis
    head+torso lengths below, x at the horizontal middle of the silhouette there."""
    rows = np.flatnonzero(silhouette.any(axis=1))
    top, bottom = int(rows[0]), int(rows[-1])
    head = LENGTH[SEGMENT_INDEX["head"]] * scale
    pelvis_y = min(top + head + LENGTH[SEGMENT_INDEX["torso"]] * scale, bottom)
    xs = np.nonzero(silhouette[int(top + head): int(pelvis_y) + 1])[1]
    x = float(np.median(xs)) if len(xs) else float(np.median(np.nonzero(silhouette)[1]))
    return Pose2D(pelvis=np.array([x, pelvis_y]), scale=scale)


def fit_frame(silhouette: np.ndarray, scale: float, prev: Pose2D | None = None,
              spread: float | None = None, grey: np.ndarray | None = None) -> Fit2D:
    """Fit the 10-cylinder model to one normalised silhouette (section 3.3) with the
    best leg hypothesis, the others as ``alternatives``; with ``spread`` the torso's
    horizontal foreshortening is taken as given; with the frame's ``grey`` levels
    (same size) the arms also follow the edges inside the silhouette."""
    canvas = Canvas(silhouette, grey)
    pose = initial_pose(canvas.sil, scale)
    if prev is not None:
        pose = replace(prev, pelvis=pose.pelvis, scale=scale)
    pose = fit_torso_head(canvas, pose, prev, spread)
    canvas.commit(pose_quads(pose, TORSO_HEAD))
    legs = leg_hypotheses(canvas, pose, prev)
    pose = legs[0]
    canvas.commit(pose_quads(pose, LEGS))
    facing = facing_of_knees(pose)
    for side in ("l", "r"):
        pose = fit_arm(canvas, pose, side, prev, facing)
        canvas.commit(pose_quads(pose, ARM[side]))
    others = tuple(with_legs(canvas.sil, pose, other) for other in legs[1:])
    return Fit2D(pose, forward_kinematics_2d(pose), canvas.score_model(), others)


def with_legs(silhouette: np.ndarray, pose: Pose2D, legs: Pose2D) -> Fit2D:
    """The fit of pose with the legs of ``legs``, scored on the whole silhouette (Eq. 3)."""
    k = [SEGMENT_INDEX[s] for s in LEGS]
    angle, ratio = pose.angle.copy(), pose.ratio.copy()
    angle[k], ratio[k] = legs.angle[k], legs.ratio[k]
    pose = replace(pose, angle=angle, ratio=ratio)
    return Fit2D(pose, forward_kinematics_2d(pose), similarity(silhouette, draw_model(pose, silhouette.shape)))
