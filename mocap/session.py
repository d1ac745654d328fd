"""From a video file to a 3D animation: the pipeline the command line and the app share.

Two passes over the video, both streamed: silhouettes (section 3.2), kept as small
bit-packed crops, then the 2D fit (section 3.3) on each crop normalised to the
model's size. The body's height in pixels comes from the silhouettes' heights
around each frame, so a performer who walks toward the camera keeps a right scale.

Then ``Session`` owns the video's per-frame fits and the user's annotations: it
resolves the lifting inputs (orientation, sides, overrides, signs: the user's over
the first guess of ``mocap.lift.orientation``), lifts the keyframes (section 3.4), and
interpolates the other frames (``mocap.lift.motion``). An edit of the annotations
re-resolves the inputs and re-lifts the clip (milliseconds both).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from collections.abc import Iterator
from typing import Callable

import cv2
import numpy as np

from mocap.io.annotations import Annotations, load_annotations
from mocap.body import JOINTS, Pose2D, reported_joints
from mocap.errors import MocapError
from mocap.io.export.motion_json import write_motion
from mocap.lift.motion import Motion, build_motion
from mocap.lift.inputs import Inputs, resolve_inputs, root_track
from mocap.silhouette.legchain import LAG_S, LegChain
from mocap.lift.orientation import guess_orientations
from mocap.silhouette.fit2d import FIT_BODY_PX, FIT_SCALE, Fit2D, fit_frame, torso_spread
from mocap.silhouette.background import estimate_background, extract_silhouette
from mocap.io.video import VideoInfo, iter_frames, open_video, processing_scale

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
    """A frame's silhouette as its bounding box and the packed mask inside it, with
    the frame's grey levels in the box (the inner edges' source, mocap.edges)."""

    box: tuple[int, int, int, int]          # x0, y0, x1, y1 in processing pixels
    bits: np.ndarray
    grey: np.ndarray | None = None

    @classmethod
    def from_mask(cls, mask: np.ndarray, frame: np.ndarray | None = None) -> "Silhouette | None":
        x, y, w, h = cv2.boundingRect((mask > 0).astype(np.uint8))
        if w * h == 0 or np.count_nonzero(mask) < MIN_PERSON_FRACTION * mask.size:
            return None
        grey = None if frame is None else cv2.cvtColor(frame[y:y + h, x:x + w], cv2.COLOR_BGR2GRAY)
        return cls((x, y, x + w, y + h), np.packbits(mask[y:y + h, x:x + w] > 0), grey)

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
    body_px: float | None = None    # video pixels of the model's 175-unit body height


def iter_silhouettes(info: VideoInfo, scale: float) -> Iterator[Silhouette | None]:
    """Pass one (section 3.2): the background, then every frame's silhouette in turn."""
    background = estimate_background(info, scale=scale)
    for _, frame in iter_frames(info, scale=scale):
        yield Silhouette.from_mask(extract_silhouette(frame, background), frame)


def extract_silhouettes(info: VideoInfo, scale: float,
                        progress: Progress | None = None) -> list[Silhouette | None]:
    """Pass one as a list, with progress."""
    return _collect(iter_silhouettes(info, scale), info.frame_count, progress)


def _collect(items: Iterator, total: int, progress: Progress | None) -> list:
    out = []
    for item in items:
        out.append(item)
        if progress:
            progress(len(out), total)
    return out


def body_heights(silhouettes: list[Silhouette | None], fps: float) -> np.ndarray:
    """The standing body height in pixels around each frame (NaN where nobody is):
    a high percentile of the silhouette heights within SCALE_WINDOW_S."""
    h = np.array([np.nan if s is None else s.height for s in silhouettes], float)
    return rolling_percentile(h, max(1, int(round(SCALE_WINDOW_S * fps))), SCALE_PERCENTILE)


def normalise(sil: Silhouette, body_px: float) -> tuple[np.ndarray, np.ndarray, float]:
    """The silhouette cropped with a margin and resized to FIT_BODY_PX body height;
    returns (mask, origin in processing pixels, pixels of processing per fit pixel)."""
    pad = int(np.ceil(MARGIN * body_px))
    small = _fit_sized(sil.mask() * 255, pad, FIT_BODY_PX / body_px) > 127
    origin = np.array([sil.box[0] - pad, sil.box[1] - pad], float)
    return small.astype(np.uint8), origin, (sil.box[2] - sil.box[0] + 2 * pad) / small.shape[1]


def normalised_grey(sil: Silhouette, body_px: float) -> np.ndarray | None:
    """The silhouette's grey levels cropped and resized as ``normalise`` does its mask."""
    if sil.grey is None:
        return None
    return _fit_sized(sil.grey, int(np.ceil(MARGIN * body_px)), FIT_BODY_PX / body_px)


