"""The 10 tracked body parts and their colour models (Pan, Zhuang and Liu 2000, "Feature tracking"): morph blocks
between two joints, as wide as their cylinders, searched coarse to fine along Fig. 6's path (``search_part``)."""

from __future__ import annotations

from dataclasses import dataclass

import cv2
import numpy as np

from mocap import body
from mocap.body import JOINT_INDEX, JOINTS, LENGTH, SEGMENT_INDEX, SEGMENTS, SHOULDER_HALF_SPAN, WIDTH, torso_width
from mocap.track import blocks
from mocap.track.blocks import M, N, block_end, from_block

SHORTEST = 0.3  # of a part's longest length: the shortest it is seen (search_part)
LENGTHEN_STEPS = np.arange(1, 6) * 0.03  # of the longest: lengthenings tried (blocks.lengthen)
LENGTHEN_TOLERANCE = 0.03  # relative loss of S a lengthening may cost
FAR_MARGIN_M = 0.1  # metres one shoulder of the marks lies deeper than the other: the far arm
TOLD_APART = 40.0  # grey levels from what lies beside an arm at which its sub-pixel weighs fully
LEAST_WEIGHT = 0.05  # ... the share of its weight a sub-pixel like what lies beside keeps
SAME_CLOTHES = 30.0  # CIELAB a*b* units: a trunk's core this far in chroma from the marked one's is another's clothes


@dataclass(frozen=True)
class Stage:
    """One morph-block search: angle offsets (deg), length offsets (of m), path circles (0: held), px spacing."""

    d_theta_deg: tuple[float, ...]
    d_m: tuple[float, ...]
    rings: int = 0
    step: float = 1.0


def _span(limit: float, step: float) -> tuple[float, ...]:
    return tuple(np.arange(-limit, limit + step / 2, step))


_HELD, _FREE = Stage(_span(2, 1), _span(0.03, 0.03)), Stage(_span(2, 1), _span(0.03, 0.03), 1, 0.5)
_SWING = Stage(_span(30, 5), _span(0.2, 0.1))
SCHEDULES = {  # coarse to fine, by the kind of part
    "head": (Stage(_span(6, 3), _span(0.06, 0.06), 8), _FREE),
    "torso": (Stage(_span(12, 3), _span(0.1, 0.05)), _HELD),
    "lower": (_SWING, Stage(_span(4, 2), (0.0,), 3), _FREE),
}


@dataclass(frozen=True)
class Part:
    """A tracked block from joint ``start`` (its (x, y)) to joint ``end``."""

    segment: str
    start: str
    end: str

    @property
    def schedule(self) -> tuple[Stage, ...]:
        return SCHEDULES[self.segment.split("_")[0]]


# head to feet: the head and the trunk each from its distal to its proximal joint, then
# every limb's two segments from its root
PARTS = (
    *(Part(s, *SEGMENTS[s][::-1]) for s in ("head", "torso")),
    *(Part(s, *SEGMENTS[s]) for one in body.LIMBS for s in one.segments),
)
PART_JOINTS = np.array([[JOINT_INDEX[p.start], JOINT_INDEX[p.end]] for p in PARTS])
HEAD, TORSO = 0, 1
# upper part of each limb (its lower part follows it), in body.LIMBS's order
LIMBS = tuple(2 + 2 * n for n in range(len(body.LIMBS)))
ARMS, LEGS = (tuple(k for k, one in zip(LIMBS, body.LIMBS) if one.kind == kind) for kind in ("arm", "leg"))
TWINS = (ARMS, LEGS)
TWIN_PART = {a + 1: b + 1 for a, b in (ARMS, ARMS[::-1])}  # each forearm's twin


