"""The silhouettes as files (CONTRACT.md's ``masks``): a folder of ``NNNNNN.png``, one
per frame (6-digit 0-based index), 8-bit, 255 = performer, at the video's size."""

from __future__ import annotations

import shutil
from pathlib import Path

import cv2
import numpy as np

from mocap.errors import MocapError


def mask_name(index: int) -> str:
    """A frame's mask file name."""
    return f"{index:06d}.png"


class MaskFolder:
    """A masks folder written frame by frame into a hidden folder beside it and put in place whole by
    ``finish``, so a run killed halfway leaves the old folder or none."""

    def __init__(self, folder: str | Path):
        self.folder = Path(folder)
        self.partial = self.folder.with_name(f".{self.folder.name}.partial")
        self.count = 0
        shutil.rmtree(self.partial, ignore_errors=True)
        self._guard(lambda: self.partial.mkdir(parents=True))

    def add(self, index: int, mask: np.ndarray) -> None:
        """Write one frame's mask."""
        if not cv2.imwrite(str(self.partial / mask_name(index)), mask):
            raise MocapError(f"cannot write mask {index} into {self.folder}")
        self.count += 1

    def finish(self) -> Path:
        """Put the written masks in the folder's place."""

        def swap() -> None:
            shutil.rmtree(self.folder, ignore_errors=True)
            self.partial.rename(self.folder)

        self._guard(swap)
        return self.folder

    def _guard(self, action) -> None:
        try:
            action()
        except OSError as exc:
            raise MocapError(f"cannot write the masks folder {self.folder}: {exc.strerror or exc}") from None
