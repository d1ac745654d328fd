"""Latency of the browser app, server side, on a 640x480 video.

From a user's action (the call its callback makes) to the update of the page having
been sent: a foreshortening toggle (a sign click) to the new 3D pose (budget 100 ms:
on a 300-frame clip: ``--seconds 10``), a frame change to all three views
(video frame, silhouette and fit, 3D; budget 100 ms), and a joint override and an undo
to every view they change; with the silhouette method, how many frames the clip solve
(mocap.lift.solve) solved again for each, and when the whole clip was settled (an edit solves
the window of its own frame first, the rest on a thread of its own: app.edits._settle_soon). "Queued" is when the server has
queued every message of the update; "received" is when a connected websocket client
(what a browser tab's socket gets, without a browser) has received all of it: a
marker label queued after the update says when.

    python benchmarks/bench_app.py [--video VIDEO] [--seconds S] [--repeats N] [--track]
    python benchmarks/bench_app.py --startup [--video VIDEO] [--repeats N]
    python benchmarks/bench_app.py --play [--video VIDEO] [--repeats N]

``--startup`` times what a user waits for after ``mocap serve``: from the app's
creation to the page's frame 0 showing its silhouette, then its fitted model (the
first fitted frame in the app), and to every frame fitted (best and median of N runs).

``--play`` plays the whole video N times with one websocket client connected: how
long it took against the video's own length, and how many frames were shown (the
player skips the frames it is late for).

Default video: the bundled sample (640x480, 99 frames). ``--seconds`` renders the
procedural walk at 640x480 and 30 fps for that long instead (how latency grows with
the clip: each edit re-resolves the lifting inputs of the whole clip). ``--track``
(with ``--seconds``) renders it walking in place turned toward the camera, through a
perspective camera over a panning background, marks frame 0 with the true joints and times the tracking
method's page (each edit reshapes the whole clip's tracked 3D); the time tracking
itself takes is printed too.
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import viser
import zstandard
from websockets.sync.client import connect

from app.serve import SAMPLE, create
from mocap.body import JOINTS, SEGMENT_NAMES
from mocap.io.video import open_video
from mocap.lift import solve
from mocap.lift.taylor import depth_fractions
from mocap.synth import render_clip
from mocap.synth.walk import walk_cycle


class Receiver:
    """A websocket client of the server that notes when a marker text arrives."""

    def __init__(self, port: int):
        self.socket = connect(f"ws://127.0.0.1:{port}", subprotocols=[f"viser-v{viser.__version__}"], max_size=None)
        self.wanted, self.arrived = b"", threading.Event()
        self._zstd = zstandard.ZstdDecompressor()
        threading.Thread(target=self._run, daemon=True).start()

    def _run(self) -> None:
        for data in self.socket:
            inner, packed = int.from_bytes(data[:8], "little"), int.from_bytes(data[8:16], "little")
            payload = self._zstd.decompress(data[16 : 16 + packed], max_output_size=inner)
            if self.wanted and self.wanted in payload:
                self.arrived.set()

    def expect(self, marker: str) -> None:
        self.wanted = marker.encode()
        self.arrived.clear()


def measure(app, receiver: Receiver, marker, action) -> tuple[float, float]:
    """(queued, received) milliseconds of one action's update."""
    text = f"bench-marker-{time.monotonic_ns()}"
    receiver.expect(text)
    t0 = time.perf_counter()
    action()
    queued = time.perf_counter()
    marker.text = text
    app.server.flush()
    if not receiver.arrived.wait(10.0):
        raise RuntimeError("the update never arrived")
    return 1000 * (queued - t0), 1000 * (time.perf_counter() - t0)


def plan(app, rng: np.random.Generator) -> dict[str, tuple]:
    """action name -> (frame -> the call to time, budget in ms or None). Frame changes
    come first, while no frame has been decoded and drawn yet."""
    state = app.state

    def flip(frame: int):
        state.go_to(frame)
        segment = deepest_segment(state)
        return lambda: state.flip_sign(frame, segment)

    def override(frame: int):
        state.go_to(frame)
        return lambda: state.set_override(frame, "wrist_r", (rng.uniform(0, 640), rng.uniform(0, 480)))

    return {
        "frame change -> three views": (lambda f: lambda: state.go_to(f), 100.0),
        "toggle -> 3D pose": (flip, 100.0),
        "joint override -> all views": (override, None),
        "undo -> all views": (lambda f: state.undo, None),
    }


