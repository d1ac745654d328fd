"""Choosing each frame's legs over time (beyond the paper): where the legs pass in profile S (Eq. 3) tells the
hypotheses (``legs.leg_hypotheses``) apart badly, so fixed-lag Viterbi picks the path maximising S less
SMOOTH_WEIGHT times the knees' and ankles' motion (each by name); a frame without a person ends the path."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from mocap.body import JOINT_INDEX, LIMB_JOINTS, SIDES
from mocap.silhouette.fit2d import FIT_BODY_PX, Fit2D

LAG_S = 0.5  # seconds of later frames seen before a frame's legs are chosen
SMOOTH_WEIGHT = 1.0  # S given up per body height that knees and ankles move (mean)
_LEG_JOINTS = [JOINT_INDEX[f"{j}_{s}"] for s in SIDES for j in LIMB_JOINTS["leg"][1:]]


def leg_offsets(fit: Fit2D) -> np.ndarray:
    """(4, 2) knees and ankles about the pelvis, in body heights."""
    return (fit.joints[_LEG_JOINTS] - fit.joints[JOINT_INDEX["pelvis"]]) / FIT_BODY_PX


def motion_cost(before: list[Fit2D], after: list[Fit2D]) -> np.ndarray:
    """(len(before), len(after)): SMOOTH_WEIGHT times the mean distance the knees and ankles move."""
    a = np.stack([leg_offsets(f) for f in before])[:, None]
    b = np.stack([leg_offsets(f) for f in after])[None]
    return SMOOTH_WEIGHT * np.linalg.norm(a - b, axis=-1).mean(-1)


@dataclass
class _Frame:
    item: Any
    options: list[Fit2D]
    back: np.ndarray = field(default_factory=lambda: np.zeros(0, int))


class LegChain:
    """Fixed-lag Viterbi over the frames' leg hypotheses: ``push`` an item (returned as is) with its fit, or None
    where nobody is; get the (item, chosen fit) pairs now decided, in frame order."""

    def __init__(self, lag: int):
        self.lag = lag
        self.frames: list[_Frame] = []
        self.cost = np.zeros(0)

    def push(self, item, fit: Fit2D | None) -> list[tuple[Any, Fit2D | None]]:
        if fit is None:
            return self.flush() + [(item, None)]
        options = [replace(fit, alternatives=())] + list(fit.alternatives)
        gain = -np.array([f.score for f in options])
        frame = _Frame(item, options)
        if self.frames:
            total = self.cost[:, None] + motion_cost(self.frames[-1].options, options)
            frame.back = np.argmin(total, axis=0)
            gain = gain + total[frame.back, np.arange(len(options))]
        self.frames.append(frame)
        self.cost = gain
        return self._decided(len(self.frames) - self.lag)

    @property
    def current(self) -> Fit2D | None:
        """The newest frame's hypothesis on the best path so far (None before any)."""
        return self.frames[-1].options[int(np.argmin(self.cost))] if self.frames else None

    def flush(self) -> list[tuple[Any, Fit2D | None]]:
        """Decide every frame still held; the next push starts a new path."""
        out = self._decided(len(self.frames))
        self.cost = np.zeros(0)
        return out

    def _decided(self, count: int) -> list[tuple[Any, Fit2D | None]]:
        """The first ``count`` held frames on the best path, released."""
        if count <= 0:
            return []
        path = [int(np.argmin(self.cost))]
        for frame in reversed(self.frames[1:]):
            path.append(int(frame.back[path[-1]]))
        path.reverse()
        out = [(f.item, f.options[k]) for f, k in zip(self.frames[:count], path)]
        self.frames = self.frames[count:]
        return out
