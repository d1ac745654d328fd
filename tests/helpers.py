"""Small rendered clips with exact ground truth, and where the real test data lives.

Clips are tiny (320x240, 30 frames) so that the suite stays fast on two cores. At
15 fps two seconds of walking cross most of the frame, which lets the background
estimate (a temporal median) see the empty scene at every pixel.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

import cv2
import numpy as np

from mocap import synth
from mocap.io.video import write_video
from mocap.synth import RenderOptions
from mocap.synth.truth import Truth
from mocap.synth.walk import walk_cycle

SHARED_DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
DOG_WALKER = SHARED_DATA / "video" / "dog_walker.avi"
DEV_CLIPS = SHARED_DATA / "clips"  # rendered CMU motion capture with exact masks (README there)
# joints marked by hand on every third frame of dog_walker (see the file's own notes)
DOG_WALKER_LABELS = Path(__file__).resolve().parent / "data" / "dog_walker.labels.json"
CLIP = dict(size=(320, 240), fps=15.0, seconds=2.0)


def render_walk(path: str | Path, view: str = "side", seed: int = 1, **overrides) -> Truth:
    """The procedural walk across a CLIP-sized frame; returns its truth."""
    opts = {**CLIP, **overrides}
    joints = walk_cycle(opts.pop("seconds"), opts["fps"])
    return synth.render_clip(joints, path, view=view, seed=seed, **opts)


def render_tracked_walk(path: str | Path, **overrides) -> Truth:
    """The tracking method's walk: 320x240, three-quarter, a pinhole camera and a panning,
    cluttered background (``overrides``: render_clip's other settings, e.g. shape)."""
    return synth.render_clip(
        walk_cycle(1.6, 15.0),
        path,
        size=(320, 240),
        fps=15.0,
        yaw=45.0,
        perspective=400.0,
        moving_background=True,
        seed=3,
        **overrides,
    )


def render_walk_with_exit(path: str | Path, gone: slice, seed: int = 2, regraded: bool = False, **overrides) -> Truth:
    """The walk with the performer stepped far out of the frame (20 m to the image
    right) on the frames of `gone`; the camera frames the walk as if they had stayed.
    ``regraded``: the frames after `gone` in other colours (red and blue swapped, as
    a cut to a camera graded otherwise), where the marked colours are not found.
    Keyword ``overrides`` set RenderOptions fields (e.g. yaw, perspective)."""
    fps, seconds = CLIP["fps"], CLIP["seconds"]
    opts = RenderOptions(size=CLIP["size"], fps=fps, seed=seed, **overrides)
    scene = synth.plan_scene(walk_cycle(seconds, fps), opts)
    joints_cam = scene.joints_cam.copy()
    joints_cam[gone, :, 0] += 20.0
    scene = dataclasses.replace(scene, joints_cam=joints_cam)
    n = len(joints_cam)

    def frame(i: int) -> np.ndarray:
        image = synth.draw_frame(scene, i)
        return np.ascontiguousarray(image[..., ::-1]) if regraded and i >= gone.stop else image

    write_video(path, (frame(i) for i in range(n)), fps, opts.size)
    return synth.scene_truth(scene, "walk-cycle with an exit", np.arange(n))


def render_walk_with_occluder(path: str | Path, hidden: slice, seed: int = 2, **overrides) -> Truth:
    """The walk with a board (grey, as wide as the frame's third) passing in front of
    the camera: it slides in from the image left, covers the performer whole on the
    frames of ``hidden`` and is gone after them. Keyword ``overrides`` set
    RenderOptions fields (e.g. yaw, perspective)."""
    fps, seconds = CLIP["fps"], CLIP["seconds"]
    opts = RenderOptions(size=CLIP["size"], fps=fps, seed=seed, **overrides)
    scene = synth.plan_scene(walk_cycle(seconds, fps), opts)
    truth = synth.scene_truth(scene, "walk-cycle behind a board", np.arange(len(scene.joints_cam)))
    width, height = opts.size
    board = width // 3

    def frame(i: int) -> np.ndarray:
        image = synth.draw_frame(scene, i)
        body = truth.joints2d[i, :, 0]
        left = np.interp(
            i,
            [hidden.start - 2, hidden.start, hidden.stop - 1, hidden.stop + 1],
            [-board, body.min() - 8, body.max() + 8 - board, width],
        )
        lo, hi = int(np.clip(left, 0, width)), int(np.clip(left + board, 0, width))
        image[:, lo:hi] = (90, 95, 100)
        return image

    write_video(path, (frame(i) for i in range(len(truth.joints2d))), fps, opts.size)
    return truth


def assert_root_comes_nearer(frames: list[dict], truth: Truth) -> None:
    """A motion file's ``frames`` of a walk toward the camera: a root on nine frames
    in ten, its depth following the true pelvis' (r >= 0.9), the last frames a
    quarter nearer than the first."""
    have = np.array(["root" in f for f in frames])
    depth = np.array([-f["root"][2] for f in frames if "root" in f])
    true_depth = -truth.pelvis_camera[have, 2]
    assert have.mean() > 0.9 and np.ptp(true_depth) > 2.5
    assert np.corrcoef(depth, true_depth)[0, 1] >= 0.9
    assert depth[-5:].mean() < 0.75 * depth[:5].mean()


def write_empty_scene(path: str | Path, n: int = 20) -> None:
    """A clip of the renderer's room with nobody in it (sensor noise only)."""
    opts = RenderOptions(size=CLIP["size"], fps=CLIP["fps"])
    scene = synth.plan_scene(walk_cycle(1.0, opts.fps), opts)
    room, rng = synth.background(scene, 0), np.random.default_rng(0)
    frames = (np.clip(room + rng.normal(0, 2, room.shape), 0, 255).astype(np.uint8) for _ in range(n))
    write_video(path, frames, opts.fps, opts.size)


def dog_walker_marks() -> dict[str, dict[str, list[float]]]:
    """frame -> joint -> (x, y): the hand marks of dog_walker (mocap.synth.metrics.labelled_errors)."""
    return json.loads(DOG_WALKER_LABELS.read_text())["frames"]


def frame_joints(motion: dict) -> np.ndarray:
    """(F, 16, 2) joints2d of a motion file, NaN where no person was found."""
    return np.array(
        [f["joints2d"] if f.get("person", True) else np.full((16, 2), np.nan) for f in motion["frames"]], dtype=float
    )


def text_mp4(folder: Path) -> Path:
    """A text file named like a video."""
    path = folder / "notes.mp4"
    path.write_text("this is not a video\n" * 20)
    return path


def png_avi(folder: Path) -> Path:
    """A still image renamed like a video."""
    cv2.imwrite(str(folder / "still.png"), np.zeros((48, 64, 3), np.uint8))
    return shutil.move(folder / "still.png", folder / "still.avi")


def page_data(text: str) -> dict:
    """The clip a playback page carries (the JSON of its `const DATA = ...;` line)."""
    line = next(line for line in text.splitlines() if line.startswith("const DATA = "))
    return json.loads(line[len("const DATA = ") :].rstrip(";"))


def run_cli(capsys, *argv) -> tuple[int, list[str]]:
    """Exit code and stderr lines of `mocap ARGV` run in this process."""
    from mocap.cli import main

    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err.splitlines()


def assert_one_line_error(err: list[str], *words: str) -> None:
    """stderr is one `mocap: error: ...` line (no traceback) holding every word."""
    assert len(err) == 1, err
    assert err[0].startswith("mocap: error: "), err
    for word in words:
        assert word in err[0], err
