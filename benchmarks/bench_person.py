"""The person model's price: MediaPipe alone against `mocap fit` with it and without.

On one clip (default ../shared/data/clips/wash_front; by default played --loops times,
forward and back, into a longer video so that the one-time costs weigh less), times:

  (a) mediapipe   MediaPipe Pose alone over every frame: decode (cv2.VideoCapture) and
                  observe, the model's loading included
  (b) product     `mocap fit --person-model mediapipe` (the command line's own code)
  (c) classical   `mocap fit --person-model none` (the paper's path)

each as CPU seconds (os.times: every thread of the process, and the person model's own
process where it has one) and wall seconds
(time.perf_counter), and frames per second of wall time; then the ratios b/a and c/a.
All three run in this process, the same way, after one untimed warm-up that imports
and loads MediaPipe, with OpenCV on one thread as `mocap fit` sets it; each is run
--repeats times, interleaved, and the minimum of each of its CPU and wall times kept.

    python benchmarks/bench_person.py [--video PATH] [--loops 4] [--repeats 2]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import sys
import tempfile
import time
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_clips import CLIPS, warm_up  # noqa: E402

from mocap.cli import main as mocap_main  # noqa: E402
from mocap.io.video import iter_frames, open_video, write_video  # noqa: E402
from mocap.person import open_person_model  # noqa: E402

VARIANTS = ("mediapipe", "product", "classical")


def looped_video(video: Path, loops: int, out: Path) -> Path:
    """The video played ``loops`` times, every other time backwards (no jump at the
    joins), written to ``out``; the video itself for one loop."""
    if loops <= 1:
        return video
    info = open_video(video)
    frames = [frame for _, frame in iter_frames(info)]
    played = [frame for k in range(loops) for frame in (frames if k % 2 == 0 else frames[::-1])]
    write_video(out, played, info.fps, (info.width, info.height))
    return out


def mediapipe_alone(video: Path) -> int:
    """MediaPipe Pose over every frame of the video in order; the number of frames."""
    capture, model, count = cv2.VideoCapture(str(video)), open_person_model("mediapipe"), 0
    try:
        while (frame := capture.read()[1]) is not None:
            model.observe(frame)
            count += 1
    finally:
        model.close()
        capture.release()
    return count


def mocap_fit(video: Path, person: str, out: Path) -> None:
    """`mocap fit VIDEO --person-model person`, the motion file to ``out``."""
    with contextlib.redirect_stdout(io.StringIO()):
        code = mocap_main(["fit", str(video), "--out", str(out), "--person-model", person, "--quiet"])
    if code:
        raise SystemExit(f"mocap fit --person-model {person} failed on {video} (exit {code})")


def timed(run) -> tuple[float, float]:
    """(CPU seconds, wall seconds) of one call of ``run``, the CPU of the processes it waited for included."""
    cpu, wall = _cpu(), time.perf_counter()
    run()
    return _cpu() - cpu, time.perf_counter() - wall


def _cpu() -> float:
    """CPU seconds of this process and of its children that ended (the person model's own process)."""
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--video", type=Path, default=CLIPS / "wash_front" / "video.mp4")
    parser.add_argument("--loops", type=int, default=4, help="play the clip this many times, back and forth")
    parser.add_argument("--repeats", type=int, default=2, help="runs of each; the minimum is kept")
    args = parser.parse_args()
    if not args.video.is_file():
        print(f"skipped: {args.video} is absent")
        return 0
    cv2.setNumThreads(1)  # what `mocap fit` sets, so that every variant runs with it
    warm_up()
    with tempfile.TemporaryDirectory() as tmp:
        video = looped_video(args.video, args.loops, Path(tmp) / "looped.mp4")
        frames, out = open_video(video).frame_count, Path(tmp) / "motion.json"
        runs = {
            "mediapipe": lambda: mediapipe_alone(video),
            "product": lambda: mocap_fit(video, "mediapipe", out),
            "classical": lambda: mocap_fit(video, "none", out),
        }
        times = {v: [] for v in VARIANTS}
        for _ in range(args.repeats):
            for variant in VARIANTS:
                times[variant].append(timed(runs[variant]))
    best = {v: (min(c for c, _ in t), min(w for _, w in t)) for v, t in times.items()}
    print(
        f"{args.video} x{max(args.loops, 1)} back and forth: {frames} frames; in-process, "
        f"minimum of {args.repeats} runs"
    )
    print(f"{'':14s} {'cpu_s':>7s} {'wall_s':>7s} {'fps':>7s} {'cpu/a':>6s} {'wall/a':>6s}")
    for label, variant in zip(("(a)", "(b)", "(c)"), VARIANTS):
        cpu, wall = best[variant]
        print(
            f"{label} {variant:10s} {cpu:7.2f} {wall:7.2f} {frames / wall:7.1f} "
            f"{cpu / best['mediapipe'][0]:6.2f} {wall / best['mediapipe'][1]:6.2f}"
        )
    return 0


if __name__ == "__main__":
    sys.exit(main())
