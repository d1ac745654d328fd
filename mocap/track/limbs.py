"""Finding a limb on a frame, beyond the paper's constant-velocity start (Pan, Zhuang and Liu 2000): the best
directions around its root, and penalties (grey levels added to 1/S) against impossible places."""

from __future__ import annotations

import numpy as np

from mocap import body
from mocap.body import JOINT_INDEX, LENGTH, SEGMENT_INDEX
from mocap.camera import Pinhole
from mocap.image.edges import Edges
from mocap.track import blocks
from mocap.track.blocks import THETA, M, N, X, Y, block_end
from mocap.track.calibration import KEY, MODEL, UNIT_M, calibrate
from mocap.track.keydepths import body_axes, frame_key_depths
from mocap.track.rays import limb_candidates
from mocap.track.rays import limb_penalty as joint_limits

AROUND_STEP = 15.0  # degrees between the directions tried around a limb's root
FOLD_COST = 20.0  # grey levels per unit of overlap: a lower block on its own upper block (limbs look alike),
HEAD_COST = 40.0  # ... an arm's lower block on the head,
TWIN_COST = 25.0  # ... a lower block on its twin's
JUMP_COST = 8.0  # grey levels per usual length that a lower block's ends moved (a hidden limb stays)
TWIN_OVERLAP = 0.3  # overlap of twin lower blocks past which the twins are placed jointly
OVERLAP_POINTS = 8  # points along a lower block's middle line that measure its overlap
OUTLINE_COST = 20.0  # grey levels an arm block pays for long sides without an edge
LEG_OUTLINE_COST = 5.0  # ... a leg block (legs cross, and share their edges where they do)
LIMITS_COST = 10.0  # grey levels per unit of an arm's least joint-limit penalty in 3D
KNEE_STEP = 0.04  # of the shin's length: spacing of the knee places tried (settled_knee)
KNEE_STEPS = 3  # ... that many steps up and down the shin, one to either side
ARM_M = tuple(float(LENGTH[SEGMENT_INDEX[f"{kind}_arm_l"]]) * UNIT_M for kind in ("upper", "lower"))


def overlap(lowers: np.ndarray, others: np.ndarray) -> np.ndarray:
    """How much each block of ``lowers`` (K, 5) lies on ``others``: one block (5,), K blocks or stacks of K (..., K, 5),
    (..., K) in [0, 1]: the mean of max(1 - d / n, 0) along its middle line, d the distance to the other's middle
    line, n the other's width. The lowers' points are placed once for every stack."""
    t = (np.arange(OVERLAP_POINTS) + 0.5) / OVERLAP_POINTS
    length = lowers[:, M, None] * t  # (K, P)
    x = lowers[:, X, None] + length * np.cos(lowers[:, THETA])[:, None]
    y = lowers[:, Y, None] + length * np.sin(lowers[:, THETA])[:, None]
    others = np.broadcast_to(others, np.broadcast_shapes(np.shape(others), lowers.shape))
    cos, sin = np.cos(others[..., THETA])[..., None], np.sin(others[..., THETA])[..., None]
    dx, dy = x - others[..., X, None], y - others[..., Y, None]
    along = np.clip(dx * cos + dy * sin, 0.0, others[..., M, None])
    distance = np.hypot(dx - along * cos, dy - along * sin)
    return np.maximum(1.0 - distance / others[..., N, None], 0.0).mean(axis=-1)


def twin_overlap(lower_a: np.ndarray, lower_b: np.ndarray) -> float:
    """How much two twin limbs' lower blocks lie on one another (``overlap`` both ways)."""
    return float(overlap(lower_a[None], lower_b)[0] + overlap(lower_b[None], lower_a)[0]) / 2


def limb_penalty(root: np.ndarray, width: float, last: np.ndarray, length: float, avoid: tuple = ()) -> blocks.Penalty:
    """Penalty of lower blocks whose upper part (``width``) runs from ``root``: FOLD_COST per overlap with it,
    ``cost`` per overlap with each (cost, block) of ``avoid``, JUMP_COST per ``length`` moved from ``last``."""
    last_end = block_end(last)

    def penalty(lowers: np.ndarray) -> np.ndarray:
        uppers = blocks.between(np.broadcast_to(root, (len(lowers), 2)), lowers[:, :2], width)
        jump = (
            np.linalg.norm(lowers[:, :2] - last[:2], axis=-1) + np.linalg.norm(block_end(lowers) - last_end, axis=-1)
        ) / length
        laps = overlap(lowers, np.stack([uppers, *(np.broadcast_to(block, uppers.shape) for _, block in avoid)]))
        return FOLD_COST * laps[0] + JUMP_COST * jump + sum(cost * lap for (cost, _), lap in zip(avoid, laps[1:]))

    return penalty


