"""The background without the performer (mocap.silhouette.plate) on the development
clips, against the photo each was rendered over, and the silhouettes it gives.

Per clip: the pixels where the clip's own background (``plate.clip_background``, what
`mocap fit` uses with no input) is off the photo (brought to the clip's tones by
``plate.clean_plate``) by more than the clip's noise floor, where its scene is a guess
(``Background.held``) and elsewhere; the held pixels; and the silhouettes'
(``background.extract_silhouette``) IoU against the true masks on every --step-th
frame. No fit: seconds a clip where bench_clips.py takes minutes, for work on the
plate; its IoU column (the written masks, on every frame) stays the reference.

    python benchmarks/bench_plate.py [--clips NAME ...] [--step 3]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_clips import CLIPS, background_photo, clip_names  # noqa: E402

from mocap.io.video import iter_frames, open_video, processing_scale  # noqa: E402
from mocap.silhouette.background import extract_silhouette, noise_floor  # noqa: E402
from mocap.silhouette.plate import clean_plate, clip_background  # noqa: E402


def plate_row(name: str, step: int) -> tuple[str, float]:
    """One clip's table row and its mean IoU."""
    clip = CLIPS / name
    info = open_video(clip / "video.mp4")
    scale = processing_scale(info)
    background = clip_background(info, scale)
    photo = clean_plate(background_photo(clip), info, scale).image
    off = cv2.absdiff(background.image, photo).max(axis=2) > noise_floor(background.sigma)
    held = background.held if background.held is not None else np.zeros(off.shape, bool)
    scores = []
    for index, frame in iter_frames(info, scale=scale):
        if index % step:
            continue
        truth = cv2.imread(str(clip / "masks" / f"{index:06d}.png"), cv2.IMREAD_GRAYSCALE) > 0
        truth = cv2.resize(truth.astype(np.uint8), frame.shape[1::-1], interpolation=cv2.INTER_NEAREST) > 0
        mask = extract_silhouette(frame, background) > 0
        scores.append((mask & truth).sum() / max((mask | truth).sum(), 1))
    iou = float(np.mean(scores))
    return (f"{name:18s} {(off & held).sum():8d} {(off & ~held).sum():8d} {held.sum():8d} {iou:8.4f}", iou)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    parser.add_argument("--step", type=int, default=3, help="score every STEP-th frame's silhouette (default 3)")
    args = parser.parse_args()
    if not CLIPS.is_dir():
        print(f"skipped: {CLIPS} is absent (the shared data sits beside the checkout)")
        return 0
    print(f"{'clip':18s} {'off_held':>8s} {'off_rest':>8s} {'held':>8s} {'iou':>8s}")
    ious = []
    for name in args.clips or clip_names():
        row, iou = plate_row(name, max(1, args.step))
        print(row, flush=True)
        ious.append(iou)
    print(f"mean IoU {np.mean(ious):.4f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