def part_widths(marks: np.ndarray, scale: float) -> np.ndarray:
    """(10,) block widths (px) at ``scale`` px per unit; the torso as wide as the marked shoulders show it."""
    j = JOINT_INDEX
    axis = marks[j["pelvis"]] - marks[j["neck"]]
    normal = np.array([-axis[1], axis[0]]) / max(np.hypot(*axis), 1e-9)
    span = abs((marks[j["shoulder_l"]] - marks[j["shoulder_r"]]) @ normal)
    widths = np.array([WIDTH[SEGMENT_INDEX[p.segment]] for p in PARTS]) * scale
    widths[TORSO] = torso_width(min(span / (2 * SHOULDER_HALF_SPAN * scale), 1.0)) * scale
    return widths


def part_lengths() -> np.ndarray:
    """(10,) model lengths of the parts; an arm's two parts both take the longer (elbows sit differently)."""

    def length(segment: str) -> float:
        if "_arm_" not in segment:
            return float(LENGTH[SEGMENT_INDEX[segment]])
        return float(max(LENGTH[SEGMENT_INDEX[f"{kind}_arm{segment[-2:]}"]] for kind in ("upper", "lower")))

    return np.array([length(p.segment) for p in PARTS])


def skeleton(parts: np.ndarray, chest: np.ndarray) -> np.ndarray:
    """(16, 2) joints of the 10 blocks ``parts``: their ends, the chest at ``chest`` in the trunk's block frame."""
    joints = np.empty((len(JOINTS), 2))
    joints[PART_JOINTS[:, 0]] = parts[:, :2]
    joints[PART_JOINTS[:, 1]] = block_end(parts)
    joints[JOINT_INDEX["chest"]] = from_block(chest, parts[TORSO])
    return joints


def search_part(
    image: np.ndarray,
    model: np.ndarray,
    grid: blocks.Grid,
    start: np.ndarray,
    part: Part,
    longest: float,
    penalty: blocks.Penalty | None = None,
) -> tuple[np.ndarray, float]:
    """The part's block and S searched coarse to fine from ``start`` (blocks.search, charged ``penalty``); every part
    but the head kept within SHORTEST to 1 times ``longest`` px, then lengthened to its end (blocks.lengthen)."""
    best, s = start.copy(), 0.0
    for stage in part.schedule:
        best[M] = np.clip(best[M], SHORTEST * longest, longest)
        best, s = blocks.search(
            image,
            model,
            grid,
            best,
            np.radians(stage.d_theta_deg),
            best[M] * np.asarray(stage.d_m),
            zoom=part.segment == "head",
            max_ring=stage.rings,
            step=stage.step,
            penalty=penalty,
        )
    if part.segment != "head":
        best[M] = np.clip(best[M], SHORTEST * longest, longest)
        extra = LENGTHEN_STEPS * longest
        best, s = blocks.lengthen(image, model, grid, best, extra[best[M] + extra <= longest], LENGTHEN_TOLERANCE)
    return best, s


def far_arm(key_depths: np.ndarray) -> str | None:
    """ "l" or "r": the arm whose shoulder is FAR_MARGIN_M deeper in ``key_depths`` (l, r, chest), else None."""
    gap = key_depths[0] - key_depths[1]
    if abs(gap) < FAR_MARGIN_M:
        return None
    return "l" if gap > 0 else "r"


def far_forearm(key_depths: np.ndarray) -> int | None:
    """Beyond the paper: the far arm's forearm part (None facing or away), matched by its own colours or its twin's
    mirrored: marked behind the trunk, its own are often the shirt's."""
    side = far_arm(key_depths)
    return None if side is None else ARMS[body.SIDES.index(side)] + 1


def mirrored_model(model: np.ndarray, shape: tuple) -> np.ndarray:
    """A colour model (R, C, 3) mirrored across its block (the twin limb's view) and resized to ``shape``."""
    flipped = np.ascontiguousarray(model[:, ::-1])
    return cv2.resize(flipped, (shape[1], shape[0]), interpolation=cv2.INTER_LINEAR)


