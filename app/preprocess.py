"""Preprocessing a video frame by frame, so that the page shows each frame's
silhouette and fit as soon as it exists.

The two passes of ``mocap.session.fit_video`` (silhouettes, then the 2D fit of each
normalised silhouette, each search centred on the previous fit), as generators over
the session module's own per-frame steps; ``tests/test_app.py`` checks that they
give exactly ``fit_video``'s results. ``Progress`` is how far they are.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mocap.fit2d import FIT_BODY_PX, FIT_SCALE, fit_frame
from mocap.session import MIN_TRACK_SCORE, FrameFit, Silhouette, normalise, torso_spreads
from mocap.silhouette import estimate_background, extract_silhouette
from mocap.video import VideoInfo, iter_frames


@dataclass(frozen=True)
class Progress:
    """How far preprocessing is: ``done`` of ``total`` steps (two per frame)."""

    done: int
    total: int
    stage: str
    error: str | None = None

    @property
    def ready(self) -> bool:
        return self.done == self.total and self.error is None


class Throttle:
    """Passes (done, stage) on at each whole percent of ``total`` and at a new stage."""

    def __init__(self, report: Callable[[int, str], None], total: int):
        self.report, self.total, self.last = report, max(total, 1), (-1, "")

    def __call__(self, done: int, stage: str) -> None:
        key = (100 * done // self.total, stage)
        if key != self.last:
            self.last = key
            self.report(done, stage)


def iter_silhouettes(info: VideoInfo, scale: float) -> Iterator[Silhouette | None]:
    """Pass one (section 3.2): the background, then every frame's silhouette in turn."""
    background = estimate_background(info, scale=scale)
    for _, frame in iter_frames(info, scale=scale):
        yield Silhouette.from_mask(extract_silhouette(frame, background))


def iter_fits(silhouettes: Sequence[Silhouette | None], heights: np.ndarray, scale: float,
              fps: float) -> Iterator[FrameFit]:
    """Pass two (section 3.3): every frame's 2D fit in turn, centred on the previous one."""
    spreads = torso_spreads(list(silhouettes), heights, fps)
    prev = None
    for index, sil in enumerate(silhouettes):
        if sil is None:
            prev = None
            yield FrameFit(index, None, None)
            continue
        small, origin, step = normalise(sil, heights[index])
        fit = fit_frame(small, FIT_SCALE, prev, spreads[index])
        prev = fit.pose if fit.score >= MIN_TRACK_SCORE else None
        joints = (origin + (fit.joints + 0.5) * step - 0.5) / scale
        yield FrameFit(index, joints, fit.score, fit, FIT_BODY_PX * step / scale)
