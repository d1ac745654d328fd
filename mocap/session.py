"""From a video file to a fitted 2D body on every frame: the pipeline the command
line and the app share.

Two passes over the video, both streamed: silhouettes (section 3.2), kept as small
bit-packed crops, then the 2D fit (section 3.3) on each crop normalised to the
model's size. The body's height in pixels comes from the silhouettes' heights
around each frame, so a performer who walks toward the camera keeps a right scale.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import cv2
import numpy as np

from mocap.body import MIRROR_JOINTS, Pose2D
from mocap.errors import MocapError
from mocap.export.motion_json import write_motion
from mocap.fit2d import FIT_BODY_PX, FIT_SCALE, Fit2D, fit_frame, torso_spread
from mocap.silhouette import estimate_background, extract_silhouette
from mocap.video import VideoInfo, iter_frames, open_video, processing_scale

Progress = Callable[[int, int], None]
MIN_PERSON_FRACTION = 0.002     # of the frame's area: smaller blobs are nobody
SCALE_PERCENTILE = 90           # of silhouette heights around a frame: the standing height
SCALE_WINDOW_S = 1.0            # half-width of that window, seconds
MARGIN = 0.25                   # of the body height, around the silhouette's box when fitting
SPREAD_PERCENTILE = 5           # of torso foreshortening estimates around a frame
SPREAD_WINDOW_S = 0.5           # half-width of that window, seconds
MIN_TRACK_SCORE = 0.5           # a previous fit below this is not used as a search centre


@dataclass(frozen=True)
class Silhouette:
    """A frame's silhouette as its bounding box and the packed mask inside it."""

    box: tuple[int, int, int, int]          # x0, y0, x1, y1 in processing pixels
    bits: np.ndarray

    @classmethod
    def from_mask(cls, mask: np.ndarray) -> "Silhouette | None":
        x, y, w, h = cv2.boundingRect((mask > 0).astype(np.uint8))
        if w * h == 0 or np.count_nonzero(mask) < MIN_PERSON_FRACTION * mask.size:
            return None
        return cls((x, y, x + w, y + h), np.packbits(mask[y:y + h, x:x + w] > 0))

    @property
    def height(self) -> int:
        return self.box[3] - self.box[1]

    def mask(self) -> np.ndarray:
        x0, y0, x1, y1 = self.box
        n = (x1 - x0) * (y1 - y0)
        return np.unpackbits(self.bits, count=n).reshape(y1 - y0, x1 - x0)


@dataclass(frozen=True)
class FrameFit:
    """The fit of one frame: joints in original video pixels (image sides), or
    nothing when no person was found."""

    index: int
    joints2d: np.ndarray | None
    score: float | None
    fit: Fit2D | None = None


def extract_silhouettes(info: VideoInfo, scale: float,
                        progress: Progress | None = None) -> list[Silhouette | None]:
    """Pass one: background (section 3.2) and every frame's silhouette."""
    background = estimate_background(info, scale=scale)
    out = []
    for index, frame in iter_frames(info, scale=scale):
        out.append(Silhouette.from_mask(extract_silhouette(frame, background)))
        if progress:
            progress(index + 1, info.frame_count)
    return out


def body_heights(silhouettes: list[Silhouette | None], fps: float) -> np.ndarray:
    """The standing body height in pixels around each frame (NaN where nobody is):
    a high percentile of the silhouette heights within SCALE_WINDOW_S."""
    h = np.array([np.nan if s is None else s.height for s in silhouettes], float)
    return rolling_percentile(h, max(1, int(round(SCALE_WINDOW_S * fps))), SCALE_PERCENTILE)