def deepest_segment(state) -> str:
    """The current frame's segment farthest out of the image plane (its flip moves most)."""
    return SEGMENT_NAMES[int(np.argmax(depth_fractions(state.view().pose3d)))]


def switch_to_tracking(state, marks: np.ndarray) -> None:
    """Choose the tracking method, mark frame 0, track; print how long tracking took."""
    state.set_method("track")
    for name, xy in zip(JOINTS, marks):
        state.set_override(0, name, tuple(xy))
    t0 = time.perf_counter()
    state.start_tracking().join()
    print(f"tracking {state.n_frames} frames in the app: {time.perf_counter() - t0:.1f} s")


class Counted(solve.Problem):
    """mocap.lift.solve's problem, counting the frames it solves (``free``)."""

    frames: list[int] = []

    def __init__(self, clip, frames, base, free, *args):
        Counted.frames.append(int(free.sum()))
        super().__init__(clip, frames, base, free, *args)


def bench(video: Path, repeats: int, seed: int = 0, marks: np.ndarray | None = None) -> None:
    app = create(video, port=0)
    app.state.start()
    app.state.ready.wait()
    if marks is not None:
        switch_to_tracking(app.state, marks)
    receiver = Receiver(app.server.get_port())
    marker = app.server.scene.add_label("/bench-marker", "", visible=False)
    measure(app, receiver, marker, lambda: None)  # the backlog has arrived
    rng = np.random.default_rng(seed)
    frames = [int(f) for f in 1 + rng.permutation(app.state.n_frames - 1)[:repeats]]
    info = app.state.info
    print(
        f"{info.width}x{info.height}, {info.frame_count} frames; {len(frames)} repeats, one connected websocket client"
    )
    print(f"{'action':30s} {'queued median':>13s} {'received median':>15s} {'p95':>7s} {'max':>7s} {'budget':>7s}")
    solved, settled = {}, {}
    for name, (make, budget) in plan(app, rng).items():
        times, solved[name], settled[name] = [], [], []
        for f in frames:
            app.state.wait_settled()
            action, Counted.frames = make(f), []
            times.append(measure(app, receiver, marker, action))
            t0 = time.perf_counter()
            app.state.wait_settled()
            settled[name].append(1000 * (time.perf_counter() - t0) + times[-1][1])
            solved[name].append(sum(Counted.frames))
        queued, received = np.array(times).T
        verdict = "" if budget is None else f"{budget:5.0f} {'ok' if received.max() <= budget else 'OVER'}"
        print(
            f"{name:30s} {np.median(queued):11.1f}ms {np.median(received):13.1f}ms "
            f"{np.percentile(received, 95):5.1f}ms {received.max():5.1f}ms  {verdict}".rstrip()
        )
    if app.state.method == "silhouette":
        print("frames the clip solve solved again per action (median, max), and ms to the clip settled (median, max):")
        for name, counts in solved.items():
            done = settled[name]
            print(
                f"  {name:28s} {np.median(counts):5.0f} {max(counts):5d} of {app.state.n_frames}"
                f" {np.median(done):8.1f} {max(done):8.1f}"
            )
    app.server.stop()


def startup(video: Path) -> np.ndarray:
    """(3, 2): seconds from creating the app to frame 0's silhouette on the page, to its
    fit, and to every frame fitted; wall-clock and this process's CPU."""
    marks: dict[str, tuple[float, float]] = {}
    t0, c0 = time.perf_counter(), time.process_time()
    app = create(video, port=0)
    state = app.state

    def note() -> None:  # after the app's own listener: the page's update is queued
        view = state.view(0)
        for name, reached in (("silhouette", view.silhouette_ready), ("fit", view.fitted)):
            if reached and name not in marks:
                marks[name] = (time.perf_counter() - t0, time.process_time() - c0)

    state.on_change(note)
    state.start()
    state.ready.wait()
    marks["ready"] = (time.perf_counter() - t0, time.process_time() - c0)
    app.server.stop()
    if state.progress.error is not None:
        raise RuntimeError(state.progress.error)
    return np.array([marks["silhouette"], marks["fit"], marks["ready"]])


