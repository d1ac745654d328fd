"""Finding a limb on a frame, beyond the tracking paper's constant-velocity start
(Pan, Zhuang and Liu, *Video motion capture in VBA*, 2000, section "Feature
tracking"): the best pair of directions of its parts all around its root
(``around_root``), and the penalties that keep its lower part off the places where
it cannot be: its own upper part, the head for an arm, its twin's lower part, far
from where it was (``limb_penalty``), sides without edges (``outline_cost``), a pose
a human limb cannot take in 3D (``arm_limits_cost``, ``leg_limits_cost``, from the key
triangle followed as the reconstruction does, ``TrunkDepth``); a leg's knee settled where its thigh and
shin match best together (``settled_knee``).
"""

from __future__ import annotations

import numpy as np

from mocap import body
from mocap.body import JOINT_INDEX, LENGTH, SEGMENT_INDEX
from mocap.edges import Edges
from mocap.track import blocks
from mocap.track.blocks import M, N, THETA, X, Y, block_end
from mocap.track.calibration import KEY, MODEL, UNIT_M, Pinhole, calibrate
from mocap.track.keydepths import body_axes, frame_key_depths
from mocap.track.rays import limb_candidates, limb_penalty as joint_limits

AROUND_STEP = 15.0         # degrees between the directions tried around a limb's root
FOLD_COST = 20.0           # grey levels per unit of overlap: a lower block on its own upper block,
HEAD_COST = 40.0           # ... an arm's lower block on the head,
TWIN_COST = 25.0           # ... a lower block on its twin's
JUMP_COST = 8.0            # grey levels per usual length that a lower block's ends moved
TWIN_OVERLAP = 0.3         # overlap of twin lower blocks past which the twins are placed jointly
OVERLAP_POINTS = 8         # points along a lower block's middle line that measure its overlap
OUTLINE_COST = 20.0        # grey levels an arm block pays for long sides without an edge
LEG_OUTLINE_COST = 5.0     # ... a leg block (legs cross, and share their edges where they do)
LIMITS_COST = 10.0         # grey levels per unit of an arm's least joint-limit penalty in 3D
KNEE_STEP = 0.04           # of the shin's length: spacing of the knee places tried (settled_knee)
KNEE_STEPS = 3             # ... that many steps up and down the shin, one to either side
ARM_M = tuple(float(LENGTH[SEGMENT_INDEX[f"{kind}_arm_l"]]) * UNIT_M for kind in ("upper", "lower"))


def overlap(lowers: np.ndarray, other: np.ndarray) -> np.ndarray:
    """Beyond the paper: how much each of the blocks ``lowers`` (K, 5) lies on the
    block ``other`` (5,) (or each on its own of K blocks), in [0, 1]: the mean over
    OVERLAP_POINTS points along its middle line of 1 - d / n, d the point's distance
    to other's middle line (a segment) and n other's width, at least 0."""
    t = (np.arange(OVERLAP_POINTS) + 0.5) / OVERLAP_POINTS
    length = lowers[:, M, None] * t                                        # (K, P)
    other = np.broadcast_to(other, lowers.shape)
    cos, sin = np.cos(other[:, THETA])[:, None], np.sin(other[:, THETA])[:, None]
    dx = lowers[:, X, None] + length * np.cos(lowers[:, THETA])[:, None] - other[:, X, None]
    dy = lowers[:, Y, None] + length * np.sin(lowers[:, THETA])[:, None] - other[:, Y, None]
    along = np.clip(dx * cos + dy * sin, 0.0, other[:, M, None])
    distance = np.hypot(dx - along * cos, dy - along * sin)
    return np.maximum(1.0 - distance / other[:, N, None], 0.0).mean(axis=1)


def twin_overlap(lower_a: np.ndarray, lower_b: np.ndarray) -> float:
    """How much two twin limbs' lower blocks lie on one another (``overlap`` both ways)."""
    return float(overlap(lower_a[None], lower_b)[0] + overlap(lower_b[None], lower_a)[0]) / 2


