"""`mocap batch` speed with 1 and 2 workers, and a worker's peak memory against video length.

Speed: the development clips ../shared/data/clips/*/video.mp4 without the two
track_* clips (their backgrounds move: they are the tracking method's, which needs
joints marked on frame 0, and the silhouette method is not meant for them), 8 clips
of 480x360, every export, on a local cluster of 1 and of 2 worker
processes, each run --repeat times interleaved and the fastest kept (other jobs on a
shared machine come and go). Wall time counts the cluster's start; frames/s counts
from the first task; load is the 1-minute load average after the run. CPU ms/frame
is the workers' own CPU time (the work, whatever else runs), and "cores had" that
CPU time over the run's time: how much of the machine the batch got. On a quiet
machine the speed-up is the ratio of the cores had at an equal CPU ms/frame.

Memory: one clip, and the same clip looped 10 times (forward, backward, ...), each on
a fresh single-worker cluster; the worker process's peak resident memory after the
video is done (its high-water mark, so everything the task held counts).

    python benchmarks/bench_batch.py [--workers 1 2] [--repeat 2] [--clip punch_front] [--loops 10]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import resource
import sys
import tempfile
import time
from pathlib import Path

import cv2

from mocap.batch import Tally, batch, dask_client, plan, run_batch
from mocap.batch.task import DEFAULT_EXPORTS

CLIPS = Path(__file__).resolve().parents[2] / "shared" / "data" / "clips"


def speed(videos: list[Path], workers: int) -> tuple[float, Tally]:
    """Wall seconds of `mocap batch` on the videos, and its tally."""
    with tempfile.TemporaryDirectory() as tmp:
        start = time.perf_counter()
        with contextlib.redirect_stdout(io.StringIO()):  # the table alone on stdout
            tally = batch([str(v) for v in videos], tmp, workers=workers)
        wall = time.perf_counter() - start
    if tally.failed:
        raise SystemExit(f"failed: {[(o.name, o.error) for o in tally.failed]}")
    return wall, tally


def looped(source: Path, out: Path, loops: int) -> Path:
    """The clip played forward, backward, forward... ``loops`` times (no jump at the seams)."""
    cap = cv2.VideoCapture(str(source))
    frames = []
    while (frame := cap.read())[0]:
        frames.append(frame[1])
    height, width = frames[0].shape[:2]
    writer = cv2.VideoWriter(str(out), cv2.VideoWriter_fourcc(*"mp4v"), cap.get(cv2.CAP_PROP_FPS), (width, height))
    for loop in range(loops):
        for frame in frames if loop % 2 == 0 else frames[::-1]:
            writer.write(frame)
    writer.release()
    return out


def peak_rss_mb() -> float:
    """This process's peak resident memory (Linux reports kB)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def peak_memory(video: Path, folder: Path) -> tuple[int, float]:
    """Frames of the video and the peak memory (MB) of the worker that did it."""
    jobs = plan([video], folder, list(DEFAULT_EXPORTS), 0.0, None)
    tally = Tally(1)
    with dask_client(None, 1) as client:
        run_batch(jobs, client, tally)
        peaks = client.run(peak_rss_mb)
    if tally.failed:
        raise SystemExit(f"failed: {tally.failed[0].error}")
    return tally.frames, max(peaks.values())


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--workers", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--clip", default="punch_front", help="the clip of the memory test")
    parser.add_argument("--loops", type=int, default=10)
    parser.add_argument("--repeat", type=int, default=2, help="runs of each worker count (the best)")
    args = parser.parse_args()
    videos = sorted(p for p in CLIPS.glob("*/video.mp4") if not p.parent.name.startswith("track_"))
    if not videos:
        print(f"skipped: no clips in {CLIPS}")
        return 0
    frames = sum(int(cv2.VideoCapture(str(v)).get(cv2.CAP_PROP_FRAME_COUNT)) for v in videos)
    print(
        f"{len(videos)} clips, {frames} frames; load average before: {os.getloadavg()[0]:.2f}; {os.cpu_count()} cores"
    )
    print(
        f"{'workers':>7s} {'wall s':>7s} {'videos/min':>10s} {'frames/s':>9s} {'speed-up':>8s} "
        f"{'load':>5s} {'CPU ms/frame':>12s} {'cores had':>9s}"
    )
    best: dict[int, tuple[float, Tally, float]] = {}
    for _ in range(args.repeat):  # interleaved, the best of each: others' jobs come and go
        for n in args.workers:
            wall, tally = speed(videos, n)
            if n not in best or tally.fps > best[n][1].fps:
                best[n] = (wall, tally, os.getloadavg()[0])
    base = best[args.workers[0]][1].fps
    for n, (wall, tally, load) in best.items():
        busy = tally.frames / tally.fps  # seconds from the first task to the last
        print(
            f"{n:7d} {wall:7.1f} {60 * len(videos) / wall:10.1f} {tally.fps:9.1f} "
            f"{tally.fps / base:7.2f}x {load:5.1f} {1000 * tally.cpu / tally.frames:12.1f} "
            f"{tally.cpu / busy:9.2f}",
            flush=True,
        )
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    with tempfile.TemporaryDirectory() as tmp:
        clip = CLIPS / args.clip / "video.mp4"
        long = looped(clip, Path(tmp) / f"{args.clip}_x{args.loops}.mp4", args.loops)
        print(f"\n{'video':>24s} {'frames':>7s} {'worker peak MB':>15s}")
        rows = [(name, *peak_memory(v, Path(tmp) / name)) for name, v in ((args.clip, clip), (long.stem, long))]
        for name, frames, peak in rows:
            print(f"{name:>24s} {frames:7d} {peak:15.1f}")
        print(f"{'long / short':>24s} {'':7s} {rows[1][2] / rows[0][2]:14.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
