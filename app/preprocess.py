"""How far preprocessing is, reported to the page as the two passes of
``mocap.session`` (``iter_silhouettes``, ``iter_fits``) run frame by frame, so that
the page shows each frame's silhouette and fit as soon as it exists."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable


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
