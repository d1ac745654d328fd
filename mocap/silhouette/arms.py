"""The arms of the 2D fit (section 3.3): first guesses by contour analysis with elbow
detection (Algorithms 2-4), refined by Algorithm 1 (upper arm with the lower arm
attached, then the lower arm) and Algorithm 6. Beyond the paper: each arm explains
only its own image side; guesses whose elbow bends backward (the knees tell which
way the performer faces) are dropped; the model's lower arm reaches on into a hand
(raster.HAND_LENGTH), so the wrist is not put at the silhouette's end; with the
frame's grey levels the edges inside the silhouette along an arm's sides add to S
(mocap.edges), so that an arm in front of the trunk, which the silhouette cannot
place, is found where it shows.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from mocap.body import (BODY_HEIGHT, JOINT_INDEX, LENGTH, SEGMENT_INDEX, SIDES, WIDTH, Pose2D,
                        forward_kinematics_2d, image_angle, knee_bend, limb)
from mocap.silhouette.contour import arm_curve, find_angle, find_elbow_corner
from mocap.silhouette.raster import HAND_LENGTH, Canvas, draw_model, pose_quads, posed_quads, sweep_scorer
from mocap.silhouette.search import Knob, span, refine_limb, search_angle

ARM = {side: limb("arm", side).segments for side in SIDES}
GUESS_RATIOS = (1.0, 0.8)
ARM_REFINE_HALF_RANGE = 15.0     # degrees searched around an arm's best first guess
KNEE_FACING = 0.01               # knee bend, of body height, that tells the facing side
ELBOW_BACK = 20.0                # degrees an elbow may seem to bend backward (fit noise)
ELBOW_SHOWS_SPREAD = 0.8         # torso spread below which the elbow's bend shows in the image
CROSS_SPREAD = 0.3               # torso spread below which (near profile) an arm may cross the torso's axis
# (upper, lower) angles every 30 degrees all around the shoulder: arm guesses that the
# frame's edges may pick inside the silhouette
ARM_GRID = [(float(u), float(u + b)) for u in range(0, 360, 30) for b in range(-150, 151, 30)]
_GRID_GUESSES = np.array([(*a, GUESS_RATIOS[0], GUESS_RATIOS[0]) for a in ARM_GRID])
GRID_SHORTENED = 16              # the grid's best arms that are also tried at the other GUESS_RATIOS


def _contour_guess(points: np.ndarray, default: tuple[float, float]) -> tuple[float, float]:
    """Upper and lower arm angles from the arm curve (Algorithms 3-4)."""
    corner = find_elbow_corner(points)
    if corner < 0:
        a = find_angle(points, default[0])
        return a, a
    return find_angle(points[: corner + 1], default[0]), find_angle(points[corner:], default[1])


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


def arm_candidates(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None, crossing: bool = False):
    """First guesses (G, 4) for one arm's (upper, lower) angles and foreshortening ratios:
    contour analysis (Algorithms 2-4) of the arm curve on its image side (``crossing``:
    on either side), the arm reaching the curve's farthest point bent either way or
    straight and foreshortened, hanging down, the previous frame's arm as it was and,
    where the frame's edges can tell arms inside the silhouette apart, a grid of arms
    all around the shoulder (ARM_GRID, last); each new guess at GUESS_RATIOS of the
    model's lengths (an arm turned toward the camera is shorter in the image, and one
    hanging in front of the trunk scores alike at any length), the grid's at the
    first (``best_arm_guess`` shortens the best of them)."""
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
    guesses = np.array([(*a, *r) for a, r in guesses])
    return np.concatenate([guesses, _GRID_GUESSES]) if canvas.by_edges else guesses


def _curve_guesses(points: np.ndarray, shoulder: np.ndarray, default: tuple[float, float],
                   reach: tuple[float, float]):
    """An arm curve's (upper, lower) angle guesses (Algorithms 3-4, and the arm of
    ``reach`` lengths reaching its farthest point bent either way), and the straight
    arm pointing there foreshortened to reach it: ((upper, lower), (ratio, ratio))."""
    tip = points[np.argmax(np.hypot(*(points - shoulder).T))]
    toward = image_angle(tip - shoulder)
    ratio = min(float(np.hypot(*(tip - shoulder))) / sum(reach), 1.0)
    return [_contour_guess(points, default), *two_link_angles(shoulder, tip, *reach)], ((toward, toward), (ratio, ratio))


def image_side(shape: tuple[int, int], pose: Pose2D, side: str) -> np.ndarray:
    """Pixels on one image side ('l' or 'r') of the torso's axis: an arm explains only
    silhouette on its own side (section 3.3 names limbs by image side), so one arm
    cannot take the other's pixels. Above the head either arm may take them: hands
    raised overhead come together there, and the axis's line beyond the head (off by
    the fitted torso's lean) says nothing of which shoulder a hand belongs to."""
    joints = forward_kinematics_2d(pose)
    pelvis, neck = joints[JOINT_INDEX["pelvis"]], joints[JOINT_INDEX["neck"]]
    ys, xs = np.arange(shape[0])[:, None], np.arange(shape[1])[None, :]
    # positive on the image-right of the upward axis (image y points down)
    cross = (neck[0] - pelvis[0]) * (ys - pelvis[1]) - (neck[1] - pelvis[1]) * (xs - pelvis[0])
    return (cross < 0 if side == "l" else cross > 0) | (ys < joints[JOINT_INDEX["head_top"], 1])


