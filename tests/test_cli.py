"""The command line: `mocap fit` on bad and unusual input (exit 2 and one line naming
the problem, never a traceback), a 4K video, `mocap synth` bad arguments, and
`mocap sheet`."""

from __future__ import annotations

import json
import re
import shutil
import subprocess
import sys

import cv2
import numpy as np
import pytest
from helpers import assert_one_line_error, frame_joints, png_avi, render_walk, text_mp4, write_empty_scene
from helpers import run_cli as run

from mocap.cli import main
from mocap.io.export.motion_json import read_motion
from mocap.io.video import iter_frames, write_video
from mocap.synth import render_clip
from mocap.synth.metrics import side_matched_errors
from mocap.synth.walk import walk_cycle

# -- bad input ----------------------------------------------------------------------


def _header_only_avi(tmp_path):
    path = tmp_path / "zero.avi"
    cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 25.0, (160, 120)).release()
    return path


def _nobody_avi(tmp_path):
    path = tmp_path / "room.avi"
    write_empty_scene(path)
    return path


def _one_frame_avi(tmp_path):
    path, first = tmp_path / "one.avi", tmp_path / "first.avi"
    render_walk(first, seconds=0.2)
    write_video(path, (f for i, f in iter_frames(first) if i == 0), 15.0, (320, 240))
    return path


@pytest.mark.parametrize(
    "make, problem",
    [
        (lambda p: p / "missing.mp4", "no such file"),
        (lambda p: p, "is a directory"),
        (text_mp4, "not a video file"),
        (png_avi, "still image"),
        (_header_only_avi, "no frames"),
        (_nobody_avi, "no person found in any of its 20 frames"),
        (
            _one_frame_avi,
            "no person found in its only frame (one who never moves shows only against a photo "
            "of the empty scene: --background",
        ),
    ],
)
def test_fit_refuses_bad_input_in_one_line(tmp_path, capsys, make, problem):
    video, out = make(tmp_path), tmp_path / "out.motion.json"
    code, err = run(capsys, "fit", video, "--out", out, "--quiet")
    assert code == 2
    assert_one_line_error(err, str(video), problem)
    assert not out.exists()