def bench_startup(video: Path, repeats: int) -> None:
    info = open_video(video)
    runs = np.stack([startup(video) for _ in range(repeats)])
    print(
        f"{info.width}x{info.height}, {info.frame_count} frames at {info.fps:g} fps; {repeats} runs; "
        "CPU: this process's (all its threads)"
    )
    print(f"{'from the app created to':34s} {'wall best':>9s} {'median':>7s} {'CPU median':>10s}")
    for k, name in enumerate(
        ("frame 0's silhouette on the page", "first fitted frame on the page", "every frame fitted")
    ):
        wall, cpu = runs[:, k, 0], runs[:, k, 1]
        print(f"{name:34s} {wall.min():8.2f}s {np.median(wall):6.2f}s {np.median(cpu):9.2f}s")


def bench_play(video: Path, repeats: int) -> None:
    app = create(video, port=0)
    app.state.start()
    app.state.ready.wait()
    receiver = Receiver(app.server.get_port())
    marker = app.server.scene.add_label("/bench-marker", "", visible=False)
    measure(app, receiver, marker, lambda: None)  # the backlog has arrived
    state, shown = app.state, []
    state.on_change(lambda: shown.append(state.frame))
    n, fps = state.n_frames, state.info.fps
    print(
        f"{state.info.width}x{state.info.height}, {n} frames at {fps:g} fps ({n / fps:.2f} s); "
        "one connected websocket client"
    )
    print(f"{'run':>3s} {'played in':>9s} {'frames shown':>12s} {'skipped':>7s}")
    for run in range(repeats):
        state.go_to(0)
        shown.clear()
        t0 = time.perf_counter()
        app.player.toggle()
        while app.controls.play.label != "Play":
            time.sleep(0.01)
        took, frames = time.perf_counter() - t0, len(set(shown))
        print(f"{run + 1:3d} {took:8.2f}s {frames:12d} {n - frames:7d}")
    steps = []
    for frame in range(n):  # what a shown frame costs: stepping through every one
        t0 = time.perf_counter()
        state.go_to(frame)
        steps.append(time.perf_counter() - t0)
    print(
        f"a frame shown (every view redrawn), frame after frame: median "
        f"{1000 * np.median(steps):.1f} ms, p95 {1000 * np.percentile(steps, 95):.1f} ms "
        f"(the video's frames are {1000 / fps:.1f} ms apart)"
    )
    app.server.stop()


def main() -> int:
    solve.Problem = Counted  # the silhouette session's windows are counted
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--video", type=Path, default=SAMPLE)
    parser.add_argument("--seconds", type=float, default=None)
    parser.add_argument("--repeats", type=int, default=30)
    parser.add_argument("--track", action="store_true", help="the tracking method (needs --seconds)")
    parser.add_argument(
        "--startup", action="store_true", help="time to the first fitted frame and to every frame fitted"
    )
    parser.add_argument("--play", action="store_true", help="play the video through")
    args = parser.parse_args()
    if args.track and not args.seconds:
        parser.error("--track renders its clip: give --seconds")
    with tempfile.TemporaryDirectory() as tmp:
        video, marks = Path(tmp) / "bench.mp4", None
        if args.track:
            truth = render_clip(
                walk_cycle(args.seconds, 30.0, in_place=True),
                video,
                size=(640, 480),
                fps=30.0,
                yaw=45.0,
                perspective=800.0,
                moving_background=True,
                seed=1,
            )
            marks = truth.joints2d[0]
        elif args.seconds:
            render_clip(walk_cycle(args.seconds, 30.0), video, size=(640, 480), fps=30.0, view="three-quarter", seed=1)
        else:
            shutil.copy(args.video, video)  # edits are saved beside it: not the sample's
        if args.startup:
            bench_startup(video, args.repeats)
        elif args.play:
            bench_play(video, args.repeats)
        else:
            bench(video, args.repeats, marks=marks)
    return 0


if __name__ == "__main__":
    sys.exit(main())