def outline_cost(edges: Edges, cost: float = OUTLINE_COST) -> blocks.Penalty:
    """Penalty of blocks (K, 5): ``cost`` times one less their long sides' edge support (Edges.support)."""

    def penalty(candidates: np.ndarray) -> np.ndarray:
        return cost * (
            1.0 - edges.support(candidates[:, None, :2], block_end(candidates)[:, None], candidates[:, None, N])
        )

    return penalty


class TrunkDepth:
    """The tracked key triangle in 3D per frame as the reconstruction finds it (Eq. 6-11, on the side ``turn`` says),
    with the model's chest, against which the limb costs were tuned."""

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
    """(upper, lower) metres of a limb ``kind`` as the marks (16, 2) show it at ``depth``: the longer side's."""
    out = []
    for n in range(2):
        seen = [
            np.linalg.norm(marks[JOINT_INDEX[one.joints[n + 1]]] - marks[JOINT_INDEX[one.joints[n]]])
            for one in body.LIMBS
            if one.kind == kind
        ]
        out.append(max(seen) * depth / camera.focal)
    return out[0], out[1]


def arm_limits_cost(camera: Pinhole, key: np.ndarray, arm: int, cost: float = LIMITS_COST) -> blocks.Penalty:
    """Penalty of lower blocks for the arm's 3D pose from its shoulder in ``key`` (3, 3); ``arm``: 0 left, 1 right."""
    return limits_cost(camera, key[arm], body_axes(key), ARM_M, 1.0 if arm == 0 else -1.0, False, cost)


def leg_limits_cost(
    camera: Pinhole, key: np.ndarray, hip: np.ndarray, leg: int, lengths: tuple[float, float], cost: float = LIMITS_COST
) -> blocks.Penalty:
    """Penalty of a leg's lower blocks for their 3D pose at ``lengths`` from the hip, on its pixel ``hip``'s ray at
    the model trunk's depth under ``key`` (3, 3); ``leg`` 0 left, 1 right."""
    axes = body_axes(key)
    rigid = key[2] + axes @ (MODEL[JOINT_INDEX[("hip_l", "hip_r")[leg]]] - MODEL[JOINT_INDEX["chest"]])
    root = rigid[2] * camera.rays(hip)
    return limits_cost(camera, root, axes, lengths, 1.0 if leg == 0 else -1.0, True, cost)


def limits_cost(
    camera: Pinhole,
    root: np.ndarray,
    axes: np.ndarray,
    lengths: tuple[float, float],
    side: float,
    leg: bool,
    cost: float = LIMITS_COST,
) -> blocks.Penalty:
    """Penalty of lower blocks (K, 5): ``cost`` times the least joint-limit penalty of their ends' four placements at
    ``lengths`` from ``root`` (3,) (rays.limb_candidates); ``axes`` (3, 3); ``side`` +1 left, -1 right."""

    def penalty(lowers: np.ndarray) -> np.ndarray:
        rays = camera.rays(np.stack([lowers[:, :2], block_end(lowers)], axis=1))
        roots = np.broadcast_to(root, (len(lowers), 3))
        placed = limb_candidates(roots, rays, lengths)
        body = np.broadcast_to(axes, (len(lowers), 3, 3))
        return cost * joint_limits(roots, placed, body, leg, side).min(axis=1)

    return penalty


class Summed:
    """Penalties added in turn (a blocks.Penalty), kept apart so that ``least`` can leave the later ones out."""

    def __init__(self, parts: tuple):
        self.parts = parts

    def __call__(self, candidates: np.ndarray) -> np.ndarray:
        total = self.parts[0](candidates)
        for part in self.parts[1:]:
            total = total + part(candidates)
        return total


def added(*penalties: blocks.Penalty) -> Summed:
    """The sum of penalties, sums among them taken apart (``parts``)."""
    return Summed(tuple(part for penalty in penalties for part in parts(penalty)))