def normalise(sil: Silhouette, body_px: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The silhouette cropped with a margin and resized to FIT_BODY_PX body height;
    returns (mask, origin in processing pixels, pixels of processing per fit pixel)."""
    factor = FIT_BODY_PX / body_px
    pad = int(np.ceil(MARGIN * body_px))
    mask = cv2.copyMakeBorder(sil.mask() * 255, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
    h, w = mask.shape
    size = (max(1, round(w * factor)), max(1, round(h * factor)))
    interp = cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR
    small = cv2.resize(mask, size, interpolation=interp) > 127
    origin = np.array([sil.box[0] - pad, sil.box[1] - pad], float)
    return small.astype(np.uint8), origin, w / size[0]


def torso_spreads(silhouettes: list[Silhouette | None], heights: np.ndarray, fps: float) -> np.ndarray:
    """Each frame's torso horizontal foreshortening, as a low percentile of the
    per-frame estimates within SPREAD_WINDOW_S (arms passing the torso widen it)."""
    raw = np.full(len(silhouettes), np.nan)
    for i, sil in enumerate(silhouettes):
        if sil is not None:
            raw[i] = torso_spread(normalise(sil, heights[i])[0], FIT_SCALE)
    return rolling_percentile(raw, max(1, int(round(SPREAD_WINDOW_S * fps))), SPREAD_PERCENTILE)


def rolling_percentile(values: np.ndarray, half: int, q: float) -> np.ndarray:
    """The q-th percentile of the finite values within +-half of each finite entry."""
    out = np.full(len(values), np.nan)
    for i in np.flatnonzero(np.isfinite(values)):
        out[i] = np.nanpercentile(values[max(0, i - half): i + half + 1], q)
    return out


def fit_silhouettes(silhouettes: list[Silhouette | None], heights: np.ndarray, scale: float,
                    fps: float, progress: Progress | None = None) -> list[FrameFit]:
    """Pass two: the 2D fit of every frame, each search centred on the previous fit."""
    spreads = torso_spreads(silhouettes, heights, fps)
    fits: list[FrameFit] = []
    prev: Pose2D | None = None
    for index, sil in enumerate(silhouettes):
        if sil is None:
            fits.append(FrameFit(index, None, None))
            prev = None
        else:
            small, origin, step = normalise(sil, heights[index])
            fit = fit_frame(small, FIT_SCALE, prev, spreads[index])
            joints = (origin + (fit.joints + 0.5) * step - 0.5) / scale
            fits.append(FrameFit(index, joints, fit.score, fit))
            prev = fit.pose if fit.score >= MIN_TRACK_SCORE else None
        if progress:
            progress(index + 1, len(silhouettes))
    return fits


def fit_video(path: str | os.PathLike, progress: Progress | None = None) -> tuple[VideoInfo, list[FrameFit]]:
    """Silhouettes and 2D fits for every frame of a video."""
    info = open_video(path)
    scale = processing_scale(info)
    total = 2 * info.frame_count
    first = (lambda d, _t: progress(d, total)) if progress else None
    second = (lambda d, _t: progress(info.frame_count + d, total)) if progress else None
    silhouettes = extract_silhouettes(info, scale, first)
    if all(s is None for s in silhouettes):
        raise MocapError(f"{info.path}: no person found in any of its {info.frame_count} frames")
    heights = body_heights(silhouettes, info.fps)
    return info, fit_silhouettes(silhouettes, heights, scale, info.fps, second)


def anatomical(joints_image_side: np.ndarray) -> np.ndarray:
    """Image-side joints to the performer's own sides, for a performer facing the
    camera (their left on the image's right). The 3D stage decides from the
    orientation; until then this is the default reading."""
    return joints_image_side[MIRROR_JOINTS]


def motion_frames(fits: list[FrameFit]) -> list[dict]:
    """Motion-file entries: joints2d and score where a person was fitted, else person: false."""
    frames = []
    for f in fits:
        if f.joints2d is None:
            frames.append({"index": f.index, "keyframe": False, "person": False})
        else:
            frames.append({"index": f.index, "keyframe": True, "person": True, "score": f.score,
                           "joints2d": anatomical(f.joints2d)})
    return frames


def video_dict(info: VideoInfo) -> dict:
    return {"path": info.path, "width": info.width, "height": info.height, "fps": info.fps,
            "frame_count": info.frame_count}


def fit_video_to_file(video: str | os.PathLike, out: str | os.PathLike | None, *,
                      progress: Progress | None = None) -> Path:
    """`mocap fit`: fit every frame and write the motion file."""
    info, fits = fit_video(video, progress)
    out = Path(out) if out else Path(video).with_suffix(".motion.json")
    return write_motion(out, video_dict(info), motion_frames(fits))
