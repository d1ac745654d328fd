"""The tracking method's price against the silhouette method's, on the same clips, in one run.

For each clip (default: the perspective clips of ../shared/data/clips, track_salsa and track_walk, and
bench_track_clips.py's salsa_spin render if --renders names its folder), times in this process:

  silhouette   `mocap fit VIDEO` (the silhouette method, looking through the person model)
  track        `mocap fit --method track VIDEO --annotations MARKS` (frame 0 marked from the truth,
               looking through the person model: its second opinion and re-seeding)
  track alone  the same with --person-model none (the colours alone)
  person       the person model alone over every frame (decoding and observing)

as wall seconds (time.perf_counter, the minimum of --repeats interleaved runs, after an untimed
warm-up that imports and loads MediaPipe), with OpenCV on one thread as `mocap fit` sets it; then
the ratios track / silhouette and track alone / silhouette, and the person model's share of each.

    python benchmarks/bench_track_speed.py [--clips track_walk] [--renders DIR] [--repeats 2]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import cv2

sys.path.insert(0, str(Path(__file__).resolve().parent))

from bench_clips import warm_up  # noqa: E402

from mocap.errors import MocapError  # noqa: E402
from mocap.io.video import iter_frames, open_video, processing_scale  # noqa: E402
from mocap.person import open_person_model  # noqa: E402
from mocap.pipeline import fit_video_to_file  # noqa: E402

DATA = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "clips"
SHARED = ("track_salsa", "track_walk")


def person_alone(video: Path) -> None:
    """The person model over every frame at the processing scale, as both methods feed it."""
    info, model = open_video(video), open_person_model("mediapipe")
    try:
        for _, frame in iter_frames(info, scale=processing_scale(info)):
            model.observe(frame)
    finally:
        model.close()


def variants(video: Path, marks: Path, out: Path) -> dict:
    """name -> a call running it on ``video`` (frame 0 marked in ``marks``), its motion file to ``out``."""
    return {
        "silhouette": lambda: fit_video_to_file(video, {"json": out}, method="silhouette", person="mediapipe"),
        "track": lambda: fit_video_to_file(video, {"json": out}, annotations=marks, method="track", person="mediapipe"),
        "track alone": lambda: fit_video_to_file(
            video, {"json": out}, annotations=marks, method="track", person="none"
        ),
        "person": lambda: person_alone(video),
    }


def clip_files(name: str, renders: Path | None) -> tuple[Path, Path]:
    """(video, frame-0 marks) of a shared clip or of bench_track_clips.py's render in ``renders``."""
    if name in SHARED:
        return DATA / name / "video.mp4", DATA / name / "oracle_track.json"
    if renders is None:
        raise SystemExit(f"{name}: give --renders, the folder of bench_track_clips.py --keep")
    return renders / f"{name}.mp4", renders / f"{name}.marks.json"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--clips", nargs="+", default=None)
    parser.add_argument("--renders", type=Path, help="bench_track_clips.py --keep folder (salsa_spin, laugh_arms_up)")
    parser.add_argument("--repeats", type=int, default=2)
    args = parser.parse_args()
    clips = args.clips or [*SHARED, *(("salsa_spin",) if args.renders else ())]
    cv2.setNumThreads(1)
    warm_up()
    print(
        f"{'clip':<13} {'frames':>6} {'silh s':>7} {'track s':>7} {'alone s':>7} {'person s':>8} {'track/silh':>10} "
        f"{'alone/silh':>10} {'person share':>12}"
    )
    with tempfile.TemporaryDirectory() as tmp:
        for name in clips:
            video, marks = clip_files(name, args.renders)
            runs = variants(video, marks, Path(tmp) / f"{name}.motion.json")
            best = dict.fromkeys(runs, float("inf"))
            try:
                for _ in range(args.repeats):
                    for key, run in runs.items():
                        start = time.perf_counter()
                        run()
                        best[key] = min(best[key], time.perf_counter() - start)
            except MocapError as error:
                print(f"{name:<13} {key} failed: {error}")
                continue
            sil, track, alone, person = (best[k] for k in runs)
            print(
                f"{name:<13} {open_video(video).frame_count:>6} {sil:>7.2f} {track:>7.2f} {alone:>7.2f} {person:>8.2f} "
                f"{track / sil:>10.2f} {alone / sil:>10.2f} {person / track:>12.2f}",
                flush=True,
            )


if __name__ == "__main__":
    main()