def test_truncated_video_is_fitted_on_the_frames_that_decode(tmp_path, capsys):
    whole = tmp_path / "whole.avi"
    truth = render_walk(whole)
    data = whole.read_bytes()
    cut, out = tmp_path / "cut.avi", tmp_path / "cut.motion.json"
    cut.write_bytes(data[: len(data) // 2])
    code, err = run(capsys, "fit", cut, "--out", out, "--quiet")
    motion = read_motion(out)
    n = motion["video"]["frame_count"]
    # the first warning; the half walk may also be told its planted feet hide the scene
    assert code == 0 and err[0] == (
        f"mocap: warning: {cut}: only {n} of the 30 frames the file "
        "announces decode (truncated or damaged); using those"
    )
    assert all(line.startswith("mocap: warning: ") for line in err)
    assert 10 <= n < 30 and [f["index"] for f in motion["frames"]] == list(range(n))
    assert all(f["person"] for f in motion["frames"])
    err2d = side_matched_errors(frame_joints(motion), truth.joints2d[:n]) / truth.body_height_px
    assert np.median(err2d) < 0.05


def test_4k_video_gives_joints_in_full_resolution_pixels(tmp_path, capsys):
    # 5 frames far apart, drawn at 960x540 and enlarged 4x (drawing at 4K takes seconds)
    small, video, out = tmp_path / "small.avi", tmp_path / "big.avi", tmp_path / "big.motion.json"
    truth = render_clip(walk_cycle(2.0, 30.0)[::12], small, size=(960, 540))
    write_video(
        video,
        (cv2.resize(f, (3840, 2160), interpolation=cv2.INTER_LINEAR) for _, f in iter_frames(small)),
        30.0,
        (3840, 2160),
    )
    code, err = run(capsys, "fit", video, "--out", out, "--quiet")
    assert code == 0, err
    motion = read_motion(out)
    assert (motion["video"]["width"], motion["video"]["height"]) == (3840, 2160)
    assert len(motion["frames"]) == 5
    joints = frame_joints(motion)
    assert np.isfinite(joints).all()
    truth_4k = (truth.joints2d + 0.5) * 4 - 0.5
    err2d = side_matched_errors(joints, truth_4k) / (4 * truth.body_height_px)
    assert np.median(err2d) < 0.08


@pytest.fixture(scope="module")
def mocap_command():
    path = shutil.which("mocap")
    if path is None:
        pytest.skip("the `mocap` command is not installed (pip install -e .)")
    return path


def test_the_installed_command_reports_in_one_line(tmp_path, mocap_command):
    missing = tmp_path / "missing.mp4"
    done = subprocess.run(
        [mocap_command, "fit", str(missing)], capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=60
    )
    assert done.returncode == 2
    assert done.stderr.splitlines() == [f"mocap: error: {missing}: no such file"]


def test_ffmpeg_messages_stay_off_stderr(tmp_path, mocap_command):
    video = text_mp4(tmp_path)
    done = subprocess.run(
        [mocap_command, "fit", str(video)], capture_output=True, text=True, stdin=subprocess.DEVNULL, timeout=60
    )
    assert done.returncode == 2
    assert done.stderr.splitlines() == [f"mocap: error: {video}: not a video file (unrecognised format)"]


def test_fit_starts_without_the_export_and_smoothing_libraries(tmp_path):
    """`mocap fit` imports what a fit needs, not the GLB writer's trimesh and pygltflib
    nor --smooth's scipy.interpolate: a third of a second of every run's start-up; nor
    the other commands' modules (the renderer, the contact sheet, the batch runner) nor,
    with no bar to draw, tqdm."""
    code = "import sys; from mocap.cli import main; main(['fit', sys.argv[1]]); print(*sys.modules)"
    done = subprocess.run(
        [sys.executable, "-c", code, str(tmp_path / "missing.mp4")],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=60,
    )
    imported = set(done.stdout.split())
    assert "mocap.pipeline" in imported
    assert not imported & {
        "trimesh",
        "pygltflib",
        "scipy.interpolate",
        "tqdm",
        "mocap.synth",
        "mocap.batch.sheet",
        "mocap.batch",
    }


def test_fit_names_the_frames_the_review_would_show(tmp_path, capsys, monkeypatch):
    """After what it wrote, `mocap fit` says how many frames are doubtful (the app's
    review queue, most doubtful first) and names the first ones."""
    from mocap.session import review

    video = tmp_path / "walk.avi"
    render_walk(video, seconds=0.6)
    monkeypatch.setattr(review, "LOW_SCORE", 1.1)  # every fit doubtful, ranked by S
    assert main(["fit", str(video), "--quiet"]) == 0
    lines = capsys.readouterr().out.splitlines()
    n = len(read_motion(video.with_suffix(".motion.json"))["frames"])
    assert lines[0] == f"wrote {video.with_suffix('.motion.json')}"
    said = re.fullmatch(
        rf"{n} of {n} frames doubtful, most first: ([0-9, ]+), \.\.\. "
        rf"\(`mocap serve {re.escape(str(video))}` shows why, on its Review tab\)",
        lines[1],
    )
    named = [int(f) for f in said.group(1).split(", ")]
    assert len(set(named)) == 5 and all(0 <= f < n for f in named)


def test_version_and_help_say_what_the_command_is(capsys):
    from importlib.metadata import version

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out == f"mocap {version('mocap')}\n"
    with pytest.raises(SystemExit):
        main(["--help"])
    assert "`mocap fit VIDEO`" in capsys.readouterr().out


# -- mocap synth ----------------------------------------------------------------------


@pytest.mark.parametrize(
    "args, problem",
    [
        (["walk-cycle", "{tmp}/a.mkv"], "video must end in .mp4 or .avi"),
        (["walk-cycle", "{tmp}/a.mp4", "--size", "big"], "--size expects AxB"),
        (["walk-cycle", "{tmp}/a.mp4", "--fps", "0"], "--fps"),
        (["walk-cycle", "{tmp}/no/such/folder/a.mp4"], "does not exist"),
        (["{tmp}/missing.bvh", "{tmp}/a.mp4"], "missing.bvh"),
    ],
)
def test_synth_refuses_bad_arguments(tmp_path, capsys, args, problem):
    code, err = run(capsys, "synth", *[a.format(tmp=tmp_path) for a in args])
    assert code == 2
    assert_one_line_error(err, problem)
    assert not (tmp_path / "a.mp4").exists()


def test_synth_refuses_an_unknown_view(tmp_path):
    with pytest.raises(SystemExit) as exit_:
        main(["synth", "walk-cycle", str(tmp_path / "a.mp4"), "--view", "top"])
    assert exit_.value.code == 2


# -- mocap sheet ----------------------------------------------------------------------


def test_sheet_tiles_frames_beside_their_silhouettes(fitted_walk, tmp_path, capsys):
    clip = fitted_walk("side")
    motion = json.loads(clip.motion.read_text())
    motion["frames"][0] = {"index": 0, "keyframe": False, "person": False}
    edited, sheet = tmp_path / "edited.motion.json", tmp_path / "sheet.png"
    edited.write_text(json.dumps(motion))
    code, err = run(capsys, "sheet", clip.video, edited, "--out", sheet, "--frames", "4")
    assert code == 0, err
    image = cv2.imread(str(sheet))
    # 4 tiles in rows of 3; a tile is the 320x240 frame and its silhouette, 240 px tall
    assert image.shape == (2 * 240, 3 * 2 * 320, 3)
    assert image[240:, 2 * 640 :].max() == 0  # the empty place after the 4th tile


def test_small_videos_are_upscaled_on_the_sheet(tmp_path, capsys):
    video, motion = tmp_path / "small.avi", tmp_path / "small.motion.json"
    render_walk(video, size=(180, 144))
    assert main(["fit", str(video), "--out", str(motion), "--quiet"]) == 0
    code, err = run(capsys, "sheet", video, motion, "--out", tmp_path / "s.png", "--frames", "2")
    assert code == 0, err
    assert cv2.imread(str(tmp_path / "s.png")).shape == (240, 2 * 2 * 300, 3)


@pytest.mark.parametrize(
    "edit, args, problem",
    [
        (lambda m: m["video"].update(frame_count=31), [], "fitted on a video of 320x240, 31 frames"),
        (lambda m: m.update(format="other"), [], "not a mocap-motion version 1 file"),
        (lambda m: None, ["--frames", "0"], "--frames must be at least 1"),
        (lambda m: None, ["--out", "{tmp}/sheet.gif"], "must end in .png or .jpg"),
    ],
)
def test_sheet_refuses_bad_input_in_one_line(fitted_walk, tmp_path, capsys, edit, args, problem):
    clip = fitted_walk("side")
    motion = json.loads(clip.motion.read_text())
    edit(motion)
    path = tmp_path / "m.json"
    path.write_text(json.dumps(motion))
    args = [a.format(tmp=tmp_path) for a in args]
    out = [] if "--out" in args else ["--out", tmp_path / "sheet.png"]
    code, err = run(capsys, "sheet", clip.video, path, *out, *args)
    assert code == 2
    assert_one_line_error(err, problem)
    assert not (tmp_path / "sheet.png").exists()
