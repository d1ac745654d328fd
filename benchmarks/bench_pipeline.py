"""Whole-pipeline speed of `mocap fit` on a 640x480 clip, stage by stage.

Renders 20 s of the CMU jumps motion capture (600 frames, 640x480, three-quarter
view), or takes --video (brought to 640x480), and times `mocap fit`'s own code
(pipeline.fit_video_to_file, in this process) split by its progress reports into
the background (up to the first silhouette), the silhouettes, the 2D fit and the
rest (lift, motion file); wall and CPU time, the best of --repeats runs; then the
command itself end to end, start-up included (wall and CPU, the best of --repeats runs),
and again as installed, with every module's bytecode cached.

    python benchmarks/bench_pipeline.py [--seconds 20] [--video PATH] [--repeats 3]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import cv2
import numpy as np

from mocap.io.video import iter_frames, open_video, write_video
from mocap.pipeline import FITTING, SILHOUETTES, Progress, fit_video_to_file
from mocap.synth import render_motion

BVH = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "bvh" / "cmu_01_01_jumps.bvh"
SIZE = (640, 480)
STAGES = ("background", "silhouettes", "2D fit", "lift + motion file")


def stage_times(video: Path, out: Path) -> np.ndarray:
    """(4, 2) wall and CPU seconds of each of STAGES in one run of `mocap fit`."""
    marks: dict[str, tuple[float, float]] = {}

    def mark(step: Progress) -> None:
        now = (time.perf_counter(), time.process_time())
        marks.setdefault(f"first {step.stage}", now)
        marks[f"last {step.stage}"] = now

    start = (time.perf_counter(), time.process_time())
    with contextlib.redirect_stdout(io.StringIO()):
        fit_video_to_file(video, {"json": out}, progress=mark)
    end = (time.perf_counter(), time.process_time())
    points = [start, marks[f"first {SILHOUETTES}"], marks[f"last {SILHOUETTES}"], marks[f"last {FITTING}"], end]
    return np.diff(np.array(points), axis=0)


def installed_env(video: Path, out: Path, folder: Path) -> dict[str, str]:
    """The environment of a `mocap fit` run as installed, every module's bytecode
    cached (pip compiles a package at install time): one untimed run writes it into
    ``folder``, not the checkout. Where PYTHONDONTWRITEBYTECODE is set, every start
    otherwise compiles mocap's modules (0.1 s of CPU)."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    env["PYTHONPYCACHEPREFIX"] = str(folder)
    command_time(video, out, env)
    return env


def command_time(video: Path, out: Path, env: dict[str, str]) -> tuple[float, float]:
    """Wall and CPU seconds of the `mocap fit` command, start-up included (the CPU of
    the child process, from the operating system's accounting)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    subprocess.run(["mocap", "fit", str(video), "--out", str(out), "--quiet"], check=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)


def prepare(video: Path | None, folder: Path, seconds: float) -> Path:
    """The 640x480 clip: --video resized, or the rendered jumps."""
    path = folder / "clip.mp4"
    if video is None:
        render_motion(BVH, path, view="three-quarter", seconds=seconds)
        return path
    info = open_video(video)
    frames = [cv2.resize(f, SIZE, interpolation=cv2.INTER_LINEAR) for _, f in iter_frames(info)]
    write_video(path, frames, info.fps, SIZE)
    return path


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--video", type=Path, help="time this video, resized to 640x480, instead")
    parser.add_argument("--repeats", type=int, default=3, help="runs of the fit; the fastest is shown")
    args = parser.parse_args()
    if args.video is None and not BVH.is_file():
        print(f"skipped: {BVH} is absent")
        return 0
    with tempfile.TemporaryDirectory() as tmp:
        video = prepare(args.video, Path(tmp), args.seconds)
        n = open_video(video).frame_count
        out = Path(tmp) / "clip.motion.json"
        runs = [stage_times(video, out) for _ in range(args.repeats)]
        best = min(runs, key=lambda r: r[:, 0].sum())
        commands = [
            min((command_time(video, out, env) for _ in range(args.repeats)), key=lambda t: t[0])
            for env in (dict(os.environ), installed_env(video, out, Path(tmp) / "pycache"))
        ]
    print(f"{'stage':32s} {'ms/frame':>9s} {'CPU ms/frame':>13s} {'frames/s':>9s}")
    for name, (wall, cpu) in zip(STAGES, best):
        print(f"{name:32s} {1000 * wall / n:9.2f} {1000 * cpu / n:13.2f} {n / wall:9.1f}")
    wall, cpu = best.sum(axis=0)
    print(f"{'mocap fit (its code)':32s} {1000 * wall / n:9.2f} {1000 * cpu / n:13.2f} {n / wall:9.1f}")
    for name, (wall, cpu) in zip(("mocap fit, whole command", "the same as installed"), commands):
        print(f"{name:32s} {1000 * wall / n:9.2f} {1000 * cpu / n:13.2f} {n / wall:9.1f}")
    print(f"{n} frames {SIZE[0]}x{SIZE[1]}; best of {args.repeats} runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
