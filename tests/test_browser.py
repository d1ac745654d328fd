"""The app in a real browser: Debian's chromium driven by Python playwright.

Each test serves a fresh copy of a tiny rendered clip on port 0 and does what a user
does: steps frames, flips a foreshortening toggle (button and 3D segment), places a
joint override by clicking the video frame and undoes it, downloads a BVH, uses
two tabs at once, watches preprocessing, kills the server mid-work, and switches to
the tracking method, marks the 16 joints by clicking and tracks them. Screenshots
go to artifacts/browser/ (gitignored).
"""

from __future__ import annotations

import os
import re
import signal
import subprocess
import sys

import bvhio
import numpy as np
import pytest
from app_helpers import (  # noqa: F401
    TINY_FRAMES,
    app,
    deepest_segment,
    download_export,
    fresh_copy,
    hold_fitting,
    panning_clip,
    started_app,
    tiny_video,
)
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    TIMEOUT_MS,
    VIEWPORT,
    open_page,
    screen_point,
    shot,
    unhidden_point,
    wait_until,
)

from app.signs import segment_label, sign_button
from mocap.body import JOINT_INDEX, JOINTS, SEGMENT_INDEX
from mocap.io.annotations import load_annotations

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
sync_api = pytest.importorskip("playwright.sync_api")


def video_point(app, xy) -> np.ndarray:
    """The scene point showing video pixel ``xy`` on the video panel."""
    layout, scale = app.layout, app.state.scale
    u = (xy[0] + 0.5) * scale / app.size[0] - 0.5
    v = (xy[1] + 0.5) * scale / app.size[1] - 0.5
    return np.array([layout.video[0] + u * layout.width, layout.video[1] - v * layout.height, 0.0])


def to_tracking(page, status: str) -> None:
    """Choose the tracking method, wait for the status line to say ``status``, and
    open the Tracking tab."""
    page.get_by_label("Method").click()
    page.get_by_role("option", name="tracking").click()
    page.get_by_text(status).wait_for()
    page.get_by_role("tab", name="Tracking").click()


def mark_by_clicking(page, app, joints2d: np.ndarray) -> None:
    """Press Mark joints and click each of the 16 joints (16, 2) where the app asks
    for it on the video frame."""
    page.get_by_role("button", name="Mark joints").click()
    for name in JOINTS:
        wait_until(lambda name=name: app.placing == name)
        xy = joints2d[JOINT_INDEX[name]]
        page.mouse.click(*screen_point(page, app, video_point(app, xy)))


def segment_button(page, segment: str):
    """The foreshortening toggle of a segment (its label also shows its state)."""
    return page.get_by_role("button", name=re.compile(f"^{segment_label(segment)}:"))


def test_step_frames_with_buttons_slider_and_keys(browser, app):
    page = open_page(browser, app.server.get_port())
    page.get_by_role("button", name="frame ▶", exact=True).click()
    wait_until(lambda: app.state.frame == 1)
    page.mouse.click(5, VIEWPORT["height"] - 5)  # focus the page, not a control
    page.keyboard.press("l")
    page.keyboard.press("l")
    wait_until(lambda: app.state.frame == 3)
    page.keyboard.press("j")
    wait_until(lambda: app.state.frame == 2)
    box = page.locator(".mantine-NumberInput-input")  # the slider's number box
    # the page shows frame 2 before typing: a late update would overwrite what is typed
    sync_api.expect(box).to_have_value("2", timeout=TIMEOUT_MS)
    box.fill("9")
    page.keyboard.press("Enter")
    wait_until(lambda: app.state.frame == 9)
    keys = app.state.annotations.keyframes  # the fit's proposal
    before = [k for k in keys if k < 9][::-1]
    page.get_by_role("button", name="◀ keyframe").click()
    wait_until(lambda: app.state.frame == before[0])
    page.mouse.click(5, VIEWPORT["height"] - 5)
    for frame in before[1:]:  # one keyframe back per press, each seen through
        page.keyboard.press("Shift+J")
        wait_until(lambda want=frame: app.state.frame == want)
    page.get_by_role("button", name="Unmark keyframe").click()
    page.get_by_role("button", name="Mark as keyframe").wait_for()
    assert load_annotations(app.state.path).keyframes == tuple(k for k in keys if k != before[-1])
    shot(page, "step_frames")


