"""The product, the paper's classical path and MediaPipe alone on the development
clips, scored side by side against their exact truth.

Per static-camera clip of ../shared/data/clips, with no user input (or, with --oracle,
with each clip's oracle.json annotations), three variants (--variants picks some):

  product     `mocap fit` as shipped: the silhouette method looking also through the
              person model (mocap.person, MediaPipe Pose)
  classical   `mocap fit --person-model none`: the silhouette method alone (the paper)
  mediapipe   MediaPipe Pose alone over the frames in order (mediapipe_motion): its
              landmarks mapped to the 16 joints as joints2d, its world landmarks as
              joints3d, its mask as the silhouettes; a frame where it sees nobody has
              null joints, a failure to the scorer

`mocap fit` runs as the command line's own code, in this process, writing the
silhouettes too. Every variant is scored by ../shared/bench/score.py in a folder of its
own (the product's in the output folder itself, DIR/<clip>/auto.json as before; the
others' in DIR/classical/ and DIR/mediapipe/), and one table compares each clip's
failed frames, 2D error (median, mean), PA-MPJPE, signs, silhouette IoU against the
true masks and frames per second (the variant's wall time, the model's loading
included, its one-time import not: warm_up),
then the scorer's devset line of each.
With --plate each clip gets its background photo (backgrounds/) as the clean plate.
With --true-masks the fit runs on each clip's true masks instead of its own silhouettes
(the product with the person model's landmarks on them, the classical path without):
the fitter's and the lift's error alone, apart from the silhouettes' (no IoU then).
--oracle, --plate and --true-masks change the product and the classical path only.

    python benchmarks/bench_clips.py [--oracle] [--plate | --true-masks] [--clips NAME ...]
                                     [--variants product classical mediapipe] [--keep DIR]
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from mocap.cli import main as mocap_main
from mocap.person import NONE, available, install_hint

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
CLIPS = SHARED / "data" / "clips"
SCORER = SHARED / "bench" / "score.py"

VARIANTS = ("product", "classical", "mediapipe")
PERSON = {"product": "mediapipe", "classical": NONE}  # the person model of each `mocap fit` variant
MOTION_FILE = {"auto": "auto.json", "oracle": "oracle.out.json", "peer": "peer_mp.json"}  # the scorer's OUTPUTS
COLUMNS = ("fail%", "2d_med%", "2d_mean%", "pa-mpjpe", "signs%", "iou", "fps")  # of the scorer's table


def clip_names() -> list[str]:
    """The static-camera clips (the track_* ones belong to the tracking method)."""
    return sorted(p.name for p in CLIPS.iterdir() if (p / "truth.json").is_file() and not p.name.startswith("track_"))


def clip_folder(name: str, out_dir: Path, masks: bool = True) -> Path:
    """A new folder out_dir/<name>/ holding links to the clip's truth (and true masks)
    as the scorer expects."""
    folder = out_dir / name
    folder.mkdir(parents=True)
    for item in ("truth.json", "masks") if masks else ("truth.json",):
        (folder / item).symlink_to(CLIPS / name / item)
    return folder


def fit_clip(name: str, out_dir: Path, mode: str, plate: bool, person: str = "mediapipe") -> float:
    """Fit one clip with `mocap fit --person-model person` into out_dir/<name>/ as the
    scorer expects; the wall time in seconds."""
    clip, folder = CLIPS / name, clip_folder(name, out_dir)
    argv = [
        "fit",
        str(clip / "video.mp4"),
        "--out",
        str(folder / MOTION_FILE[mode]),
        "--masks",
        str(folder / f"{mode}_masks"),
        "--person-model",
        person,
        "--quiet",
    ]
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


def fit_true_masks(name: str, out_dir: Path, mode: str, person: str = NONE) -> float:
    """Fit one clip's true masks (the frames' grey levels kept for the inner edges; the
    ``person`` model's landmarks on them) into out_dir/<name>/ as fit_clip does, with no
    silhouettes written; the wall time."""
    from mocap.io.export.formats import write_format

    folder = clip_folder(name, out_dir, masks=False)
    start = time.perf_counter()
    session = true_mask_session(name, mode, person=person)
    write_format("json", folder / MOTION_FILE[mode], session.clip())
    return time.perf_counter() - start


def true_mask_session(name: str, mode: str = "auto", grow: int = 0, person: str = NONE):
    """The silhouette method's session of one clip fitted on its true masks (the
    pipeline's own pass two), with the clip's oracle.json annotations in mode
    "oracle", none otherwise; each mask dilated by ``grow`` pixels (eroded where
    negative); with the ``person`` model's landmarks (mocap.person) as data."""
    from mocap.io.annotations import Annotations, load_annotations
    from mocap.session.silhouette import SilhouetteSession
    from mocap.silhouette.passes import FitStream

    clip = CLIPS / name
    info, scale, silhouettes = mask_silhouettes(clip, clip / "masks", grow, person)
    stream, fits = FitStream(scale, info.fps), []
    for silhouette in silhouettes:  # the pipeline's own pass two
        fits += stream.push(silhouette)
    fits += stream.finish()
    notes = load_annotations(clip / "oracle.json", info.frame_count) if mode == "oracle" else Annotations()
    return SilhouetteSession(
        info,
        fits,
        notes,
        silhouettes=silhouettes,  # their grey levels: the heads' look
        person=person,
    )


