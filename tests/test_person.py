"""The person model (mocap.person): MediaPipe Pose loads from the installed wheel with
the network forbidden and sees the rendered performer; without mediapipe, `mocap fit`
says in one line how to install it and fits by silhouettes alone; an unknown model's
name is refused."""

from __future__ import annotations

import dataclasses
import importlib.util
import json
import socket
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest
from helpers import CLIP, render_walk
from helpers import run_cli as run

from mocap import synth
from mocap.body import JOINT_INDEX
from mocap.cli import main
from mocap.errors import MocapError
from mocap.io.export.motion_json import read_motion
from mocap.person import CHOICES, DEFAULT_MODEL, NONE, PersonView, available, open_person_model, watched
from mocap.person.worker import Apart as Worker
from mocap.synth import RenderOptions
from mocap.synth.metrics import side_matched_errors
from mocap.synth.walk import walk_cycle

INSTALL = "pip install --no-deps mediapipe==0.10.14"
NOT_INSTALLED = (
    "the person model 'mediapipe' needs mediapipe, not installed here: "
    ".venv/bin/pip install --no-deps mediapipe==0.10.14"
)
# The renderer's body as MediaPipe finds it on every frame: slim (the default widths
# make it lose the walker on some frames), with hair (a head it takes for one), seen
# from the front.
SEEN = RenderOptions(size=CLIP["size"], fps=CLIP["fps"], view="front", shape="slim", hair=True, seed=1)
FRAMES = 10


def _no_network(*args, **kwargs):
    raise OSError("network access is forbidden in this test")


@pytest.fixture
def offline(monkeypatch):
    """Every socket connection refused (a model file fetched at first use would fail)."""
    monkeypatch.setattr(socket.socket, "connect", _no_network)
    monkeypatch.setattr(socket.socket, "connect_ex", _no_network)
    monkeypatch.setattr(socket, "create_connection", _no_network)
    with pytest.raises(OSError, match="forbidden"):
        socket.create_connection(("127.0.0.1", 9))


@pytest.fixture
def without_mediapipe(monkeypatch):
    """mediapipe as if not installed: find_spec finds no such package and importing it
    fails (also where an earlier test imported it)."""
    find_spec = importlib.util.find_spec

    def missing(name, *args, **kwargs):
        if name == "mediapipe" or name.startswith("mediapipe."):
            return None
        return find_spec(name, *args, **kwargs)

    monkeypatch.setattr(importlib.util, "find_spec", missing)
    for name in ["mediapipe", *(m for m in sys.modules if m.startswith("mediapipe."))]:
        monkeypatch.setitem(sys.modules, name, None)
    assert not available("mediapipe")


@pytest.fixture(scope="module")
def walk_video(tmp_path_factory):
    """A small rendered walk (helpers.render_walk) to fit."""
    video = tmp_path_factory.mktemp("person") / "walk.avi"
    render_walk(video)
    return video


# -- MediaPipe, offline -------------------------------------------------------------------


