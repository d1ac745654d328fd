"""The silhouettes out of the fit: mask files (CONTRACT.md's optional "masks"), each frame's silhouette
confidence (the share not over the inpainted background, ``Background.held``), and the clip's warning."""

from __future__ import annotations

import os
from collections.abc import Iterator
from pathlib import Path

import cv2
import numpy as np

from mocap.io.export.masks import MaskFolder
from mocap.io.video import VideoInfo, iter_frames, processing_scale
from mocap.silhouette.background import Background
from mocap.silhouette.blend import silhouette_and_cover
from mocap.silhouette.passes import holds_person

HELD_WARNING = 0.1  # median share of the silhouettes over guessed pixels that warns
DOUBTFUL = 0.8  # a frame's silhouette confidence below this is worth a look


def silhouette_confidence(silhouettes: list, background: Background) -> np.ndarray:
    """(F,) each frame's share of silhouette told from the seen scene or by the person model; NaN where
    nobody is."""
    out = np.full(len(silhouettes), np.nan)
    for i, sil in enumerate(silhouettes):
        if sil is None:
            continue
        mask = sil.mask() > 0
        if background.held is None or sil.learned is not None:  # fused: held pixels are the model's (fused_mask)
            out[i] = 1.0
            continue
        x0, y0, x1, y1 = sil.box
        out[i] = 1.0 - np.count_nonzero(background.held[y0:y1, x0:x1] & mask) / max(1, np.count_nonzero(mask))
    return out


def held_warning(confidence: np.ndarray) -> str | None:
    """The clip's warning if the median share of silhouette over guessed pixels is HELD_WARNING, else None."""
    found = confidence[np.isfinite(confidence)]
    if not len(found) or 1.0 - float(np.median(found)) < HELD_WARNING:
        return None
    return (
        f"the empty scene was never seen under {1.0 - float(np.median(found)):.0%} of the "
        f"performer's silhouette (they stay there), where it is guessed: give a clean plate "
        f"with --background (a photo or short video of the empty scene)"
    )


def write_masks(folder: str | os.PathLike, info: VideoInfo, background: Background) -> Path:
    """Every frame's ``written_masks`` as ``folder/NNNNNN.png``, replacing the folder whole."""
    out = MaskFolder(folder)
    for i, mask in enumerate(written_masks(info, background)):
        out.add(i, mask)
    return out.finish()


def write_silhouettes(folder: str | os.PathLike, info: VideoInfo, silhouettes: list) -> Path:
    """The fit's own silhouettes (processing pixels; None: nobody) written as ``write_masks`` does."""
    out = MaskFolder(folder)
    scale, size = processing_scale(info), (info.width, info.height)
    for i, sil in enumerate(silhouettes):
        mask = np.zeros((round(info.height * scale), round(info.width * scale)), np.uint8)
        if sil is not None:
            x0, y0, x1, y1 = sil.box
            mask[y0:y1, x0:x1] = sil.mask() * 255
        out.add(i, video_sized(mask, size))
    return out.finish()


def video_sized(mask: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """A mask at processing size brought to the video's ``size`` (width, height)."""
    return mask if mask.shape[::-1] == size else cv2.resize(mask, size, interpolation=cv2.INTER_NEAREST)


def written_masks(info: VideoInfo, background: Background) -> Iterator[np.ndarray]:
    """Each frame's mask (uint8, 255 = performer, the video's size), from a pass of its own: the cover (blend)
    where the fit's silhouette holds somebody, that silhouette if the cover holds nobody, else empty."""
    size = (info.width, info.height)
    for _, frame in iter_frames(info, scale=processing_scale(info)):
        fit, cover = silhouette_and_cover(frame, background)
        found = cover if holds_person(cover) else fit
        mask = np.where(found > 0, 255, 0).astype(np.uint8) if holds_person(fit) else np.zeros_like(fit)
        yield video_sized(mask, size)
