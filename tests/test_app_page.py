"""The page's layout per window, its plain words, its keyframes and its playback reel,
without a browser: the layout for a canvas (grids, a phone's views above its sheet, two at a
time where four would be too small), the fit's proposed keyframes and an edit keying its
frame, the dropdowns' words mapped to the contract's names, the joint placing ended by other
work, and the reel's slots shown only once their pictures had time to reach the page."""

from __future__ import annotations

import time
from types import SimpleNamespace

import pytest
from app_helpers import TINY_FRAMES, app, tiny_video  # noqa: F401

from app.controls import NO_JOINT
from app.layout import MIN_SHARE, MIN_SHEET, PAIRS, PANELS, Layout, is_phone
from app.reel import LEAD_S
from app.words import JOINT_CHOICES, ORIENTATION_CHOICES, joint_label, orientation_label
from mocap.body import JOINTS, ORIENTATIONS, segment_label

SHAPES = {"4x3": (320, 240), "16x9": (384, 216), "9x16": (216, 384)}


@pytest.mark.parametrize("shape", list(SHAPES))
def test_a_phone_shows_the_views_above_its_sheet_each_wide_enough(shape):
    canvas = (540, 960)
    layout = Layout.for_video(*SHAPES[shape], canvas)
    assert is_phone(*canvas) and layout.panel_px(*canvas) >= MIN_SHARE * canvas[0]
    top = layout.sheet_top(*canvas)
    assert top <= canvas[1] * (1 - MIN_SHEET) + 1  # the sheet keeps its share
    # the camera puts the views' extent in the rows above the sheet
    position, look_at = layout.camera(*canvas)
    per_px = layout.units_per_px(*canvas)
    bottom = canvas[1] / 2 - (-layout.extent[1] / 2 - look_at[1]) / per_px
    assert bottom <= top
    assert layout.shown == (PANELS if shape != "9x16" else PAIRS[0])
    assert Layout.for_video(*SHAPES[shape], canvas, pair=1).shown == (PANELS if shape != "9x16" else PAIRS[1])


@pytest.mark.parametrize("canvas", [(700, 768), (1276, 900), (892, 720)])
def test_a_landscape_window_shows_four_views_as_large_as_it_can(canvas):
    for size in SHAPES.values():
        layout = Layout.for_video(*size, canvas)
        assert layout.shown == PANELS
        best = max(Layout.grid(*size, *g).panel_px(*canvas) for g in ((2, 2), (4, 1), (1, 4)))
        assert layout.panel_px(*canvas) == best


def test_words_for_the_page():
    assert joint_label("wrist_r") == "right wrist" and joint_label("head_top") == "top of the head"
    assert segment_label("lower_arm_l") == "left lower arm"
    assert orientation_label("forward_left") == "front, turned to image left"
    assert sorted(JOINT_CHOICES.values()) == sorted(JOINTS)
    assert sorted(ORIENTATION_CHOICES.values()) == sorted(ORIENTATIONS)


def test_the_fit_proposes_keyframes_and_an_edit_keys_its_frame(app):  # noqa: F811
    state = app.state
    keys = state.annotations.keyframes
    assert keys is not None and list(keys) == sorted(keys) and keys[0] == 0
    assert {d.frame for d in state.review_stops()} <= set(keys)
    assert state.keyframe_after(keys[0], 1) == keys[1]  # the jumps go between them
    if len(keys) == TINY_FRAMES:
        pytest.skip("every frame of this clip is doubtful")
    free = next(k for k in range(TINY_FRAMES) if k not in keys)
    assert state.set_orientation(free, "right")
    assert free in state.annotations.keyframes and state.view(free).keyframe
    state.undo()
    assert state.annotations.keyframes == keys


def test_dropdowns_speak_plain_words_and_placing_ends_with_other_work(app):  # noqa: F811
    c, state = app.controls, app.state
    assert "front, turned to image right" in c.orientation.options and "forward_right" not in c.orientation.options
    assert "right wrist" in c.joint.options and "wrist_r" not in c.joint.options
    c.joint.value = joint_label("wrist_r")
    assert app.placing == "wrist_r"
    app.refresh()
    assert app.scene.captions["video"].text == "click: right wrist"
    state.set_override(3, "wrist_r", (100.0, 120.0))
    app.refresh()
    assert "**right wrist** at (100, 120)" in c.overrides.content
    event = SimpleNamespace(client=None)
    app._on(lambda: state.go_to(4), placing=True)(event)  # stepping: placing goes on
    assert app.placing == "wrist_r"
    app._on(lambda: state.go_to(5))(event)  # any other tab's work ends it
    assert c.joint.value == NO_JOINT and app.placing is None
    assert app.scene.captions["video"].text == "frame 5"


def test_the_reel_shows_a_frame_once_its_pictures_had_time(app):  # noqa: F811
    reel = app.reel
    reel.key = "test"
    reel.load_ahead(0, time.monotonic() + 60, app._reel_images)
    assert not reel.show(1)  # just sent: not yet
    time.sleep(LEAD_S)
    assert reel.ready(1) and reel.show(1) and reel.shown_frame == 1
    assert not app.scene.video.visible and reel.images[0][1].visible
    assert reel.latest_ready(reel.slots + 5) == reel.slots + 5  # none held: the clock's own
    assert not reel.show(None) and app.scene.video.visible and not reel.images[0][1].visible
