"""`mocap sheet`: a contact sheet to judge a fit at a glance. Frames spread over the clip, each
beside its silhouette (section 3.2) and fitted skeleton, captioned with S (Eq. 3) or "no person"."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import cv2
import numpy as np

from mocap.errors import MocapError
from mocap.image.draw import silhouette_view
from mocap.io.export.atomic import write_export
from mocap.io.export.motion_json import read_motion
from mocap.io.fileio import check_writable
from mocap.io.video import VideoInfo, open_video, processing_scale, read_frame
from mocap.silhouette.background import Background, extract_silhouette
from mocap.silhouette.plate import clip_background

Progress = Callable[[int, int, str], None]  # done, total, stage
DEFAULT_FRAMES = 12
TILE_HEIGHT = 240  # px: smaller videos are upscaled to this
COLUMNS = 3  # tiles per row
_FONT = cv2.FONT_HERSHEY_SIMPLEX


def sheet_indices(frame_count: int, n: int) -> list[int]:
    """About `n` frame indices spread evenly over the clip, first and last included."""
    return np.unique(np.linspace(0, frame_count - 1, max(n, 1)).round().astype(int)).tolist()


def tile_width(info: VideoInfo, height: int = TILE_HEIGHT) -> int:
    """Width of one half of a tile (frame or silhouette) `height` px tall."""
    return max(1, round(info.width * height / info.height))


def frame_tile(
    frame: np.ndarray, background: Background, scale: float, entry: dict | None, index: int, height: int = TILE_HEIGHT
) -> np.ndarray:
    """The frame beside its silhouette and fitted skeleton, captioned; `entry` is the
    frame's motion-file entry (None when the file has none for it)."""
    size = (round(frame.shape[1] * height / frame.shape[0]), height)
    small = _resize(frame, scale)
    mask = cv2.resize(extract_silhouette(small, background), size, interpolation=cv2.INTER_NEAREST)
    joints = _joints(entry)
    view = silhouette_view(mask, None if joints is None else joints * (height / frame.shape[0]))
    picture = cv2.resize(frame, size, interpolation=cv2.INTER_AREA if height < frame.shape[0] else cv2.INTER_LINEAR)
    tile = np.hstack([picture, view])
    cv2.rectangle(tile, (0, 0), (tile.shape[1] - 1, height - 1), (90, 90, 90), 1)
    _caption(tile, f"#{index}  {_status(entry)}")
    return tile


def _joints(entry: dict | None) -> np.ndarray | None:
    if not entry or not entry.get("person", "joints2d" in entry) or "joints2d" not in entry:
        return None
    return np.asarray(entry["joints2d"], dtype=float)


def _status(entry: dict | None) -> str:
    if entry is None:
        return "not in the motion file"
    if _joints(entry) is None:
        return "no person"
    score = entry.get("score")
    return "interpolated" if score is None else f"S {score:.2f}"


def _caption(tile: np.ndarray, text: str) -> None:
    """White text on a dark strip in the tile's top-left corner."""
    (w, h), base = cv2.getTextSize(text, _FONT, 0.55, 1)
    cv2.rectangle(tile, (1, 1), (w + 8, h + base + 6), (30, 30, 30), -1)
    cv2.putText(tile, text, (4, h + 4), _FONT, 0.55, (255, 255, 255), 1, cv2.LINE_AA)


def _resize(frame: np.ndarray, scale: float) -> np.ndarray:
    """As `video.iter_frames(scale=...)` sizes frames, so the silhouette matches the fit's."""
    if scale >= 1.0:
        return frame
    size = (max(1, round(frame.shape[1] * scale)), max(1, round(frame.shape[0] * scale)))
    return cv2.resize(frame, size, interpolation=cv2.INTER_AREA)


def contact_sheet(
    video: str | os.PathLike,
    motion: dict,
    n: int = DEFAULT_FRAMES,
    height: int = TILE_HEIGHT,
    progress: Progress | None = None,
) -> np.ndarray:
    """The contact sheet (BGR image) of `n` frames of `video` fitted as `motion` says;
    ``progress(done, total, stage)`` after the background and after each tile."""
    if n < 1:
        raise MocapError(f"--frames must be at least 1, got {n}")
    report = progress or (lambda done, total, stage: None)
    info = open_video(video)
    _check_match(info, motion)
    indices = sheet_indices(info.frame_count, n)
    scale = processing_scale(info)
    background = clip_background(info, scale)
    report(1, len(indices) + 1, "background")
    entries = {f.get("index"): f for f in motion.get("frames", [])}
    tiles = []
    for i in indices:
        tiles.append(frame_tile(read_frame(info, i), background, scale, entries.get(i), i, height))
        report(len(tiles) + 1, len(indices) + 1, "tiles")
    return _grid(tiles, min(COLUMNS, len(tiles)))


def _check_match(info: VideoInfo, motion: dict) -> None:
    """Refuse a motion file fitted on another video (other size or frame count)."""
    v = motion.get("video", {})
    theirs = (v.get("width"), v.get("height"), v.get("frame_count"))
    if theirs != (info.width, info.height, info.frame_count):
        raise MocapError(
            f"{info.path}: the motion file was fitted on a video of "
            f"{theirs[0]}x{theirs[1]}, {theirs[2]} frames; this one is "
            f"{info.width}x{info.height}, {info.frame_count} frames"
        )


def _grid(tiles: list[np.ndarray], columns: int) -> np.ndarray:
    """Tiles (all one size) in rows of `columns`, the last row padded with black."""
    blank = np.zeros_like(tiles[0])
    tiles = tiles + [blank] * (-len(tiles) % columns)
    return np.vstack([np.hstack(tiles[r : r + columns]) for r in range(0, len(tiles), columns)])


def write_sheet(
    video: str | os.PathLike,
    motion_path: str | os.PathLike,
    out: str | os.PathLike | None = None,
    n: int = DEFAULT_FRAMES,
    progress: Progress | None = None,
) -> Path:
    """`mocap sheet`: read the motion file, draw the sheet, write it (PNG or JPEG)."""
    out = Path(out) if out else Path(video).with_suffix(".sheet.png")
    if out.suffix.lower() not in (".png", ".jpg", ".jpeg"):
        raise MocapError(f"{out}: the contact sheet must end in .png or .jpg")
    check_writable(out)
    return write_image(out, contact_sheet(video, read_motion(motion_path), n, progress=progress), "contact sheet")


def write_image(out: Path, image: np.ndarray, kind: str = "image") -> Path:
    """Encode an image as its suffix says (.png, .jpg) and write it atomically."""
    ok, data = cv2.imencode(out.suffix, image)
    if not ok:
        raise MocapError(f"{out}: OpenCV could not encode the {kind}")
    return write_export(out, data.tobytes(), kind)


def add_sheet_arguments(parser) -> None:
    """Arguments of `mocap sheet`; sets ``run``."""
    parser.add_argument("video", help="the video that was fitted")
    parser.add_argument("motion", help="its motion file (mocap fit --out)")
    parser.add_argument("--out", help="image to write, .png or .jpg (default VIDEO.sheet.png)")
    parser.add_argument(
        "--frames", type=int, default=DEFAULT_FRAMES, help=f"how many frames, spread evenly (default {DEFAULT_FRAMES})"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(run=run_sheet)


def run_sheet(args) -> None:
    out = write_sheet(args.video, args.motion, args.out, args.frames, progress=args.progress)
    print(f"wrote {out}")
