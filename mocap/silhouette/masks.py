"""The silhouettes out of the fit: mask files (CONTRACT.md's optional "masks"), each
frame's silhouette confidence, and the clip's warning when the background had to
be guessed where the performer never leaves.

A silhouette pixel that the performer covers on every sample of the background
(``Background.held``) was told from an inpainted guess of the scene
(mocap.silhouette.plate), not from the scene itself; a frame's confidence is the
share of its silhouette that was not.
"""

from __future__ import annotations

import os
from pathlib import Path

import cv2
import numpy as np

from mocap.io.export.masks import MaskFolder
from mocap.silhouette.background import Background

HELD_WARNING = 0.1      # median share of the silhouettes over guessed pixels that warns
DOUBTFUL = 0.8          # a frame's silhouette confidence below this is worth a look


def silhouette_confidence(silhouettes: list, background: Background) -> np.ndarray:
    """(F,) each frame's share of silhouette pixels told from the seen scene, in
    [0, 1]; NaN where nobody was found. ``silhouettes`` are session.Silhouette."""
    out = np.full(len(silhouettes), np.nan)
    for i, sil in enumerate(silhouettes):
        if sil is None:
            continue
        mask = sil.mask() > 0
        if background.held is None:
            out[i] = 1.0
            continue
        x0, y0, x1, y1 = sil.box
        out[i] = 1.0 - np.count_nonzero(background.held[y0:y1, x0:x1] & mask) / max(1, np.count_nonzero(mask))
    return out


def held_warning(confidence: np.ndarray) -> str | None:
    """The clip-level warning when the performer never leaves a good part of their
    silhouette (median share over HELD_WARNING), else None."""
    found = confidence[np.isfinite(confidence)]
    if not len(found) or 1.0 - float(np.median(found)) < HELD_WARNING:
        return None
    return (f"the empty scene was never seen under {1.0 - float(np.median(found)):.0%} of the "
            f"performer's silhouette (they stay there), where it is guessed: give a clean plate "
            f"with --background (a photo or short video of the empty scene)")


def write_masks(folder: str | os.PathLike, silhouettes: list, shape: tuple[int, int],
                size: tuple[int, int]) -> Path:
    """Every frame's silhouette as written out (passes.Silhouette.written, in a
    processing frame of ``shape`` (height, width)) as ``folder/NNNNNN.png``: 8-bit,
    255 = performer, the video's ``size`` (width, height); an empty image where
    nobody was found. The folder is
    replaced whole (io.export.masks.MaskFolder), as mocap batch writes it."""
    out = MaskFolder(folder)
    for i, sil in enumerate(silhouettes):
        full = np.zeros(shape, np.uint8) if sil is None else sil.written(shape)
        if full.shape[::-1] != tuple(size):
            full = cv2.resize(full, tuple(size), interpolation=cv2.INTER_NEAREST)
        out.add(i, full)
    return out.finish()