def parts(penalty: blocks.Penalty) -> tuple:
    """The penalties a penalty adds up: a Summed's parts, else itself alone."""
    return penalty.parts if isinstance(penalty, Summed) else (penalty,)


def least(base: np.ndarray, candidates: np.ndarray, penalty: blocks.Penalty) -> int:
    """The index of the least ``base`` (K,) plus ``penalty(candidates)`` (K, 5), the penalty's parts after the first
    worked out only where the sum so far is at most the full cost of the least so far: penalties are never negative,
    so elsewhere none can come down to it (around a root the first, a limb's fold and jump, leaves a few percent)."""
    first, *rest = parts(penalty)
    cost = base + first(candidates)
    guess = int(np.argmin(cost))
    ceiling = cost[guess]
    for part in rest:
        ceiling = ceiling + part(candidates[guess : guess + 1])[0]
    kept = np.flatnonzero(cost <= ceiling)
    for part in rest:
        cost[kept] = cost[kept] + part(candidates[kept])
    return int(kept[np.argmin(cost[kept])])


def limb_cost(s: np.ndarray, k: int) -> float:
    """The cost of limb k's placement: its two parts' 1/S."""
    return 1.0 / s[k] + 1.0 / s[k + 1]


def around_root(
    image: np.ndarray,
    root: np.ndarray,
    upper: tuple,
    lower: tuple,
    penalty: blocks.Penalty,
    upper_penalty: blocks.Penalty | None = None,
    upper_weight: float = 1.0,
    upper_scales: tuple[float, ...] = (1.0,),
) -> np.ndarray:
    """The lower block of the least-cost part directions around ``root`` (AROUND_STEP apart, usual lengths, upper at
    ``upper_scales``): weighted 1/S plus penalties. ``upper``, ``lower``: (colour model, grid, width, length)."""
    angles = np.radians(np.arange(0.0, 360.0, AROUND_STEP))
    (model_u, grid_u, n_u, m_u), (model_l, grid_l, n_l, m_l) = upper, lower
    ways = np.c_[np.cos(angles), np.sin(angles)]
    reach = np.repeat(np.asarray(upper_scales) * m_u, len(angles))[:, None]
    uppers = blocks.between(
        np.broadcast_to(root, (len(reach), 2)), root + reach * np.tile(ways, (len(upper_scales), 1)), n_u
    )
    starts = np.repeat(block_end(uppers), len(angles), axis=0)
    lowers = blocks.between(starts, starts + m_l * np.tile(ways, (len(uppers), 1)), n_l)
    upper_cost = upper_weight / blocks.score(image, model_u, grid_u, uppers)
    if upper_penalty is not None:
        upper_cost += upper_penalty(uppers)
    lower_cost = 1.0 / blocks.score(image, model_l, grid_l, lowers)
    return lowers[least(np.repeat(upper_cost, len(angles)) + lower_cost, lowers, penalty)]


def settled_knee(
    image: np.ndarray,
    hip: np.ndarray,
    shin: np.ndarray,
    thigh_part: tuple,
    shin_part: tuple,
    thigh_cost: blocks.Penalty,
    shin_cost: blocks.Penalty,
) -> tuple[np.ndarray, float]:
    """``shin`` and S with the knee moved (7 x 3 places KNEE_STEP apart) where thigh and shin match best: a shin alone
    slides up one-coloured trousers. ``thigh_part``: (model, grid, width); ``shin_part``: (model, grid)."""
    ankle, along = block_end(shin), np.array([np.cos(shin[THETA]), np.sin(shin[THETA])])
    steps = np.arange(-KNEE_STEPS, KNEE_STEPS + 1) * KNEE_STEP * shin[M]
    sideways = np.array([-1.0, 0.0, 1.0]) * KNEE_STEP * shin[M]
    knees = (
        shin[:2] + steps[:, None, None] * along + sideways[None, :, None] * np.array([-along[1], along[0]])
    ).reshape(-1, 2)
    shins = blocks.between(knees, np.broadcast_to(ankle, knees.shape), shin[N])
    thighs = blocks.between(np.broadcast_to(hip, knees.shape), knees, thigh_part[2])
    s_shins = blocks.score(image, *shin_part, shins)
    cost = 1.0 / blocks.score(image, *thigh_part[:2], thighs) + thigh_cost(thighs) + 1.0 / s_shins + shin_cost(shins)
    best = int(np.argmin(cost))
    return shins[best], float(s_shins[best])