def mask_silhouettes(clip: Path, masks: Path, grow: int = 0, person: str = NONE):
    """(video info, processing scale, Silhouettes) of a clip's frames from the masks
    in ``masks`` (000000.png ..., any size), with the frames' grey levels; each mask
    dilated by ``grow`` pixels (eroded where negative); each carrying the ``person``
    model's landmarks where it sees somebody (as the pipeline's pass one does)."""
    import cv2
    import numpy as np

    from mocap.io.video import iter_frames, open_video, processing_scale
    from mocap.person import open_person_model
    from mocap.silhouette.passes import Silhouette

    info = open_video(clip / "video.mp4")
    scale = processing_scale(info)
    model, silhouettes = open_person_model(person, filtered=False), []
    try:
        for index, frame in iter_frames(info, scale=scale):
            path = masks / f"{index:06d}.png"
            if not path.is_file():
                raise SystemExit(f"no mask {path} for frame {index} of {clip.name}")
            mask = cv2.imread(str(path), cv2.IMREAD_GRAYSCALE)
            mask = cv2.resize(mask, frame.shape[1::-1], interpolation=cv2.INTER_NEAREST)
            if grow:
                square = np.ones((2 * abs(grow) + 1,) * 2, np.uint8)
                mask = (cv2.dilate if grow > 0 else cv2.erode)(mask, square)
            view = None if model is None else model.observe(frame)
            silhouettes.append(Silhouette.from_mask(mask, frame, None if view is None else view.landmarks))
    finally:
        if model is not None:
            model.close()
    return info, scale, silhouettes


def mediapipe_clip(name: str, out_dir: Path) -> float:
    """MediaPipe alone on one clip into out_dir/<name>/ as the scorer expects (mode
    "peer"); the wall time in seconds."""
    folder = clip_folder(name, out_dir)
    start = time.perf_counter()
    mediapipe_motion(CLIPS / name / "video.mp4", folder / MOTION_FILE["peer"], folder / "peer_masks")
    return time.perf_counter() - start


def mediapipe_motion(video: Path, out: Path, masks: Path | None = None) -> int:
    """MediaPipe Pose alone over a video's frames in order (cv2.VideoCapture, the model's
    video mode with its own landmark smoothing, as it comes), written to ``out`` as a
    mocap-motion file (CONTRACT.md): its landmarks mapped to the 16 joints (mocap.person.mediapipe_pose) as joints2d and confidence, its
    world landmarks as joints3d, every frame a keyframe; a frame where it sees nobody
    with null joints. With ``masks``, its mask (probability > 0.5) as each frame's
    silhouette there (empty where it sees nobody). The number of frames."""
    import cv2
    import numpy as np

    from mocap.body import JOINTS
    from mocap.person import open_person_model

    capture, model, frames = cv2.VideoCapture(str(video)), open_person_model("mediapipe"), []
    size = [int(capture.get(p)) for p in (cv2.CAP_PROP_FRAME_WIDTH, cv2.CAP_PROP_FRAME_HEIGHT)]
    if masks is not None:
        masks.mkdir(parents=True, exist_ok=True)
    try:
        while (frame := capture.read()[1]) is not None:
            view, index = model.observe(frame), len(frames)
            seen = view is not None
            frames.append(
                {
                    "index": index,
                    "keyframe": True,
                    "person": seen,
                    "joints2d": view.landmarks.joints2d.tolist() if seen else None,
                    "joints3d": view.landmarks.world.tolist() if seen else None,
                    "confidence": view.landmarks.confidence.tolist() if seen else None,
                }
            )
            if masks is not None:
                mask = (view.mask > 0.5) if seen else np.zeros(frame.shape[:2], bool)
                cv2.imwrite(str(masks / f"{index:06d}.png"), mask.astype(np.uint8) * 255)
        fps = capture.get(cv2.CAP_PROP_FPS)
    finally:
        model.close()
        capture.release()
    motion = {
        "format": "mocap-motion",
        "version": 1,
        "video": {"path": str(video), "width": size[0], "height": size[1], "fps": fps, "frame_count": len(frames)},
        "joints": list(JOINTS),
        "frames": frames,
    }
    if masks is not None:
        motion["masks"] = os.path.relpath(masks, out.parent)
    out.write_text(json.dumps(motion))
    return len(frames)