@pytest.mark.filterwarnings("ignore:SymbolDatabase.GetPrototype:UserWarning")  # mediapipe on protobuf 4.25
def test_mediapipe_loads_offline_and_sees_the_performer(offline):
    """MediaPipe Pose (model_complexity=1, its model file inside the wheel) opens with
    the network forbidden and, on the first FRAMES frames of a rendered walk seen
    from the front, sees the performer on each: its mask (> 0.5) lies inside the true
    body (95% of it; the renderer's antialiased edge counts as body) and covers most
    of it, its 2D joints lie near the true ones (median 5% of the body's height,
    every joint within 15%), and its 3D joints are in metres, pelvis at the origin,
    y up. Left and right are matched by image side: MediaPipe takes the renderer's
    faceless body for one seen from behind and swaps them (on a render with a face,
    the development clip walk_toward, its anatomical sides are right)."""
    pytest.importorskip("mediapipe", reason=f"mediapipe is not installed ({INSTALL} installs it)")
    joints = walk_cycle(CLIP["seconds"], SEEN.fps)
    scene = synth.plan_scene(joints, SEEN)
    clean = synth.plan_scene(joints, dataclasses.replace(SEEN, noise=0.0))
    truth = synth.scene_truth(scene, synth.WALK_CYCLE, np.arange(len(joints)))
    model = open_person_model("mediapipe")
    assert model is not None and model.name == DEFAULT_MODEL == "mediapipe"
    try:
        views = [model.observe(synth.draw_frame(scene, i)) for i in range(FRAMES)]
    finally:
        model.close()
    assert all(isinstance(v, PersonView) for v in views), [i for i, v in enumerate(views) if v is None]
    height = truth.body_height_px
    for i, view in enumerate(views):
        body = cv2.absdiff(synth.draw_frame(clean, i), synth.background(clean, i)).max(axis=2) > 0
        assert view.mask.shape == body.shape and view.mask.dtype == np.float32
        assert 0.0 <= view.mask.min() and view.mask.max() <= 1.0
        seen = view.mask > 0.5
        assert (seen & body).sum() >= 0.95 * seen.sum(), i
        assert (seen & body).sum() >= 0.8 * body.sum(), i
        marks = view.landmarks
        assert marks.joints2d.shape == (16, 2) and marks.world.shape == (16, 3)
        assert marks.confidence.shape == (16,) and ((0 <= marks.confidence) & (marks.confidence <= 1)).all()
        errors = side_matched_errors(marks.joints2d[None], truth.joints2d[i][None])[0] / height
        assert np.median(errors) < 0.05 and errors.max() < 0.15, (i, np.round(errors * 100))
        up = marks.world[:, 1]
        assert np.allclose(marks.world[JOINT_INDEX["pelvis"]], 0.0)
        assert 0.4 < up[JOINT_INDEX["head_top"]] < 1.0
        assert -1.0 < up[[JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]]].max() < -0.4


@pytest.mark.filterwarnings("ignore:SymbolDatabase.GetPrototype:UserWarning")  # mediapipe on protobuf 4.25
def test_the_model_in_its_own_process_sees_what_it_sees_here():
    """The person model opened apart (mocap.person.worker, the silhouette method's way: frames sent ahead of
    their views) gives the views, frame for frame, that the same model gives in this process (its mask sent in
    byte levels), and so does the model looking at mirror images too."""
    pytest.importorskip("mediapipe", reason=f"mediapipe is not installed ({INSTALL} installs it)")
    scene = synth.plan_scene(walk_cycle(CLIP["seconds"], SEEN.fps), SEEN)
    frames = [synth.draw_frame(scene, i) for i in range(FRAMES)]
    for with_mirror in (False, True):
        here = open_person_model("mediapipe", filtered=False, with_mirror=with_mirror)
        apart = open_person_model("mediapipe", False, apart=True, with_mirror=with_mirror)
        try:
            near = [here.observe(f) for f in frames]
            far = list(watched(apart, iter(frames)))
        finally:
            here.close()
            apart.close()
        assert [f is frame for (f, _), frame in zip(far, frames)] == [True] * FRAMES
        assert all(v is not None for v in near)
        for a, (_, b) in zip(near, far):
            np.testing.assert_allclose(a.mask, b.mask, atol=0.5 / 255)
            np.testing.assert_array_equal(a.landmarks.joints2d, b.landmarks.joints2d)


def test_a_model_that_fails_in_its_own_process_says_why_in_one_line():
    apart = Worker("bogus", "mocap.person.no_such_model", filtered=False)
    try:
        with pytest.raises(MocapError, match="'bogus' does not load: No module named 'mocap.person.no_such_model'"):
            apart.observe(np.zeros((48, 64, 3), np.uint8))
    finally:
        apart.close()


# -- without mediapipe ----------------------------------------------------------------------