def fit_arms(canvas: Canvas, pose: Pose2D, prev: Pose2D | None, facing: int = 0) -> Pose2D:
    """Both arms, each committed to the canvas once fitted: the image-left one first,
    each on its image side (``fit_arm``). Near profile (torso spread below
    CROSS_SPREAD) both shoulders lie on the torso's axis, which parts the arms only
    when one is in front of the body and one behind it, while arms held in front (a
    guard, a forearm across the chest, a hand raised to the face) lie on one side of
    it: there the arm on the side the performer faces (``facing``, from the knees)
    comes first, on its side, and the other may take whatever silhouette the first
    left anywhere (facing unknown, the image-left arm first); where it then explains
    less than half a hand's area of silhouette beyond the fitted parts (placed by the
    frame's inner edges alone, which the head's own features also show), it is
    fitted again on its side."""
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
    return HAND_LENGTH * WIDTH[SEGMENT_INDEX["lower_arm_l"]] * scale ** 2


def own_pixels(canvas: Canvas, pose: Pose2D, side: str) -> int:
    """Silhouette pixels that one arm of pose covers and the canvas's fitted part does not."""
    drawn = draw_model(pose, canvas.sil.shape, ARM[side])
    return int(np.count_nonzero(drawn & canvas.sil & canvas.free))


def fit_arm(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None,
            facing: int = 0, crossing: bool = False) -> Pose2D:
    """One arm, on its image side (``crossing``: anywhere): the best-scoring first
    guess (among those whose elbow bends the way the performer faces, ``facing`` +1
    image right, -1 left, 0 unknown), refined by Algorithm 1 (upper arm with the lower
    arm attached, then the lower arm) and Algorithm 6."""
    keep = None if crossing else image_side(canvas.sil.shape, pose, side)
    own = canvas.fork(keep=keep, by_edges=True)
    pose = best_arm_guess(own, pose, side, prev, facing, crossing)
    upper = ARM[side][0]
    pose = search_angle(own, pose, (upper,), ARM[side],
                        *span(pose.angle[SEGMENT_INDEX[upper]], ARM_REFINE_HALF_RANGE))
    return refine_limb(pose, ARM[side], own, ARM_REFINE_HALF_RANGE)