def limb_penalty(root: np.ndarray, width: float, last: np.ndarray, length: float,
                 avoid: tuple = ()) -> blocks.Penalty:
    """Beyond the paper: the penalty (grey levels) of candidate lower blocks of a limb
    whose upper part, ``width`` wide, runs from ``root`` to the lower block's start:

    - FOLD_COST per unit of overlap with that upper part and ``cost`` per unit of
      overlap with each ``(cost, block)`` of ``avoid``: limbs look alike along their
      length (one colour of sleeve or trousers) and alike to their twins, so that a
      lower part folded back onto its own upper part, or lying on its twin, matches
      at little cost where the limb itself is hidden or hard to see;
    - JUMP_COST per ``length`` (the part's usual length) that the block's two ends
      (the limb's middle and end joints) moved from those of ``last``, the last
      frame's block: a limb hidden on a frame stays near where it was rather than
      jump to clutter that matches it as well.
    """
    def penalty(lowers: np.ndarray) -> np.ndarray:
        uppers = blocks.between(np.broadcast_to(root, (len(lowers), 2)), lowers[:, :2], width)
        jump = (np.linalg.norm(lowers[:, :2] - last[:2], axis=-1)
                + np.linalg.norm(block_end(lowers) - block_end(last), axis=-1)) / length
        return FOLD_COST * overlap(lowers, uppers) + JUMP_COST * jump + sum(
            cost * overlap(lowers, block) for cost, block in avoid)
    return penalty


def outline_cost(edges: Edges, cost: float = OUTLINE_COST) -> blocks.Penalty:
    """Beyond the paper: the penalty (grey levels) of blocks (K, 5) for the edges
    their two long sides lack, ``cost`` times one less the mean edge strength there
    (edges.Edges.support). An arm over the trunk or a sleeve over a shirt matches the
    colours under it as well as its own place does (an arm hidden behind the trunk
    matches the trunk), and a forearm matches skin-coloured clutter; the arm's own
    place shows its outline."""
    def penalty(candidates: np.ndarray) -> np.ndarray:
        return cost * (1.0 - edges.support(candidates[:, None, :2], block_end(candidates)[:, None],
                                           candidates[:, None, N]))
    return penalty


class TrunkDepth:
    """Beyond the paper, while tracking: the tracked key triangle (both shoulders and
    the chest) in 3D on every frame, as the reconstruction finds it (calibrated on
    the marks, Eq. 6-9, then Eq. 10-11 from frame to frame on the side ``turn`` says;
    mocap.track.keydepths.frame_key_depths), but with the model's chest: the limbs'
    costs were weighed against that triangle, and with the chest fitted
    (calibration.calibrate) the tracked 2D moves on some frames of every clip
    (track_salsa's mean 2.71 -> 2.81%, track_walk's 2.69 -> 2.45)."""

    def __init__(self, marks: np.ndarray, camera: Pinhole, turn: str | None):
        self.camera, self.turn = camera, turn
        self.depths, self.sides = calibrate(marks, camera, turn, MODEL[KEY[2], 1]).key_triangle()
        self.leg_lengths = marked_lengths(marks, camera, float(self.depths.mean()), "leg")

    def follow(self, key2d: np.ndarray) -> np.ndarray:
        """(3, 3) the key joints (pinhole frame) of a new frame's (3, 2) key pixels."""
        rays = self.camera.rays(key2d)
        self.depths = frame_key_depths(rays, self.depths, self.sides, self.turn)
        return self.depths[:, None] * rays


def marked_lengths(marks: np.ndarray, camera: Pinhole, depth: float, kind: str) -> tuple[float, float]:
    """The (upper, lower) bone lengths (metres) of a kind of limb ("arm", "leg") as
    the marks (16, 2) show them at ``depth``: each the longer of its two sides'.
    Bones foreshortened on the marked frame read short; the model's lengths
    (body.LENGTH) are no better: at the scale of the key triangle calibrated on
    the marks they are 1.2 to 1.4 times the marked legs of the shared perspective
    clips (motion capture), and a bone taken too long is given depth it does not
    have."""
    out = []
    for n in range(2):
        seen = [np.linalg.norm(marks[JOINT_INDEX[one.joints[n + 1]]] - marks[JOINT_INDEX[one.joints[n]]])
                for one in body.LIMBS if one.kind == kind]
        out.append(max(seen) * depth / camera.focal)
    return out[0], out[1]


