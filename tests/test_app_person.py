"""The app's learned eyes (mocap.person) without a browser: the app fits through the
person model by default, the Stage tab's switch refits the clip with or without it,
the status line says which eyes the fit used, `mocap serve --person-model` chooses
them, and the silhouette panel tints the pixels only the person model gave and draws
its joints (a checkbox hides them)."""

from __future__ import annotations

import threading
import warnings
from dataclasses import replace

import cv2
import numpy as np
import pytest
from app_helpers import fresh_copy, hold_fitting, started_app, tiny_video  # noqa: F401

from app.views import silhouette_image
from mocap.errors import MocapError, MocapWarning
from mocap.image.draw import LANDMARK_BGR, LANDMARK_BONES, LEARNED_BGR, draw_landmarks, silhouette_view


def mediapipe_importable() -> bool:
    try:
        from mediapipe.python.solutions import pose  # noqa: F401
    except Exception:  # not installed, or a package it needs is not
        return False
    return True


NEEDS_MEDIAPIPE = pytest.mark.skipif(
    not mediapipe_importable(),
    reason="mediapipe is not importable: the person model needs it "
    "(.venv/bin/pip install --no-deps mediapipe==0.10.14)",
)
TEAL = LEARNED_BGR[::-1]  # the panel's image is RGB
MAGENTA = LANDMARK_BGR[::-1]


@pytest.fixture
def app(tiny_video, tmp_path, monkeypatch):  # noqa: F811
    """app_helpers' app as `mocap serve` opens it by default: with the person model
    where it is installed (the suite's MOCAP_PERSON_MODEL=none unset)."""
    monkeypatch.delenv("MOCAP_PERSON_MODEL", raising=False)
    app = started_app(fresh_copy(tiny_video, tmp_path))
    yield app
    app.server.stop()


def seen_frame(state) -> int:
    """A frame whose silhouette the person model saw, with pixels only it gave."""
    for k, sil in enumerate(state._silhouettes):
        if sil is not None and sil.learned is not None and sil.learned_mask().sum() > 40:
            return k
    raise AssertionError("the person model added no pixels on any frame")


def wait_refit(app) -> None:
    assert app.state.ready.wait(60) and app.state.progress.error is None, app.state.progress.error
    app.refresh()


@NEEDS_MEDIAPIPE
def test_the_switch_refits_with_and_without_the_person_model(app, monkeypatch):
    state, c = app.state, app.controls
    wait_refit(app)  # the page's last refresh after the fit runs on the fit's thread
    # by default: the person model, where it is installed
    assert state.person_model == state._fitted.person_model == "mediapipe"
    assert any(s is not None and s.landmarks is not None for s in state._silhouettes)
    seen, cut_out, done = state.eyes_seen()
    said = f"Eyes: person model (MediaPipe) + silhouettes; it saw the performer on {seen} of {done} frames"
    assert (f"({cut_out} of them only when shown the silhouette cut out)" in c.status.content) == (cut_out > 0)
    assert said in c.status.content
    assert (f"the silhouettes alone answer the other {done - seen}." in c.status.content) == (seen < done)
    assert c.learned_eyes.value is True and c.learned_eyes.disabled is False
    with pytest.raises(MocapError, match="already looks through the person model 'mediapipe'"):
        state.set_person_model("mediapipe")
    with pytest.raises(MocapError, match="unknown person model"):
        state.set_person_model("openpose")

    played = app.player.pose(0)  # Play's animation, before the refit
    app._learned_eyes(False)  # the checkbox's callback: off
    wait_refit(app)
    assert state.person_model == state._fitted.person_model == "none"
    np.testing.assert_array_equal(app.player.pose(0), state.animation()[0][0])  # Play's, made anew
    assert not np.array_equal(app.player.pose(0), played)
    assert all(s is None or (s.landmarks is None and s.learned is None) for s in state._silhouettes)
    assert "Eyes: silhouettes only" in c.status.content and "person model (" not in c.status.content
    assert c.learned_eyes.value is False and state.view().pose3d is not None

    gate, held = threading.Event(), threading.Event()
    hold_fitting(monkeypatch, 5, gate, held)
    app._learned_eyes(True)  # on again: refused while that fit runs
    assert held.wait(60) and c.learned_eyes.disabled
    assert "Eyes: person model (MediaPipe)" in c.status.content  # said while it fits
    with pytest.raises(MocapError, match="still running"):
        state.set_person_model("none")
    c.learned_eyes.value = False  # a click the state refuses: the checkbox shows the
    with pytest.raises(MocapError, match="still running"):  # fit's eyes again
        app._learned_eyes(False)
    assert c.learned_eyes.value is True
    gate.set()
    wait_refit(app)
    assert state._fitted.person_model == "mediapipe" and not c.learned_eyes.disabled


