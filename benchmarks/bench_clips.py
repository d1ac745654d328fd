"""The silhouette method on the development clips, scored against their exact truth.

Runs `mocap fit` (the command line's own code, in this process) on every static-camera
clip of ../shared/data/clips with no user input (or, with --oracle, with each clip's
oracle.json annotations), writing the silhouettes too, and scores the results with
../shared/bench/score.py: its per-clip table (2D error, failed frames, PA-MPJPE, signs,
silhouette IoU against the true masks), the fit's frames per second among them.
With --plate each clip gets its background photo (backgrounds/) as the clean plate.
With --true-masks the fit runs on each clip's true masks instead of its own silhouettes:
the fitter's and the lift's error alone, apart from the silhouettes' (no IoU column then).

    python benchmarks/bench_clips.py [--oracle] [--plate | --true-masks] [--clips NAME ...] [--keep DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mocap.cli import main as mocap_main

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
CLIPS = SHARED / "data" / "clips"
SCORER = SHARED / "bench" / "score.py"


def clip_names() -> list[str]:
    """The static-camera clips (the track_* ones belong to the tracking method)."""
    return sorted(p.name for p in CLIPS.iterdir()
                  if (p / "truth.json").is_file() and not p.name.startswith("track_"))


def fit_clip(name: str, out_dir: Path, mode: str, plate: bool) -> float:
    """Fit one clip into out_dir/<name>/ as the scorer expects; the wall time in seconds."""
    clip, folder = CLIPS / name, out_dir / name
    folder.mkdir(parents=True)
    for item in ("truth.json", "masks"):
        (folder / item).symlink_to(clip / item)
    out = folder / ("oracle.out.json" if mode == "oracle" else "auto.json")
    argv = ["fit", str(clip / "video.mp4"), "--out", str(out), "--masks", str(folder / f"{mode}_masks"),
            "--quiet"]
    if mode == "oracle":
        argv += ["--annotations", str(clip / "oracle.json")]
    if plate:
        argv += ["--background", str(background_photo(clip))]
    start = time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()):
        code = mocap_main(argv)
    seconds = time.perf_counter() - start
    if code:
        raise SystemExit(f"mocap fit failed on {name} (exit {code})")
    return seconds


def fit_true_masks(name: str, out_dir: Path, mode: str) -> float:
    """Fit one clip's true masks (the frames' grey levels kept for the inner edges) into
    out_dir/<name>/ as fit_clip does, with no silhouettes written; the wall time."""
    from mocap.io.export.formats import write_format

    folder = out_dir / name
    folder.mkdir(parents=True)
    (folder / "truth.json").symlink_to(CLIPS / name / "truth.json")
    start = time.perf_counter()
    session = true_mask_session(name, mode)
    write_format("json", folder / ("oracle.out.json" if mode == "oracle" else "auto.json"), session.clip())
    return time.perf_counter() - start


def true_mask_session(name: str, mode: str = "auto", grow: int = 0):
    """The silhouette method's session of one clip fitted on its true masks (the
    pipeline's own pass two), with the clip's oracle.json annotations in mode
    "oracle", none otherwise; each mask dilated by ``grow`` pixels (eroded where
    negative)."""
    from mocap.io.annotations import Annotations, load_annotations
    from mocap.session.silhouette import SilhouetteSession
    from mocap.silhouette.passes import FitStream

    clip = CLIPS / name
    info, scale, silhouettes = mask_silhouettes(clip, clip / "masks", grow)
    stream, fits = FitStream(scale, info.fps), []
    for silhouette in silhouettes:          # the pipeline's own pass two
        fits += stream.push(silhouette)
    fits += stream.finish()
    notes = load_annotations(clip / "oracle.json", info.frame_count) if mode == "oracle" else Annotations()
    return SilhouetteSession(info, fits, notes, silhouettes=silhouettes)   # their grey levels: the heads' look


def mask_silhouettes(clip: Path, masks: Path, grow: int = 0):
    """(video info, processing scale, Silhouettes) of a clip's frames from the masks
    in ``masks`` (000000.png ..., any size), with the frames' grey levels; each mask
    dilated by ``grow`` pixels (eroded where negative)."""
    import cv2
    import numpy as np

    from mocap.io.video import iter_frames, open_video, processing_scale
    from mocap.silhouette.passes import Silhouette

    info = open_video(clip / "video.mp4")
    scale = processing_scale(info)
    silhouettes = []
    for index, frame in iter_frames(info, scale=scale):
        path = masks / f"{index:06d}.png"
        if not path.is_file():
            raise SystemExit(f"no mask {path} for frame {index} of {clip.name}")
        mask = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
        mask = cv2.resize(mask, frame.shape[1::-1], interpolation=cv2.INTER_NEAREST)
        if grow:
            square = np.ones((2 * abs(grow) + 1,) * 2, np.uint8)
            mask = (cv2.dilate if grow > 0 else cv2.erode)(mask, square)
        silhouettes.append(Silhouette.from_mask(mask, frame))
    return info, scale, silhouettes


def background_photo(clip: Path) -> Path:
    """The photo in backgrounds/ that the clip was rendered over: the one nearest its
    first frame (the clips' folders do not name it)."""
    import cv2
    import numpy as np
    ok, frame = cv2.VideoCapture(str(clip / "video.mp4")).read()
    photos = sorted((CLIPS / "backgrounds").glob("*.jpg"))
    return min(photos, key=lambda p: float(np.median(cv2.absdiff(cv2.imread(str(p)), frame))))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--oracle", action="store_true", help="fit with each clip's oracle.json annotations")
    parser.add_argument("--plate", action="store_true", help="give each clip its background photo")
    parser.add_argument("--true-masks", action="store_true", help="fit each clip's true masks")
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    parser.add_argument("--keep", type=Path, metavar="DIR", help="write the outputs here (default: a temp dir)")
    args = parser.parse_args()
    if not (CLIPS.is_dir() and SCORER.is_file()):
        print(f"skipped: {CLIPS} or {SCORER} is absent (the shared data sits beside the checkout)")
        return 0
    mode = "oracle" if args.oracle else "auto"
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = args.keep or Path(tmp)
        timings = []
        for name in args.clips or clip_names():
            seconds = (fit_true_masks(name, out_dir, mode) if args.true_masks
                       else fit_clip(name, out_dir, mode, args.plate))
            timings.append(f"{name} {mode} {seconds:.3f}")
        (out_dir / "timings.txt").write_text("\n".join(timings) + "\n")
        result = subprocess.run([sys.executable, str(SCORER), "--clips", str(out_dir), "--modes", mode,
                                 "--timings", str(out_dir / "timings.txt")],
                                capture_output=True, text=True, check=True)
    lines = result.stdout.splitlines()
    table = [ln for ln in lines if not ln.startswith(("per joint", " ")) and ln.split()[0] not in _JOINT_ROWS]
    print("\n".join(table))
    return 0


_JOINT_ROWS = {"head_top", "neck", "chest", "pelvis", "shoulder_l", "elbow_l", "wrist_l", "shoulder_r",
               "elbow_r", "wrist_r", "hip_l", "knee_l", "ankle_l", "hip_r", "knee_r", "ankle_r"}


if __name__ == "__main__":
    sys.exit(main())