def arm_limits_cost(camera: Pinhole, key: np.ndarray, arm: int,
                    cost: float = LIMITS_COST) -> blocks.Penalty:
    """Beyond the paper: the penalty (grey levels) of an arm's candidate lower blocks
    (K, 5) for the pose they give it in 3D (``limits_cost`` from the shoulder, a key
    joint of ``key`` (3, 3), at the model's arm lengths ARM_M). Where the colours
    leave an arm's place open (a sleeve over the shirt, a hidden arm), the places a
    human arm can take win. ``arm``: 0 left, 1 right."""
    return limits_cost(camera, key[arm], body_axes(key), ARM_M, 1.0 if arm == 0 else -1.0, False, cost)


def leg_limits_cost(camera: Pinhole, key: np.ndarray, hip: np.ndarray, leg: int,
                    lengths: tuple[float, float], cost: float = LIMITS_COST) -> blocks.Penalty:
    """Beyond the paper: the penalty (grey levels) of a leg's candidate lower blocks
    (K, 5) for the pose they give it in 3D (``limits_cost`` at bone ``lengths``
    (TrunkDepth.leg_lengths) from the hip, on the ray of its pixel ``hip`` (2,) at
    the depth the model trunk carried rigidly by ``key`` (3, 3) gives it). Twin legs
    look alike, and dark trousers match dark clutter: a shin folded up beside its
    thigh, a thigh across the other leg, are places a human leg does not take.
    ``leg``: 0 left, 1 right."""
    axes = body_axes(key)
    rigid = key[2] + axes @ (MODEL[JOINT_INDEX[("hip_l", "hip_r")[leg]]] - MODEL[JOINT_INDEX["chest"]])
    root = rigid[2] * camera.rays(hip)
    return limits_cost(camera, root, axes, lengths, 1.0 if leg == 0 else -1.0, True, cost)


def limits_cost(camera: Pinhole, root: np.ndarray, axes: np.ndarray, lengths: tuple[float, float],
                side: float, leg: bool, cost: float = LIMITS_COST) -> blocks.Penalty:
    """The penalty (grey levels) of a limb's candidate lower blocks (K, 5) for the
    pose they give it in 3D. The middle joint (the block's start) and the end joint
    (its end) lie on their viewing rays at bone ``lengths`` from the limb's ``root``
    (3,), pinhole frame, in one of four ways (mocap.track.rays.limb_candidates);
    ``cost`` times the least joint-limit penalty of the four (the silhouette method's
    limits: hinges bent the right way, no upper arm or thigh through the trunk, limbs
    near the sagittal plane) in the body frame ``axes`` (3, 3) (columns: the
    performer's left, up, forward). ``side``: +1 left, -1 right."""
    def penalty(lowers: np.ndarray) -> np.ndarray:
        rays = camera.rays(np.stack([lowers[:, :2], block_end(lowers)], axis=1))
        roots = np.broadcast_to(root, (len(lowers), 3))
        placed = limb_candidates(roots, rays, lengths)
        body = np.broadcast_to(axes, (len(lowers), 3, 3))
        return cost * joint_limits(roots, placed, body, leg, side).min(axis=1)
    return penalty


def added(*penalties: blocks.Penalty) -> blocks.Penalty:
    """The sum of penalties."""
    return lambda candidates: sum(penalty(candidates) for penalty in penalties)


def limb_cost(s: np.ndarray, k: int) -> float:
    """The cost of limb k's placement: its two parts' 1/S."""
    return 1.0 / s[k] + 1.0 / s[k + 1]


