"""The narrowing search of the paper's Algorithms 1 and 6: turn one pose parameter over a range to maximise S
(Eq. 1-3) of the drawn segments on their partial silhouette."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mocap.body import LENGTH, SEGMENT_INDEX
from mocap.silhouette.model2d import Pose2D
from mocap.silhouette.raster import Canvas, posed_quads, sweep_scorer

RATIO_RANGE = (0.15, 1.15)  # Algorithm 6 searches [0, 1]; real limbs differ from Table 1
TRACK_HALF_RANGE = 20.0  # degrees searched around a previous estimate
ANGLE_SWEEP_STEP = 5.0  # degrees between the poses that outline a search's reach
RATIO_SWEEP_STEP = 0.25  # the same for foreshortening ratios
ONE_ROUND = 31  # grids of at most this many values (a limb's 30 degrees) are scored in one round


@dataclass(frozen=True)
class Knob:
    """One pose parameter a search turns: 'angle' or 'ratio' of ``segments``, the pelvis's 'x', or 'spread'."""

    field: str
    segments: tuple[str, ...] = ()

    def apply(self, pose: Pose2D, value: float) -> Pose2D:
        """The pose with the knob set to ``value``."""
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
        """(pelvis, angle, ratio, spread) of the pose with each value set: angles, ratios (B, 10); pelvis (2,)
        and spread (float) as the pose has them, (B, 2) and (B,) if the knob turns them."""
        n = len(values)
        pelvis, angle, ratio, spread = (
            pose.pelvis,
            pose.angle[None].repeat(n, 0),
            pose.ratio[None].repeat(n, 0),
            pose.spread,
        )
        if self.field == "angle":
            angle[:, self.indices] = values[:, None]
        elif self.field == "ratio":
            ratio[:, self.indices] = values[:, None]
        elif self.field == "x":
            pelvis = np.asarray(pelvis, float)[None].repeat(n, 0)
            pelvis[:, 0] += values
        else:
            spread = values
        return pelvis, angle, ratio, spread

    @property
    def indices(self) -> list[int]:
        return [SEGMENT_INDEX[s] for s in self.segments]


def coarse_to_fine(score, n: int, opening: list[int], opening_scores: list[float], start: int, interval: int) -> int:
    """The narrowing of Algorithms 1 and 6 over n values: the best of the scored ``opening`` (``start`` winning
    ties, so a flat score keeps it), then the ``interval`` around it; ``score`` maps indices to S."""
    known = dict(zip(opening, opening_scores))
    best = max(opening, key=lambda i: (known[i], i == start))
    near = [i for i in range(max(best - interval // 2, 0), min(best + interval // 2, n - 1) + 1) if i not in known]
    if not near:
        return best
    known.update(zip(near, score(near)))
    top = max(near, key=known.__getitem__)
    return top if known[top] > known[best] else best


@dataclass(frozen=True)
class Search:
    """One knob turned over [lo, hi] to ``resolution`` for the drawn segments, divided every ``sweep_step``."""

    canvas: Canvas
    knob: Knob
    drawn: tuple[str, ...]
    lo: float
    hi: float
    center: float
    resolution: float
    sweep_step: float


def search(pose: Pose2D, job: Search) -> Pose2D:
    """Turn one knob of ``pose`` to maximise S of the drawn segments on their partial silhouette (Algorithms 1,
    6): a first division every ``sweep_step`` outlines it, a second at full resolution around the best."""
    n = max(3, int(round((job.hi - job.lo) / job.resolution)) + 1)
    step = (job.hi - job.lo) / (n - 1)
    values = job.lo + step * np.arange(n)
    pelvis, angle, ratio, spread = job.knob.batch(pose, values)
    drawn = [SEGMENT_INDEX[d] for d in job.drawn]
    quads, joints = posed_quads(pelvis, pose.scale, angle, ratio, spread, drawn)
    every = max(1, int(round(job.sweep_step / step)))
    start = min(max(int(round((job.center - job.lo) / step)), 0), n - 1)
    opening = sorted({*range(0, n, every), n - 1, start})

    def edges(i) -> np.ndarray:
        return job.canvas.edge_scores(joints[i], drawn, pose.scale) + job.canvas.landmark_scores(
            joints[i], drawn, pose.scale
        )

    if n <= ONE_ROUND:
        scores = (sweep_scorer(job.canvas, quads, opening)[0] + edges(slice(None))).tolist()
        best = coarse_to_fine(
            lambda i: [scores[k] for k in i], n, opening, [scores[k] for k in opening], start, 2 * every
        )
    else:
        first, score = sweep_scorer(job.canvas, quads[opening])
        best = coarse_to_fine(
            lambda i: (score(quads[i]) + edges(i)).tolist(),
            n,
            opening,
            (first + edges(opening)).tolist(),
            start,
            2 * every,
        )
    return job.knob.apply(pose, float(values[best]))


def search_angle(canvas: Canvas, pose: Pose2D, segments, drawn, lo: float, hi: float, center: float) -> Pose2D:
    """Algorithm 1: rotate segment(s) about the image normal to maximise S (to 1 degree)."""
    return search(
        pose, Search(canvas, Knob("angle", tuple(segments)), tuple(drawn), lo, hi, center, 1.0, ANGLE_SWEEP_STEP)
    )


def search_ratio(canvas: Canvas, pose: Pose2D, segment: str, drawn) -> Pose2D:
    """Algorithm 6: the foreshortening ratio maximising S (to one pixel of length)."""
    i = SEGMENT_INDEX[segment]
    return search(
        pose,
        Search(
            canvas,
            Knob("ratio", (segment,)),
            tuple(drawn),
            *RATIO_RANGE,
            pose.ratio[i],
            1.0 / max(LENGTH[i] * pose.scale, 1.0),
            RATIO_SWEEP_STEP,
        ),
    )


def refine_limb(pose: Pose2D, limb: tuple[str, str], canvas: Canvas, half_range: float) -> Pose2D:
    """A limb's distal angle within ``half_range`` (Algorithm 1), then both its ratios (Algorithm 6)."""
    upper, lower = limb
    pose = search_angle(canvas, pose, (lower,), (lower,), *span(pose.angle[SEGMENT_INDEX[lower]], half_range))
    pose = search_ratio(canvas, pose, upper, limb)
    return search_ratio(canvas, pose, lower, (lower,))


def span(center: float, half: float) -> tuple[float, float, float]:
    return center - half, center + half, center


def around(prev: Pose2D | None, segment: str, lo: float, hi: float, default: float, half: float = TRACK_HALF_RANGE):
    """(lo, hi, centre): within ``half`` of the previous frame's angle, else the whole range."""
    if prev is None:
        return lo, hi, default
    middle = (lo + hi) / 2  # the previous angle's turn nearest the range
    c = min(max(float(middle + (prev.angle[SEGMENT_INDEX[segment]] - middle + 180.0) % 360.0 - 180.0), lo), hi)
    return max(lo, c - half), min(hi, c + half), c