@NEEDS_MEDIAPIPE
def test_the_panel_tints_learned_pixels_and_draws_the_landmarks(app):
    state = app.state
    k = seen_frame(state)
    state.go_to(k)
    view = state.view()
    sil = view.silhouette
    shown = app.scene.silhouette.image.copy()
    assert np.array_equal(shown, app._silhouette_image(view))  # what the scene shows

    # the pixels only the person model gave, teal; without them, grey
    def panel(silhouette):
        return silhouette_image(silhouette, None, True, {}, state.scale, app.size, landmarks=False)

    with_learned, without = panel(sil), panel(replace(sil, learned=None))
    learned = np.zeros(app.size[::-1], bool)
    x0, y0, x1, y1 = sil.box
    learned[y0:y1, x0:x1] = sil.learned_mask() > 0
    factor = with_learned.shape[0] // learned.shape[0]
    inner = np.kron(erode(learned), np.ones((factor, factor), bool))  # away from blended edges
    assert inner.sum() > 20
    assert (with_learned[inner] == TEAL).all(axis=1).mean() > 0.9
    assert not (without[inner] == TEAL).all(axis=1).any()

    # the landmarks: magenta dots where the person model put the joints, gone when unticked
    app.controls.show_landmarks.value = False
    app.refresh()
    hidden = app.scene.silhouette.image.copy()
    app.controls.show_landmarks.value = True
    app.refresh()
    assert np.array_equal(app.scene.silhouette.image, shown)
    differ = np.abs(shown.astype(int) - hidden).max(axis=2) > 40
    marks = sil.landmarks.scaled(factor).joints2d
    near = np.zeros(differ.shape, np.uint8)  # the landmarks' dots and bones, and around
    for a, b in LANDMARK_BONES:
        cv2.line(near, tuple(np.round(marks[a]).astype(int)), tuple(np.round(marks[b]).astype(int)), 1, 9)
    for x, y in np.round(marks).astype(int):
        cv2.circle(near, (x, y), 8, 1, -1)
    near[: differ.shape[0] // 8, : differ.shape[1] // 2] = 1  # the legend's line of the joints
    assert differ.sum() > 50 and (differ & (near == 0)).sum() == 0
    sure = sil.landmarks.confidence >= 0.5
    centres = np.round(marks[sure]).astype(int)
    assert sure.any() and all(np.abs(shown[y, x].astype(int) - MAGENTA).max() < 60 for x, y in centres)


def erode(mask: np.ndarray) -> np.ndarray:
    """The pixels of ``mask`` whose four neighbours are in it too."""
    inner = mask.copy()
    inner[1:] &= mask[:-1]
    inner[:-1] &= mask[1:]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return inner


def test_the_overlay_tints_and_dots():
    mask = np.zeros((40, 60), np.uint8)
    mask[5:35, 20:40] = 1
    learned = np.zeros_like(mask)
    learned[25:35, 20:40] = 1
    learned[0:3, 0:3] = 1  # outside the silhouette: not tinted
    view = silhouette_view(mask, None, learned)
    assert (view[30, 30] == LEARNED_BGR).all() and (view[10, 30] == 110).all()
    assert (view[1, 1] == 0).all()
    assert np.array_equal(silhouette_view(mask, None), silhouette_view(mask, None, np.zeros_like(mask)))
    joints = np.tile([30.0, 20.0], (16, 1))
    joints[1] = (10.0, 10.0)
    confidence = np.ones(16)
    confidence[1] = 0.1  # unsure: a ring, not a dot
    image = draw_landmarks(np.zeros((40, 60, 3), np.uint8), joints, confidence)
    assert (image[20, 30] == LANDMARK_BGR).all()
    assert (image[10, 10] == 0).all() and image[7:14, 7:14].any()


def test_the_app_fits_by_silhouettes_alone_without_the_person_model(tiny_video, tmp_path, monkeypatch):
    """Not installed: the app warns, fits by the silhouettes alone and refuses to switch."""
    from app.state import AppState

    monkeypatch.delenv("MOCAP_PERSON_MODEL", raising=False)
    monkeypatch.setattr("mocap.pipeline.available", lambda name="mediapipe": name == "none")
    monkeypatch.setattr("app.preprocess.available", lambda name="mediapipe": name == "none")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        state = AppState(tiny_video, tmp_path / "notes.json")
    assert state.person_model == "none"
    assert any(issubclass(w.category, MocapWarning) and "pip install" in str(w.message) for w in caught)
    state.ready.set()  # as after a fit: the switch is what refuses
    with pytest.raises(MocapError, match="needs mediapipe, not installed here"):
        state.set_person_model("mediapipe")
    assert AppState(tiny_video, tmp_path / "notes.json", "none").person_model == "none"


def test_serve_takes_the_person_model(monkeypatch, tiny_video):
    import app.serve
    from mocap.cli import main

    calls = []
    monkeypatch.setattr(app.serve, "main", lambda *args, **kwargs: calls.append(kwargs))
    assert main(["serve", str(tiny_video), "--person-model", "none", "--port", "0"]) == 0
    assert main(["serve", str(tiny_video), "--port", "0"]) == 0
    assert [c["person"] for c in calls] == ["none", None]
    with pytest.raises(SystemExit):
        main(["serve", str(tiny_video), "--person-model", "openpose"])