def around_root(image: np.ndarray, root: np.ndarray, upper: tuple, lower: tuple,
                penalty: blocks.Penalty, upper_penalty: blocks.Penalty | None = None,
                upper_weight: float = 1.0, upper_scales: tuple[float, ...] = (1.0,)) -> np.ndarray:
    """Beyond the paper: the lower block of a limb hanging from ``root`` of the pair
    of directions of its two parts, AROUND_STEP degrees apart, each part at its
    usual length (the upper part at each of ``upper_scales`` times it), of least
    cost (``upper_weight`` times the upper block's 1/S plus the lower block's, the
    lower block's ``penalty`` and the upper block's ``upper_penalty``). A limb lost
    to clutter or to its twin is found again where it shows. ``upper`` and
    ``lower`` are each (colour model, grid, width, length)."""
    angles = np.radians(np.arange(0.0, 360.0, AROUND_STEP))
    (model_u, grid_u, n_u, m_u), (model_l, grid_l, n_l, m_l) = upper, lower
    ways = np.c_[np.cos(angles), np.sin(angles)]
    reach = np.repeat(np.asarray(upper_scales) * m_u, len(angles))[:, None]
    uppers = blocks.between(np.broadcast_to(root, (len(reach), 2)),
                            root + reach * np.tile(ways, (len(upper_scales), 1)), n_u)
    starts = np.repeat(block_end(uppers), len(angles), axis=0)
    lowers = blocks.between(starts, starts + m_l * np.tile(ways, (len(uppers), 1)), n_l)
    upper_cost = upper_weight / blocks.score(image, model_u, grid_u, uppers)
    if upper_penalty is not None:
        upper_cost += upper_penalty(uppers)
    cost = upper_cost[:, None] + (1.0 / blocks.score(image, model_l, grid_l, lowers)
           + penalty(lowers)).reshape(len(uppers), -1)
    return lowers[int(np.argmin(cost))]


def settled_knee(image: np.ndarray, hip: np.ndarray, shin: np.ndarray, thigh_part: tuple,
                 shin_part: tuple, thigh_cost: blocks.Penalty,
                 shin_cost: blocks.Penalty) -> tuple[np.ndarray, float]:
    """Beyond the paper: a leg's ``shin`` block and its S with the knee moved to where
    the thigh (from ``hip``) and the shin (to its ankle, which stays) match best
    together (both 1/S and the blocks' penalties ``thigh_cost`` and ``shin_cost``),
    among knee places KNEE_STEP of the shin apart around the shin's start (7 x 3).
    ``thigh_part``: (colour model, grid, width); ``shin_part``: (colour model, grid).
    A shin's search alone sees one colour of trousers above the knee as below it and
    slides its start up the thigh (tracked knees sat 1.4% of the body's height short
    along the thigh, median; benchmarks/bench_track.py). Elbows are not settled so: a
    sleeve over the shirt gives the upper arm's block nothing to match (the arms'
    mean error rose 6.1 -> 6.3% of the body's height)."""
    ankle, along = block_end(shin), np.array([np.cos(shin[THETA]), np.sin(shin[THETA])])
    steps = np.arange(-KNEE_STEPS, KNEE_STEPS + 1) * KNEE_STEP * shin[M]
    sideways = np.array([-1.0, 0.0, 1.0]) * KNEE_STEP * shin[M]
    knees = (shin[:2] + steps[:, None, None] * along
             + sideways[None, :, None] * np.array([-along[1], along[0]])).reshape(-1, 2)
    shins = blocks.between(knees, np.broadcast_to(ankle, knees.shape), shin[N])
    thighs = blocks.between(np.broadcast_to(hip, knees.shape), knees, thigh_part[2])
    s_shins = blocks.score(image, *shin_part, shins)
    cost = (1.0 / blocks.score(image, *thigh_part[:2], thighs) + thigh_cost(thighs)
            + 1.0 / s_shins + shin_cost(shins))
    best = int(np.argmin(cost))
    return shins[best], float(s_shins[best])