def _fit_sized(image: np.ndarray, pad: int, factor: float) -> np.ndarray:
    """An image with a black margin of ``pad`` pixels, resized by ``factor``."""
    padded = cv2.copyMakeBorder(image, pad, pad, pad, pad, cv2.BORDER_CONSTANT, value=0)
    h, w = padded.shape
    size = (max(1, round(w * factor)), max(1, round(h * factor)))
    return cv2.resize(padded, size, interpolation=cv2.INTER_AREA if factor < 1 else cv2.INTER_LINEAR)


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


def iter_fits(silhouettes: list[Silhouette | None], heights: np.ndarray, scale: float,
              fps: float) -> Iterator[FrameFit]:
    """Pass two (section 3.3): every frame's 2D fit in turn, each search centred on
    the previous fit; each frame's legs are chosen among its hypotheses over time
    (``mocap.silhouette.legchain``), so a fit comes out LAG_S later than its frame is fitted."""
    spreads = torso_spreads(silhouettes, heights, fps)
    chain = LegChain(max(1, int(round(LAG_S * fps))))
    for index, sil in enumerate(silhouettes):
        if sil is None:
            yield from _frame_fits(chain.push(index, None), scale)
            continue
        small, origin, step = normalise(sil, heights[index])
        best = chain.current
        prev = best.pose if best is not None and best.score >= MIN_TRACK_SCORE else None
        fit = fit_frame(small, FIT_SCALE, prev, spreads[index], normalised_grey(sil, heights[index]))
        yield from _frame_fits(chain.push((index, origin, step), fit), scale)
    yield from _frame_fits(chain.flush(), scale)


def _frame_fits(decided: list, scale: float) -> Iterator[FrameFit]:
    """FrameFits of (item, fit) pairs from ``LegChain``: the item is (index, crop
    origin, crop step) of a fitted frame, the index of one without a person."""
    for item, fit in decided:
        if fit is None:
            yield FrameFit(item, None, None)
            continue
        index, origin, step = item
        joints = (origin + (reported_joints(fit.joints, FIT_SCALE) + 0.5) * step - 0.5) / scale
        yield FrameFit(index, joints, fit.score, fit, FIT_BODY_PX * step / scale)


def fit_silhouettes(silhouettes: list[Silhouette | None], heights: np.ndarray, scale: float,
                    fps: float, progress: Progress | None = None) -> list[FrameFit]:
    """Pass two as a list, with progress."""
    return _collect(iter_fits(silhouettes, heights, scale, fps), len(silhouettes), progress)


def fit_video(video: str | os.PathLike | VideoInfo,
              progress: Progress | None = None) -> tuple[VideoInfo, list[FrameFit]]:
    """Silhouettes and 2D fits for every frame of a video (a path or an opened one)."""
    info = video if isinstance(video, VideoInfo) else open_video(video)
    scale = processing_scale(info)
    total = 2 * info.frame_count
    first = (lambda d, _t: progress(d, total)) if progress else None
    second = (lambda d, _t: progress(info.frame_count + d, total)) if progress else None
    silhouettes = extract_silhouettes(info, scale, first)
    if all(s is None for s in silhouettes):
        raise MocapError(f"{info.path}: no person found in any of its {info.frame_count} frames")
    heights = body_heights(silhouettes, info.fps)
    return info, fit_silhouettes(silhouettes, heights, scale, info.fps, second)


def video_dict(info: VideoInfo) -> dict:
    return {"path": info.path, "width": info.width, "height": info.height, "fps": info.fps,
            "frame_count": info.frame_count}


