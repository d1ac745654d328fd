"""How often the page hears of a run's progress (mocap.pipeline.Progress): each
frame's silhouette and fit are kept as they come, the page redrawn at each whole
percent."""

from __future__ import annotations

from typing import Callable


class Throttle:
    """Passes (done, stage) on at each whole percent of ``total`` and at a new stage."""

    def __init__(self, report: Callable[[int, str], None], total: int):
        self.report, self.total, self.last = report, max(total, 1), (-1, "")

    def __call__(self, done: int, stage: str) -> None:
        key = (100 * done // self.total, stage)
        if key != self.last:
            self.last = key
            self.report(done, stage)