def test_fit_without_mediapipe_warns_once_and_fits_by_silhouettes(without_mediapipe, walk_video, tmp_path, capsys):
    """`mocap fit` without mediapipe (the default person model): one warning line
    that says how to install it, then the classical path writes the motion file."""
    out = tmp_path / "walk.motion.json"
    code, err = run(capsys, "fit", walk_video, "--out", out, "--quiet", "--person-model", "mediapipe")
    assert code == 0, err
    assert len(read_motion(out)["frames"]) == 30
    assert [line for line in err if INSTALL in line] == [
        f"mocap: warning: no person model, fitting by silhouettes alone: {NOT_INSTALLED}"
    ], err
    assert all(line.startswith("mocap: warning: ") for line in err), err


def test_fit_with_person_model_none_does_not_warn(without_mediapipe, walk_video, tmp_path, capsys):
    """--person-model none chooses the classical path on purpose: no warning about it."""
    out = tmp_path / "walk.motion.json"
    code, err = run(capsys, "fit", walk_video, "--out", out, "--quiet", "--person-model", NONE)
    assert code == 0 and out.is_file()
    assert not [line for line in err if "mediapipe" in line or "person model" in line], err


def test_opening_mediapipe_without_it_says_how_to_install_in_one_line(without_mediapipe):
    with pytest.raises(MocapError) as error:
        open_person_model("mediapipe")
    assert str(error.value) == NOT_INSTALLED
    assert open_person_model(NONE) is None


# -- unknown names ----------------------------------------------------------------------------


def test_an_unknown_person_model_is_refused(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_:
        main(["fit", str(tmp_path / "walk.avi"), "--person-model", "bogus"])
    assert exit_.value.code == 2
    err = capsys.readouterr().err
    assert "--person-model: invalid choice: 'bogus'" in err and "'mediapipe'" in err and "'none'" in err
    with pytest.raises(MocapError) as error:
        open_person_model("bogus")
    assert str(error.value) == "unknown person model 'bogus': choose one of mediapipe, none"
    assert CHOICES == ("mediapipe", "none")


CLIPS = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "clips"


@pytest.mark.skipif(
    not (CLIPS / "wash_front" / "truth.json").is_file(),
    reason="needs ../shared/data/clips (the development clips) beside the checkout",
)
def test_a_performer_who_stays_is_fitted_with_the_person_model(tmp_path):
    """wash_front: the body stays, only the arms move (real motion capture over grass).
    Background subtraction sees only the arms (the classical path's joints lie a fifth
    of the body's height off); looking through the person model, every frame's joints
    lie within a few percent, and its silhouettes cover the body."""
    pytest.importorskip("mediapipe")
    clip = CLIPS / "wash_front"
    truth = json.loads((clip / "truth.json").read_text())
    true_joints = np.array([f["joints2d"] for f in truth["frames"]], float)
    errors = {}
    for model in ("none", "mediapipe"):
        out, masks = tmp_path / f"{model}.json", tmp_path / f"{model}_masks"
        assert (
            main(
                [
                    "fit",
                    str(clip / "video.mp4"),
                    "--out",
                    str(out),
                    "--masks",
                    str(masks),
                    "--quiet",
                    "--person-model",
                    model,
                ]
            )
            == 0
        )
        frames = json.loads(out.read_text())["frames"]
        joints = np.array([f["joints2d"] for f in frames], float)
        errors[model] = np.linalg.norm(joints - true_joints, axis=-1).mean() / truth["body_height_px"]
        if model == "mediapipe":  # the model sees the body the background never showed: nothing guessed
            assert all(f["silhouette_confidence"] == 1.0 for f in frames if "silhouette_confidence" in f)
            ious = []
            for i in range(0, len(frames), 10):
                fitted = cv2.imread(str(masks / f"{i:06d}.png"), cv2.IMREAD_GRAYSCALE) > 0
                true = cv2.imread(str(clip / "masks" / f"{i:06d}.png"), cv2.IMREAD_GRAYSCALE) > 0
                ious.append((fitted & true).sum() / (fitted | true).sum())
            assert min(ious) > 0.85
    assert errors["none"] > 0.15
    assert errors["mediapipe"] < 0.05