def fit_arrays(fits: list[FrameFit]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Image-side joints (F, 16, 2), body heights (F,) and torso spreads (F,) of the
    fits, NaN where nobody was found."""
    nan = np.full((len(JOINTS), 2), np.nan)
    joints = np.array([nan if f.joints2d is None else f.joints2d for f in fits], float)
    body_px = np.array([np.nan if f.body_px is None else f.body_px for f in fits], float)
    spread = np.array([np.nan if f.fit is None else f.fit.pose.spread for f in fits], float)
    return joints.reshape(len(fits), len(JOINTS), 2), body_px, spread


# -- the session ----------------------------------------------------------------------

class Session:
    """A video's per-frame 2D fits and the user's annotations; lifts on demand.

    ``annotate`` replaces the annotations (already checked; see
    mocap.io.annotations); the lifting inputs are re-resolved and the clip lifted again
    when next needed.
    """

    def __init__(self, info: VideoInfo, fits: list[FrameFit],
                 annotations: Annotations | None = None, smooth: float = 0.0):
        self.info, self.fits, self.smooth = info, fits, smooth
        self._annotations = annotations or Annotations()
        self._inputs: Inputs | None = None
        self._lifted: tuple[Inputs, np.ndarray] | None = None

    @property
    def annotations(self) -> Annotations:
        return self._annotations

    @cached_property
    def _arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return fit_arrays(self.fits)

    @cached_property
    def _guessed(self) -> list[str | None]:
        """The orientations the fits alone suggest (once per session)."""
        return guess_orientations(*self._arrays, self.info.fps)

    score_name = "similarity S"     # what ``scores`` are, for the page
    review_spacing = 0              # frames around a listed doubtful frame the review skips

    @property
    def scores(self) -> np.ndarray:
        """(F,) each frame's fit score (Eq. 3's S), NaN where nobody was found."""
        return np.array([np.nan if f.score is None else f.score for f in self.fits], float)

    def annotate(self, annotations: Annotations) -> None:
        """Take new annotations; lifting inputs are resolved again when next needed."""
        self._annotations, self._inputs = annotations, None

    @property
    def inputs(self) -> Inputs:
        if self._inputs is None:
            joints, body_px, spread = self._arrays
            self._inputs = resolve_inputs(joints, body_px, spread, self.info.fps, self._annotations,
                                          guessed=self._guessed)
        return self._inputs

    def pose3d(self, frame: int) -> np.ndarray | None:
        """(16, 3) lifted joints of a frame (metres, contract frame), None without a
        person; the clip is lifted again (milliseconds) when the inputs change."""
        if self.fits[frame].joints2d is None:
            return None
        inputs = self.inputs
        if self._lifted is None or self._lifted[0] is not inputs:
            self._lifted = (inputs, inputs.lift_clip(self.info.fps))
        return self._lifted[1][frame]

    def keyframes(self) -> list[int]:
        """The annotations' keyframes (default every frame) where a person was found."""
        return [k for k in self._annotations.keyframe_indices(len(self.fits))
                if self.fits[k].joints2d is not None]

    def motion(self) -> Motion:
        """Keyframes lifted, the frames between interpolated (mocap.lift.motion)."""
        keys = self.keyframes()
        if not keys:
            raise MocapError(f"{self.info.path}: no keyframe shows a person, nothing to lift")
        size = (self.info.width, self.info.height)
        root = root_track(self.inputs.joints2d, self.inputs.px_per_unit, size)
        return build_motion({k: self.pose3d(k) for k in keys}, len(self.fits), self.info.fps,
                            root=root, smooth=self.smooth)

    def motion_frames(self, motion: Motion) -> list[dict]:
        """Motion-file entries (CONTRACT.md). A frame without a person stays
        ``person: false``; it gets interpolated joints3d when it lies between keyframes."""
        keys = np.flatnonzero(motion.keyframes)
        frames = []
        for f in self.fits:
            entry: dict = {"index": f.index, "keyframe": bool(motion.keyframes[f.index]),
                           "person": f.joints2d is not None}
            if f.joints2d is not None:
                if entry["keyframe"]:
                    entry["score"] = f.score
                entry["orientation"] = self.inputs.orientation[f.index]
                entry["joints2d"] = self.inputs.joints2d[f.index]
            if f.joints2d is not None or keys[0] < f.index < keys[-1]:
                entry["joints3d"] = motion.joints3d[f.index]
                entry["root"] = motion.root[f.index]
            frames.append(entry)
        return frames

    def write(self, out: str | os.PathLike, *, bvh: str | os.PathLike | None = None,
              glb: str | os.PathLike | None = None, csv: str | os.PathLike | None = None) -> list[Path]:
        """Write the motion file and the exports asked for; returns the paths written."""
        motion = self.motion()
        return write_outputs(self.info, motion, self.motion_frames(motion), out, bvh=bvh, glb=glb,
                             csv=csv)


def write_outputs(info: VideoInfo, motion: Motion, frames: list[dict], out, *, bvh=None, glb=None,
                  csv=None) -> list[Path]:
    """The motion file and the exports asked for (None: not wanted); the paths written."""
    from mocap.io.export.bvh import write_bvh
    from mocap.io.export.csv import write_csv
    from mocap.io.export.glb import write_glb
    written = [write_motion(out, video_dict(info), frames)]
    for path, writer in ((bvh, write_bvh), (glb, write_glb), (csv, write_csv)):
        if path is not None:
            written.append(writer(path, motion))
    return written


def fit_video_to_file(video: str | os.PathLike, out: str | os.PathLike | None, *,
                      annotations: str | os.PathLike | None = None, method: str | None = None,
                      bvh=None, glb=None, csv=None, smooth: float = 0.0,
                      progress: Progress | None = None) -> list[Path]:
    """`mocap fit`: fit (silhouette method) or track (tracking method), lift,
    interpolate and write the motion file and exports. ``method`` None: the
    annotations' method, else the silhouette method."""
    from mocap.tracksession import TrackSession
    info = open_video(video)
    notes = load_annotations(annotations, info.frame_count) if annotations else Annotations()
    out = Path(out) if out else Path(video).with_suffix(".motion.json")
    if (method or notes.method) == "track":
        session = TrackSession.from_video(info, notes, smooth=smooth, progress=progress)
    else:
        session = Session(*fit_video(info, progress), notes, smooth)
    return session.write(out, bvh=bvh, glb=glb, csv=csv)
