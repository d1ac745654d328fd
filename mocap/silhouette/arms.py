"""The arms of the 2D fit (section 3.3): first guesses by contour analysis with elbow detection (Algorithms 2-4),
refined by Algorithm 1 (upper arm with the lower attached, then the lower arm) and Algorithm 6. Beyond the paper:
each arm explains only its image side, backward-bending elbows are dropped, the lower arm reaches into a hand
(raster.HAND_LENGTH), and inner edges (mocap.image.edges) place an arm in front of the trunk."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mocap.body import BODY_HEIGHT, JOINT_INDEX, LENGTH, LIMB_JOINTS, SEGMENT_INDEX, SIDES, WIDTH, knee_bend, limb
from mocap.person import SURE
from mocap.silhouette.contour import arm_curve, find_angle, find_elbow_corner
from mocap.silhouette.model2d import Pose2D, forward_kinematics_2d, image_angle
from mocap.silhouette.raster import HAND_LENGTH, Canvas, draw_model, pose_quads, posed_quads, sweep_scorer
from mocap.silhouette.search import RATIO_RANGE, Knob, refine_limb, search_angle, span

ARM = {side: limb("arm", side).segments for side in SIDES}
GUESS_RATIOS = (1.0, 0.8)
ARM_REFINE_HALF_RANGE = 15.0  # degrees searched around an arm's best first guess
KNEE_FACING = 0.01  # knee bend, of body height, that tells the facing side
ELBOW_BACK = 20.0  # degrees an elbow may seem to bend backward (fit noise)
ELBOW_SHOWS_SPREAD = 0.8  # torso spread below which the elbow's bend shows in the image
CROSS_SPREAD = 0.3  # torso spread below which (near profile) an arm may cross the torso's axis
# (upper, lower) angles every 30 degrees all around the shoulder: arm guesses that the
# frame's edges may pick inside the silhouette
ARM_GRID = [(float(u), float(u + b)) for u in range(0, 360, 30) for b in range(-150, 151, 30)]
_GRID_GUESSES = np.array([(*a, GUESS_RATIOS[0], GUESS_RATIOS[0]) for a in ARM_GRID])
GRID_SHORTENED = 16  # the grid's best arms that are also tried at the other GUESS_RATIOS


def _contour_guess(points: np.ndarray, default: tuple[float, float]) -> tuple[float, float]:
    """Upper and lower arm angles from the arm curve (Algorithms 3-4)."""
    corner = find_elbow_corner(points)
    if corner < 0:
        a = find_angle(points, default[0])
        return a, a
    return find_angle(points[: corner + 1], default[0]), find_angle(points[corner:], default[1])


def two_link_angles(start: np.ndarray, end: np.ndarray, l1: float, l2: float) -> list[tuple[float, float]]:
    """(upper, lower) angles, both bends, of a two-segment limb from ``start`` to ``end`` (straight if far)."""
    d = end - start
    dist = float(np.hypot(*d))
    toward = image_angle(d)
    if dist >= l1 + l2 or dist < 1e-6:
        return [(toward, toward)]
    alpha = float(np.degrees(np.arccos(np.clip((l1**2 + dist**2 - l2**2) / (2 * l1 * dist), -1, 1))))
    out = []
    for upper in (toward + alpha, toward - alpha):
        elbow = start + l1 * np.array([np.cos(np.radians(upper)), -np.sin(np.radians(upper))])
        e = end - elbow
        out.append((upper, image_angle(e)))
    return out


def arm_candidates(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None, crossing: bool = False):
    """First guesses (G, 4) of one arm's (upper, lower) angles and ratios: from its side's arm curve (Algorithms
    2-4; ``crossing``: either side's), hanging down, ``prev``'s, and with edges ARM_GRID (last), each new one at
    GUESS_RATIOS (a turned arm is shorter), the grid's at the first."""
    upper, lower = (SEGMENT_INDEX[s] for s in ARM[side])
    angles, guesses = [(270.0, 270.0)], []
    if prev is not None:
        guesses.append(((prev.angle[upper], prev.angle[lower]), (prev.ratio[upper], prev.ratio[lower])))
    joints = forward_kinematics_2d(pose)
    shoulder = joints[JOINT_INDEX[f"shoulder_{side}"]]
    # the curve ends with the hand
    reach = LENGTH[upper] * pose.scale, (LENGTH[lower] + HAND_LENGTH) * pose.scale
    default = guesses[0][0] if guesses else angles[0]
    for runs in SIDES if crossing else (side,):
        points = arm_curve(canvas, joints, side, pose.scale, runs)
        if len(points) >= 3:
            more, straight = _curve_guesses(points, shoulder, default, reach)
            angles += more
            guesses.append(straight)
    guesses += [(a, (r, r)) for a in angles for r in GUESS_RATIOS]
    marked = landmark_guess(canvas, side, pose.scale)
    if marked is not None:
        guesses.append(marked)
    guesses = np.array([(*a, *r) for a, r in guesses])
    return np.concatenate([guesses, _GRID_GUESSES]) if canvas.by_edges and marked is None else guesses


def landmark_guess(canvas: Canvas, side: str, scale: float):
    """The arm as a person model's sure landmarks draw it, ((upper, lower) angles, ratios), or None: the image-side
    shoulder, elbow and wrist targets each at least SURE."""
    targets = canvas.targets
    if targets is None:
        return None
    shoulder, elbow, wrist = (JOINT_INDEX[f"{j}_{side}"] for j in LIMB_JOINTS["arm"])
    if targets.weight[[shoulder, elbow, wrist]].min() < SURE:
        return None
    upper, lower = (targets.points[b] - targets.points[a] for a, b in ((shoulder, elbow), (elbow, wrist)))
    lengths = (LENGTH[SEGMENT_INDEX[s]] * scale for s in ARM[side])
    ratios = tuple(min(float(np.hypot(*v)) / n, RATIO_RANGE[1]) for v, n in zip((upper, lower), lengths))
    return (image_angle(upper), image_angle(lower)), ratios


def _curve_guesses(points: np.ndarray, shoulder: np.ndarray, default: tuple[float, float], reach: tuple[float, float]):
    """An arm curve's (upper, lower) angle guesses (Algorithms 3-4, and the ``reach``-long arm bent either way to
    its farthest point), and the straight arm foreshortened to it: ((u, l), (r, r))."""
    tip = points[np.argmax(np.hypot(*(points - shoulder).T))]
    toward = image_angle(tip - shoulder)
    ratio = min(float(np.hypot(*(tip - shoulder))) / sum(reach), 1.0)
    return [_contour_guess(points, default), *two_link_angles(shoulder, tip, *reach)], (
        (toward, toward),
        (ratio, ratio),
    )


def image_side(shape: tuple[int, int], pose: Pose2D, side: str) -> np.ndarray:
    """Pixels (H, W bool) one arm may explain: its image side of the torso's axis, and above the head."""
    joints = forward_kinematics_2d(pose)
    pelvis, neck = joints[JOINT_INDEX["pelvis"]], joints[JOINT_INDEX["neck"]]
    ys, xs = np.arange(shape[0])[:, None], np.arange(shape[1])[None, :]
    # positive on the image-right of the upward axis (image y points down)
    cross = (neck[0] - pelvis[0]) * (ys - pelvis[1]) - (neck[1] - pelvis[1]) * (xs - pelvis[0])
    return (cross < 0 if side == "l" else cross > 0) | (ys < joints[JOINT_INDEX["head_top"], 1])


def fit_arms(canvas: Canvas, pose: Pose2D, prev: Pose2D | None, facing: int = 0) -> Pose2D:
    """Both arms, each on its image side (``fit_arm``), committed once fitted. Near profile (CROSS_SPREAD) the
    ``facing`` arm comes first and the other may take what is left anywhere, unless it then explains under half a
    hand's area beyond the fitted parts, when it is fitted again on its side."""
    profile = pose.spread < CROSS_SPREAD
    order = ("r", "l") if profile and facing > 0 else SIDES
    for side in order:
        crossing = profile and side == order[1]
        arm = fit_arm(canvas, pose, side, prev, facing, crossing)
        if crossing and 2 * own_pixels(canvas, arm, side) < hand_area(pose.scale):
            arm = fit_arm(canvas, pose, side, prev, facing)
        pose = arm
        canvas.commit(pose_quads(pose, ARM[side]))
    return pose


def hand_area(scale: float) -> float:
    """Pixels a hand covers (HAND_LENGTH by a lower arm's width) at ``scale``."""
    return HAND_LENGTH * WIDTH[SEGMENT_INDEX["lower_arm_l"]] * scale**2


def own_pixels(canvas: Canvas, pose: Pose2D, side: str) -> int:
    """Silhouette pixels that one arm of ``pose`` covers and the canvas's fitted part does not."""
    drawn = draw_model(pose, canvas.sil.shape, ARM[side])
    return int(np.count_nonzero(drawn & canvas.sil & canvas.free))


def fit_arm(
    canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None, facing: int = 0, crossing: bool = False
) -> Pose2D:
    """One arm on its image side (``crossing``: anywhere): the best first guess bending the elbow the way the
    performer faces (``facing``: +1 image right, -1 left, 0 unknown), refined by Algorithms 1 and 6."""
    keep = None if crossing else image_side(canvas.sil.shape, pose, side)
    own = canvas.fork(keep=keep, by_edges=True)
    pose = best_arm_guess(own, pose, side, prev, facing, crossing)
    upper = ARM[side][0]
    pose = search_angle(own, pose, (upper,), ARM[side], *span(pose.angle[SEGMENT_INDEX[upper]], ARM_REFINE_HALF_RANGE))
    return refine_limb(pose, ARM[side], own, ARM_REFINE_HALF_RANGE)


def best_arm_guess(
    canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None, facing: int = 0, crossing: bool = False
) -> Pose2D:
    """The guess best by S of those not bending the elbow back, the grid narrowed as Algorithm 1 narrows."""
    guesses = arm_candidates(canvas, pose, side, prev, crossing)
    backward = elbow_bends_back(guesses[:, 0], guesses[:, 1], pose.spread, facing)
    grid = np.arange(len(guesses)) >= len(guesses) - (len(_GRID_GUESSES) if canvas.by_edges else 0)
    if not backward.all():
        guesses, grid = guesses[~backward], grid[~backward]
    angle, ratio, scores, score = _scored_guesses(canvas, pose, side, guesses)
    if grid.any():
        top = np.flatnonzero(grid)[np.argsort(-scores[grid], kind="stable")[:GRID_SHORTENED]]
        shorter = np.concatenate(
            [np.column_stack([guesses[top, :2], np.full((len(top), 2), r)]) for r in GUESS_RATIOS[1:]]
        )
        more = _scored_guesses(canvas, pose, side, shorter, score)
        angle, ratio, scores = (np.concatenate(pair) for pair in zip((angle, ratio, scores), more[:3]))
    best = int(np.argmax(scores))
    return replace(pose, angle=angle[best], ratio=ratio[best])


def _scored_guesses(canvas: Canvas, pose: Pose2D, side: str, guesses: np.ndarray, score=None):
    """(angles, ratios, S with edges, scorer) of guesses (G, 4); ``score``: an earlier round's scorer."""
    both = Knob("angle", ARM[side])
    pelvis, angle, ratio, spread = both.batch(pose, guesses[:, 0])
    angle[:, both.indices[1]] = guesses[:, 1]
    ratio[:, both.indices] = guesses[:, 2:]
    quads, joints = posed_quads(pelvis, pose.scale, angle, ratio, spread, both.indices)
    scores, score = sweep_scorer(canvas, quads) if score is None else (score(quads), score)
    return angle, ratio, scores + canvas.edge_scores(joints, both.indices, pose.scale), score


def facing_of_knees(pose: Pose2D) -> int:
    """+1/-1 if the knees bend toward image right/left (the performer faces it), 0 if legs are straight."""
    joints = forward_kinematics_2d(pose)[None]
    bend = sum(float(knee_bend(joints, side)[0]) for side in SIDES) / (BODY_HEIGHT * pose.scale)
    return 0 if abs(bend) < KNEE_FACING else int(np.sign(bend))


def elbow_bends_back(upper: np.ndarray, lower: np.ndarray, spread: float, facing: int) -> np.ndarray:
    """Whether arms at ``upper``, ``lower`` degrees (counter-clockwise, y up) bend the elbow back by over
    ELBOW_BACK: told only near profile (ELBOW_SHOWS_SPREAD) with ``facing`` known, never for an arm held up."""
    upper, lower = np.asarray(upper, float), np.asarray(lower, float)
    if not facing or spread >= ELBOW_SHOWS_SPREAD:
        return np.zeros(np.shape(upper), bool)
    held_up = (np.sin(np.radians(upper)) > 0) & (np.sin(np.radians(lower)) > 0)
    return (facing * ((lower - upper + 180.0) % 360.0 - 180.0) < -ELBOW_BACK) & ~held_up