def test_flip_foreshortening_by_button_and_by_3d_click(browser, app):
    app.state.go_to(6)
    page = open_page(browser, app.server.get_port())
    shot(page, "flip_before")
    segment = deepest_segment(app.state)
    handle = app.scene.bodies[1][SEGMENT_INDEX[segment]]  # the side view, where it shows
    pose, placed = app.state.view().pose3d, np.concatenate([handle.position, handle.wxyz])
    segment_button(page, segment).click()
    segment_button(page, segment).filter(has_text="set here").wait_for()
    assert np.abs(app.state.view().pose3d - pose).max() > 0.05
    assert not np.allclose(placed, np.concatenate([handle.position, handle.wxyz]))
    note = load_annotations(app.state.path).frames[6].foreshortening
    assert set(note) == {segment}
    shot(page, "flip_after")

    x, y = screen_point(page, app, unhidden_point(app, segment))
    page.mouse.click(x, y)  # the same segment in 3D flips it back
    wait_until(lambda: np.allclose(placed, np.concatenate([handle.position, handle.wxyz])))
    assert load_annotations(app.state.path).frames[6].foreshortening != note
    np.testing.assert_allclose(app.state.view().pose3d, pose, atol=1e-9)


def test_override_by_clicking_the_frame_then_undo(browser, app):
    app.state.go_to(4)
    opened = app.state.annotations
    page = open_page(browser, app.server.get_port())
    page.get_by_role("tab", name="Joints").click()
    page.get_by_label("Place").click()
    page.get_by_role("option", name="right wrist", exact=True).click()
    wait_until(lambda: app.placing == "wrist_r")
    target = (200.0, 150.0)
    page.mouse.click(*screen_point(page, app, video_point(app, target)))
    page.get_by_text(re.compile(r"right wrist at \(")).wait_for()
    placed = load_annotations(app.state.path).frames[4].joints2d["wrist_r"]
    assert np.hypot(*np.subtract(placed, target)) < 2.0, placed
    np.testing.assert_allclose(app.state.view().joints2d[JOINT_INDEX["wrist_r"]], placed)
    shot(page, "override_placed")
    page.get_by_role("button", name="↶ undo").click()
    page.get_by_text("No override on this frame.").wait_for()
    assert load_annotations(app.state.path) == opened
    shot(page, "override_undone")


def test_swap_legs_pins_each_leg_where_the_other_was_then_undo(browser, app):
    app.state.go_to(4)
    opened, before = app.state.annotations, app.state.view(4).joints2d
    page = open_page(browser, app.server.get_port())
    page.get_by_role("tab", name="Joints").click()
    page.get_by_role("button", name="Swap legs").click()
    page.get_by_text(re.compile(r"left ankle at \(")).wait_for()
    legs = {side: [JOINT_INDEX[f"{j}_{side}"] for j in ("hip", "knee", "ankle")] for side in "lr"}
    np.testing.assert_allclose(app.state.view(4).joints2d[legs["l"]], before[legs["r"]], atol=0.06)
    assert len(load_annotations(app.state.path).frames[4].joints2d) == 6
    shot(page, "legs_swapped")
    page.get_by_role("button", name="↶ undo").click()
    page.get_by_text("No override on this frame.").wait_for()
    assert load_annotations(app.state.path) == opened


def test_download_bvh_that_parses(browser, app, tmp_path):
    page = open_page(browser, app.server.get_port())
    path = download_export(page, "BVH", tmp_path)
    assert path.name == "walk.bvh"
    bvh = bvhio.readAsBvh(str(path))
    assert bvh.FrameCount == len(bvh.Root.Keyframes) == TINY_FRAMES
    page.get_by_role("button", name="Play").click()  # plays to the last frame and stops
    wait_until(lambda: app.state.frame == TINY_FRAMES - 1 and not app.player.playing)
    page.get_by_role("button", name="Play").wait_for()
    shot(page, "played")