def best_arm_guess(canvas: Canvas, pose: Pose2D, side: str, prev: Pose2D | None,
                   facing: int = 0, crossing: bool = False) -> Pose2D:
    """The arm_candidates guess with the highest S, among those that do not bend the
    elbow backward (``elbow_bends_back``) where that can be told. The grid's arms
    are narrowed as Algorithm 1 narrows a search: all at full length first, then
    the GRID_SHORTENED best of them at the other GUESS_RATIOS, on the partial
    silhouette that the first round outlines."""
    guesses = arm_candidates(canvas, pose, side, prev, crossing)
    backward = elbow_bends_back(guesses[:, 0], guesses[:, 1], pose.spread, facing)
    grid = np.arange(len(guesses)) >= len(guesses) - (len(_GRID_GUESSES) if canvas.by_edges else 0)
    if not backward.all():
        guesses, grid = guesses[~backward], grid[~backward]
    angle, ratio, scores, score = _scored_guesses(canvas, pose, side, guesses)
    if grid.any():
        top = np.flatnonzero(grid)[np.argsort(-scores[grid], kind="stable")[:GRID_SHORTENED]]
        shorter = np.concatenate([np.column_stack([guesses[top, :2], np.full((len(top), 2), r)])
                                  for r in GUESS_RATIOS[1:]])
        more = _scored_guesses(canvas, pose, side, shorter, score)
        angle, ratio, scores = (np.concatenate(pair) for pair in zip((angle, ratio, scores), more[:3]))
    best = int(np.argmax(scores))
    return replace(pose, angle=angle[best], ratio=ratio[best])


def _scored_guesses(canvas: Canvas, pose: Pose2D, side: str, guesses: np.ndarray, score=None):
    """(angles, ratios, S with the edges' support, scorer) of one arm's guesses (G, 4)
    posed; ``score``: the scorer of an earlier round (``sweep_scorer``), else the
    guesses outline the partial silhouette themselves."""
    both = Knob("angle", ARM[side])
    pelvis, angle, ratio, spread = both.batch(pose, guesses[:, 0])
    angle[:, both.indices[1]] = guesses[:, 1]
    ratio[:, both.indices] = guesses[:, 2:]
    quads, joints = posed_quads(pelvis, pose.scale, angle, ratio, spread, both.indices)
    scores, score = sweep_scorer(canvas, quads) if score is None else (score(quads), score)
    return angle, ratio, scores + canvas.edge_scores(joints, both.indices, pose.scale), score


def facing_of_knees(pose: Pose2D) -> int:
    """+1 if the knees of a 2D pose bend toward image right (knees bend forward, so
    the performer faces that way), -1 toward image left, 0 if both legs are straight
    (less than KNEE_FACING of body height from their hip-ankle lines)."""
    joints = forward_kinematics_2d(pose)[None]
    bend = sum(float(knee_bend(joints, side)[0]) for side in SIDES) / (BODY_HEIGHT * pose.scale)
    return 0 if abs(bend) < KNEE_FACING else int(np.sign(bend))


def elbow_bends_back(upper: np.ndarray, lower: np.ndarray, spread: float, facing: int) -> np.ndarray:
    """Whether arms whose upper and lower arm point at ``upper`` and ``lower`` degrees
    (counter-clockwise, y up) bend the elbow backward by more than ELBOW_BACK: elbows
    flex toward the front, which the image shows when the body is seen near profile
    (torso spread below ELBOW_SHOWS_SPREAD) and the facing side is known. Not for an
    arm held up (the elbow above the shoulder and the hand above the elbow): raised
    sideways, it turns its bend any way in the image, and arms held up draw the
    shoulders in over a narrowed torso, whose width then reads a profile that is not
    there (a back view with both hands up)."""
    upper, lower = np.asarray(upper, float), np.asarray(lower, float)
    if not facing or spread >= ELBOW_SHOWS_SPREAD:
        return np.zeros(np.shape(upper), bool)
    held_up = (np.sin(np.radians(upper)) > 0) & (np.sin(np.radians(lower)) > 0)
    return (facing * ((lower - upper + 180.0) % 360.0 - 180.0) < -ELBOW_BACK) & ~held_up
