"""Speed of background estimation and silhouette extraction, on one core.

    python benchmarks/bench_silhouette.py [--sheet PNG]

Prints one row per clip: the time to estimate the background and the median and 90th
percentile time per frame of `extract_silhouette`. Clips: the synthetic walking
figure of the tests at 640x480 and at 1280x720 (the processing size of a 4K video),
and the real dog_walker clip when ../shared/data is present. `--sheet` also writes a
contact sheet of dog_walker: per frame, the person zoomed with the silhouette's
outline in red, and the whole mask.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from helpers import DOG_WALKER  # noqa: E402
from test_silhouette import synthetic_scene  # noqa: E402

from mocap.io.video import iter_frames, open_video  # noqa: E402
from mocap.silhouette.background import estimate_background, extract_silhouette  # noqa: E402

REPEATS = 5  # passes over each clip's frames


def clips():
    """(name, frames) for each clip that is available."""
    for height, width in ((480, 640), (720, 1280)):
        yield f"synthetic {width}x{height}", synthetic_scene(height, width, n=30)[1]
    if DOG_WALKER.exists():
        yield "dog_walker 180x144", [f for _, f in iter_frames(open_video(DOG_WALKER))]


def measure(frames: list[np.ndarray]) -> tuple[float, np.ndarray]:
    """Seconds to estimate the background, and milliseconds per silhouette."""
    start = time.perf_counter()
    background = estimate_background(frames)
    setup = time.perf_counter() - start
    times = []
    for _ in range(REPEATS):
        for frame in frames:
            start = time.perf_counter()
            extract_silhouette(frame, background)
            times.append(time.perf_counter() - start)
    return setup, 1e3 * np.array(times)


def contact_sheet(frames: list[np.ndarray], masks: list[np.ndarray], columns: int = 6, zoom: int = 2) -> np.ndarray:
    """Tiles of (person zoomed with the mask outline, whole mask), in frame order."""
    height, width = frames[0].shape[:2]
    box = (width * 2 // 5, height * 3 // 4)  # the crop around the person
    tiles = []
    for index, (frame, mask) in enumerate(zip(frames, masks)):
        xs = np.flatnonzero(mask.any(axis=0))
        x0 = int(np.clip((xs.mean() if len(xs) else width / 2) - box[0] / 2, 0, width - box[0]))
        y0 = height - box[1]
        crop = cv2.resize(frame[y0:, x0 : x0 + box[0]], None, fx=zoom, fy=zoom, interpolation=cv2.INTER_NEAREST)
        outline = cv2.resize(mask[y0:, x0 : x0 + box[0]], crop.shape[1::-1], interpolation=cv2.INTER_NEAREST)
        contours, _ = cv2.findContours(outline, cv2.RETR_LIST, cv2.CHAIN_APPROX_NONE)
        cv2.drawContours(crop, contours, -1, (0, 0, 255), 1)
        cv2.putText(crop, str(index), (3, 14), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 255, 255))
        whole = np.zeros((crop.shape[0], width, 3), np.uint8)
        whole[:height] = cv2.cvtColor(mask, cv2.COLOR_GRAY2BGR)
        tiles.append(np.hstack([crop, whole, np.full((crop.shape[0], 4, 3), 80, np.uint8)]))
    tiles += [np.zeros_like(tiles[0])] * (-len(tiles) % columns)
    rows = [np.hstack(tiles[i : i + columns]) for i in range(0, len(tiles), columns)]
    return np.vstack(rows)


def write_sheet(path: str) -> None:
    frames = [f for _, f in iter_frames(open_video(DOG_WALKER))]
    background = estimate_background(frames)
    cv2.imwrite(path, contact_sheet(frames, [extract_silhouette(f, background) for f in frames]))
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sheet", help="write a dog_walker contact sheet PNG here")
    args = parser.parse_args()
    cv2.setNumThreads(1)
    print(f"{'clip':<22} {'frames':>6} {'background s':>12} {'ms/frame median':>15} {'p90':>6}")
    for name, frames in clips():
        setup, ms = measure(frames)
        print(f"{name:<22} {len(frames):>6} {setup:>12.2f} {np.median(ms):>15.2f} {np.percentile(ms, 90):>6.2f}")
    if args.sheet:
        write_sheet(args.sheet)


if __name__ == "__main__":
    main()