def beside(block: np.ndarray, side: float) -> np.ndarray:
    """The block moved ``side`` times its width across its middle line."""
    moved = block.copy()
    moved[:2] += blocks.turned((0.0, side * block[N]), block)
    return moved


def told_apart(frame: np.ndarray, block: np.ndarray, grid: blocks.Grid, own: bool = False) -> blocks.Grid:
    """Beyond the paper: ``grid``'s weights (Eq. 5) scaled by each sub-pixel's difference (Eq. 3) from the block moved
    a width aside on the marked ``frame``, over TOLD_APART within [LEAST_WEIGHT, 1] (``own``: other colours weigh 0
    between the joints), so an arm's block beside same-coloured cloth does not match anywhere."""
    model = blocks.sample_blocks(frame, block, grid)[0]
    around = blocks.sample_blocks(frame, np.stack([beside(block, -1.0), beside(block, 1.0)]), grid)
    nearest = (np.abs(model - around) @ blocks.CHANNEL_WEIGHTS).min(axis=0)
    weights = grid.weights * np.clip(nearest / TOLD_APART, LEAST_WEIGHT, 1.0)
    if own:
        weights = weights * own_colour(model, around, grid)
    return blocks.Grid(grid.along, grid.across, (weights / weights.sum()).astype(np.float32))


def core_colour(samples: np.ndarray, grid: blocks.Grid) -> np.ndarray:
    """(3,) the median colour of a block's ``samples`` (R, C, 3) on ``grid`` between its joints in its middle third
    of columns: the part's own colour, whatever a mark a little off its outline took in beside it."""
    inside = (grid.along >= 0) & (grid.along <= 1)
    middle = np.argsort(np.abs(grid.across))[: max(1, len(grid.across) // 3)]
    return np.median(samples[inside][:, middle].reshape(-1, 3), axis=0)


def same_clothes(model: np.ndarray, samples: np.ndarray, grid: blocks.Grid) -> bool:
    """Whether a block's ``samples`` (R, C, 3) on ``grid`` show the clothes of its colour ``model``: their core
    colours (``core_colour``) within SAME_CLOTHES of each other in chroma (CIELAB a*, b*), lightness aside: light
    and shade change a garment's lightness far more than its hue."""
    pair = np.clip(np.stack([core_colour(model, grid), core_colour(samples, grid)]), 0, 255).astype(np.uint8)
    lab = cv2.cvtColor(pair[None], cv2.COLOR_BGR2LAB)[0].astype(float)
    return float(np.hypot(*(lab[0, 1:] - lab[1, 1:]))) <= SAME_CLOTHES


def own_colour(model: np.ndarray, around: np.ndarray, grid: blocks.Grid) -> np.ndarray:
    """(R, C) whether each sub-pixel of ``model`` (R, C, 3) is the part's own colour: past the joints always, else
    nearer the middle columns' median (``core_colour``) than the colours a width out in ``around`` (2, R, C, 3)."""
    inside = (grid.along >= 0) & (grid.along <= 1)
    own = core_colour(model, grid)
    outside = np.stack([around[0, :, 0], around[1, :, -1]], axis=1)  # (R, 2, 3)
    to_own = np.abs(model - own) @ blocks.CHANNEL_WEIGHTS
    to_outside = (np.abs(model[:, :, None] - outside[:, None]) @ blocks.CHANNEL_WEIGHTS).min(axis=-1)
    return (to_own <= to_outside) | ~inside[:, None]


def arm_grids(frame: np.ndarray, parts: np.ndarray, grids: list, far: int | None) -> list:
    """Every part's grid, the arms' ``told_apart`` on the marked ``frame`` (forearms by own colour), but the far arm's
    (``far``: its forearm), whose marked colours are mostly the trunk."""
    hidden = () if far is None else (far - 1, far)
    arms = {k + i for k in ARMS for i in (0, 1)} - set(hidden)
    return [told_apart(frame, parts[k], grid, k - 1 in ARMS) if k in arms else grid for k, grid in enumerate(grids)]