def test_switch_to_tracking_mark_by_clicking_and_track(browser, panning_clip, tmp_path):
    video, truth = panning_clip
    app = started_app(fresh_copy(video, tmp_path))
    try:
        page = open_page(browser, app.server.get_port())
        to_tracking(page, "mark the 16 joints on frame 0")
        mark_by_clicking(page, app, truth.joints2d[0])
        page.get_by_text("All 16 joints marked on frame 0.").wait_for()
        marks = load_annotations(app.state.path).frames[0].joints2d
        assert np.abs(np.array([marks[j] for j in JOINTS]) - truth.joints2d[0]).max() < 2.0
        shot(page, "tracking_marked")
        page.get_by_role("button", name="Track", exact=True).click()
        page.get_by_text(f"{TINY_FRAMES} frames tracked.").first.wait_for()
        page.get_by_role("button", name="frame ▶", exact=True).click()
        wait_until(lambda: app.state.frame == 1)
        page.get_by_text("Tracking reliability").first.wait_for()
        view = app.state.view()
        assert view.method == "track" and view.index == 1 and view.pose3d is not None
        err = np.linalg.norm(view.joints2d - truth.joints2d[1], axis=-1)
        assert np.median(err) < 0.04 * truth.body_height_px
        shot(page, "tracking_tracked")
        page.get_by_role("tab", name="Review").click()
        side = {"l": "left", "r": "right"}[app.state.far_arm()]
        page.get_by_text(f"check the {side} elbow and wrist first").wait_for()
        shot(page, "tracking_review")
    finally:
        app.server.stop()


def test_two_tabs_one_truth(browser, app):
    port = app.server.get_port()
    first, second = open_page(browser, port), open_page(browser, port)
    segment = deepest_segment(app.state)
    segment_button(first, segment).click()
    segment_button(second, segment).filter(has_text="set here").wait_for()
    second.get_by_role("button", name="frame ▶", exact=True).click()
    first.get_by_text("Frame 1 of").wait_for()
    for _ in range(3):  # clicks from both tabs at once
        segment_button(first, "torso").click(no_wait_after=True)
        segment_button(second, "torso").click(no_wait_after=True)
    wait_until(lambda: app.state.undo_depth == 7)  # each click one edit, none lost
    label = sign_button("torso", app.state.view())["label"]
    for page in (first, second):
        page.get_by_role("button", name=label, exact=True).wait_for()
    assert app.state.annotations == load_annotations(app.state.path)
    shot(second, "second_tab")


def test_page_usable_while_preprocessing(browser, tiny_video, tmp_path, monkeypatch):
    """Fitted frames show at once; the others say they are not fitted yet."""
    import threading

    from app.serve import create

    gate = threading.Event()
    hold_fitting(monkeypatch, TINY_FRAMES // 2, gate)
    app = create(fresh_copy(tiny_video, tmp_path), port=0)
    try:
        app.state.start()
        page = open_page(browser, app.server.get_port())
        page.get_by_text("Preprocessing: fitting the body model").wait_for()
        page.get_by_text("Similarity S =").wait_for()  # frame 0 is fitted
        shot(page, "preprocessing")
        app.state.go_to(TINY_FRAMES - 1)
        page.get_by_text("Not fitted yet.").wait_for()
        gate.set()
        page.get_by_text(f"{TINY_FRAMES} frames fitted").wait_for()
    finally:
        gate.set()
        app.server.stop()


def test_killing_the_server_loses_no_shown_edit(browser, tiny_video, tmp_path):
    video = fresh_copy(tiny_video, tmp_path)
    server = subprocess.Popen(
        [sys.executable, "-m", "mocap.cli", "serve", str(video), "--port", "0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    try:
        line = next(line for line in server.stdout if line.startswith("mocap: serving"))
        page = open_page(browser, int(re.search(r":(\d+)/$", line.strip()).group(1)))
        page.get_by_text(f"{TINY_FRAMES} frames fitted").wait_for()
        shown = []
        for segment in ("upper_leg_l", "lower_leg_l", "upper_arm_r"):
            segment_button(page, segment).click()
            segment_button(page, segment).filter(has_text="set here").wait_for()
            shown.append(segment)
        segment_button(page, "torso").click()  # in flight when killed
    finally:
        server.send_signal(signal.SIGKILL)
        server.wait(10)
    saved = load_annotations(video.with_suffix(".annotations.json"), TINY_FRAMES)
    assert set(shown) <= set(saved.frames[0].foreshortening)
