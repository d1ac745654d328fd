"""The command line's tqdm progress bar, drawn on stderr only when it is a terminal and --quiet
was not given (tqdm is imported only then)."""

from __future__ import annotations

import sys


class Bar:
    """``bar(done, total, stage)`` after each step; a new total starts a new bar; ``close`` before other output."""

    def __init__(self, quiet: bool = False):
        self.quiet = quiet  # the caller's: --quiet, or stderr is not a terminal
        self._bar = None  # the tqdm bar drawn

    def __call__(self, done: int, total: int, stage: str = "") -> None:
        if self.quiet:
            return
        if self._bar is None or self._bar.total != total:
            from tqdm import tqdm

            self.close()
            self._bar = tqdm(total=total, desc=stage or None, file=sys.stderr, unit="step", dynamic_ncols=True)
        elif stage:
            self._bar.set_description(stage, refresh=False)
        self._bar.update(done - self._bar.n)
        if done >= total:
            self.close()

    def step(self, progress) -> None:
        """The bar of a pipeline's step (mocap.pipeline.Progress: done, total, stage)."""
        self(progress.done, progress.total, progress.stage)

    def close(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