def background_photo(clip: Path) -> Path:
    """The photo in backgrounds/ that the clip was rendered over: the one nearest its
    first frame (the clips' folders do not name it)."""
    import cv2
    import numpy as np

    ok, frame = cv2.VideoCapture(str(clip / "video.mp4")).read()
    photos = sorted((CLIPS / "backgrounds").glob("*.jpg"))
    return min(photos, key=lambda p: float(np.median(cv2.absdiff(cv2.imread(str(p)), frame))))


def warm_up() -> None:
    """Import and load MediaPipe once, untimed: its first import (seconds) would
    otherwise count in whichever variant runs first, and skew its frames per second."""
    import numpy as np

    from mocap.person import open_person_model

    model = open_person_model("mediapipe")
    model.observe(np.zeros((256, 256, 3), np.uint8))  # a graph closed unused logs to stderr
    model.close()


def run_variant(variant: str, names: list[str], root: Path, args) -> str:
    """Run one variant on every clip into ``root`` with a timings file for the scorer
    (lines 'clip mode seconds'); the scorer's mode it is scored in."""
    mode = "peer" if variant == "mediapipe" else "oracle" if args.oracle else "auto"
    timings = []
    for name in names:
        if variant == "mediapipe":
            seconds = mediapipe_clip(name, root)
        elif args.true_masks:
            seconds = fit_true_masks(name, root, mode, PERSON[variant])
        else:
            seconds = fit_clip(name, root, mode, args.plate, PERSON[variant])
        timings.append(f"{name} {mode} {seconds:.3f}")
    root.mkdir(parents=True, exist_ok=True)
    (root / "timings.txt").write_text("\n".join(timings) + "\n")
    return mode


def scored_rows(root: Path, mode: str) -> tuple[dict[str, dict[str, str]], str]:
    """The scorer's verdict on one variant's folder: each clip's row as {column: cell}
    (its table's header names the columns) and its devset line."""
    result = subprocess.run(
        [sys.executable, str(SCORER), "--clips", str(root), "--modes", mode, "--timings", str(root / "timings.txt")],
        capture_output=True,
        text=True,
        check=True,
    )
    lines = result.stdout.splitlines()
    header = next(line.split() for line in lines if line.startswith("clip "))
    rows = {
        cells[0]: dict(zip(header, cells))
        for cells in map(str.split, lines)
        if len(cells) == len(header) and cells[1] == mode
    }
    return rows, next(line for line in lines if line.startswith("devset:"))


def print_comparison(names: list[str], scored: dict[str, tuple[dict, str]]) -> None:
    """One row per clip and variant of the COLUMNS, then each variant's devset line."""
    print(f"{'clip':17s} {'variant':10s}" + "".join(f"{c:>9s}" for c in COLUMNS))
    for name in names:
        for variant, (rows, _) in scored.items():
            row = rows.get(name, {})
            print(f"{name:17s} {variant:10s}" + "".join(f"{row.get(c, '?'):>9s}" for c in COLUMNS))
    for variant, (_, devset) in scored.items():
        print(f"{variant:10s} {devset}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--oracle", action="store_true", help="fit with each clip's oracle.json annotations")
    parser.add_argument("--plate", action="store_true", help="give each clip its background photo")
    parser.add_argument("--true-masks", action="store_true", help="fit each clip's true masks")
    parser.add_argument("--clips", nargs="+", metavar="NAME", help="only these clips")
    parser.add_argument(
        "--variants", nargs="+", choices=VARIANTS, default=list(VARIANTS), help="which to run (default: all three)"
    )
    parser.add_argument("--keep", type=Path, metavar="DIR", help="write the outputs here (default: a temp dir)")
    args = parser.parse_args()
    if not (CLIPS.is_dir() and SCORER.is_file()):
        print(f"skipped: {CLIPS} or {SCORER} is absent (the shared data sits beside the checkout)")
        return 0
    if {"product", "mediapipe"} & set(args.variants) and not available("mediapipe"):
        raise SystemExit(install_hint("mediapipe"))
    if {"product", "mediapipe"} & set(args.variants):
        warm_up()
    names = args.clips or clip_names()
    with tempfile.TemporaryDirectory() as tmp:
        out_dir = args.keep or Path(tmp)
        scored = {}
        for variant in (v for v in VARIANTS if v in args.variants):
            root = out_dir if variant == "product" else out_dir / variant
            scored[variant] = scored_rows(root, run_variant(variant, names, root, args))
    print_comparison(names, scored)
    return 0


if __name__ == "__main__":
    sys.exit(main())
