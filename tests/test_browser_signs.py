"""The Body tab's foreshortening signs in a real browser, on 4:3, 16:9 and 9:16 clips:
the grouped list (torso and head, each arm, each leg) shows all ten segments, each
with its state as an icon, a word and a colour, and where it comes from; a click on a
button sets the sign (its source becomes "set here"), turns the 3D body and is saved; a
click on the segment in 3D flips it back, a click on the nose flips the head; controls
that cannot act are disabled, before the fit and on a frame where nobody is.
Screenshots: artifacts/browser/signs_*.png."""

from __future__ import annotations

import math
import re
import threading

import numpy as np
import pytest
from app_helpers import deepest_segment, hold_fitting, shaped_app  # noqa: F401
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    TIMEOUT_MS,
    VIEWPORT,
    fitted_camera,
    open_page,
    screen_point,
    shot,
    unhidden_point,
    visible_point,
    wait_until,
)
from helpers import render_walk_with_exit

from app.signs import SIGN_LOOK, segment_label, sign_groups
from mocap.body import SEGMENT_INDEX, SEGMENT_NAMES
from mocap.io.annotations import load_annotations
from mocap.io.export.formats import FORMATS
from mocap.io.export.marks import FACING_MARKS

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
sync_api = pytest.importorskip("playwright.sync_api")
FRAME = 6
NOSE = list(FACING_MARKS).index("nose")


# the controls that wait for the whole clip's fit
AFTER_THE_FIT = (
    "Play",
    "BVH",
    "GLB",
    "CSV",
    "HTML page",
    ("Review", "Next doubtful frame"),
    ("Tracking", "Marks from the silhouette fit"),
)


def sign_of(page, segment: str):
    """A segment's button (its label starts with the segment's name)."""
    return page.get_by_role("button", name=re.compile(f"^{segment_label(segment)}:"))


def check_list(page, view) -> None:
    """Every segment's button under its group's heading, above the next, saying the
    frame's sign (word, icon, colour) and its source."""
    page.mouse.move(1, 1)  # off the buttons: a hovered one is darker
    groups = []
    for heading, segments in sign_groups():
        top = page.get_by_text(heading, exact=True).first.bounding_box()["y"]
        rows = []
        for segment in segments:
            k, button = SEGMENT_INDEX[segment], sign_of(page, segment)
            word, icon, colour = SIGN_LOOK[view.signs[k]]
            text = rf"^\s*{segment_label(segment)}: {word} · {re.escape(view.sign_notes[k])}( · flat)?$"
            sync_api.expect(button).to_have_text(re.compile(text), timeout=TIMEOUT_MS)
            sync_api.expect(button).to_be_enabled()
            assert button.locator(f"svg.icon-tabler-{icon}").count() == 1, (segment, icon)
            assert button.evaluate("b => getComputedStyle(b).backgroundColor") == "rgb({}, {}, {})".format(*colour)
            rows.append(button.bounding_box()["y"])
        groups.append((top, rows))
    assert sum(len(rows) for _, rows in groups) == len(SEGMENT_NAMES)
    for (top, rows), (below, _) in zip(groups, groups[1:] + [(math.inf, None)]):
        assert top < min(rows) and max(rows) < below, "a button outside its group"


def button(page, name: str):
    return page.get_by_role("button", name=name, exact=True)


def keyframe_button(page):
    """Mark as keyframe, or Unmark keyframe on a keyframe."""
    return page.get_by_role("button", name=re.compile("^(Mark as keyframe|Unmark keyframe)$"))


def expect_enabled(page, enabled: bool, *controls) -> None:
    """Each control (a button's name, or (tab, name) for one on a tab) enabled or not;
    the Export folder is opened for the downloads."""
    if not button(page, "BVH").count():
        page.get_by_text("Export", exact=True).first.click()
    for control in controls:
        tab, name = control if isinstance(control, tuple) else (None, control)
        if tab:
            page.get_by_role("tab", name=tab).click()
        expect = sync_api.expect(button(page, name))
        expect.to_be_enabled() if enabled else expect.to_be_disabled()


def placed(handle) -> np.ndarray:
    return np.concatenate([handle.position, handle.wxyz])


def test_sign_list_and_clicks(chromium, shaped_app):  # noqa: F811
    shape, app = shaped_app
    context = chromium.new_context(viewport=VIEWPORT)
    try:
        app.state.go_to(FRAME)
        before = set(app.server.get_clients())
        page = open_page(context, app.server.get_port())
        fitted_camera(app, page, before)
        view = app.state.view()
        check_list(page, view)
        shot(page, f"signs_{shape}_before")

        segment = deepest_segment(app.state)
        k = SEGMENT_INDEX[segment]
        handle, sign = app.scene.bodies[0][k], view.signs[k]
        at = placed(handle)
        sign_of(page, segment).click()
        sign_of(page, segment).filter(has_text="set here").wait_for()
        flipped = app.state.view()
        assert flipped.signs[k] == -sign and flipped.sign_notes[k] == "set here"
        assert load_annotations(app.state.path).frames[FRAME].foreshortening == {segment: SIGN_LOOK[-sign][0]}
        assert np.abs(flipped.pose3d - view.pose3d).max() > 0.05
        wait_until(lambda: not np.allclose(placed(handle), at))  # the 3D body turned
        check_list(page, flipped)  # the word, icon and colour followed
        shot(page, f"signs_{shape}_set")

        point = visible_point(app, segment)
        if point is None:  # flipped behind the body in both views
            sign_of(page, segment).click()  # back from the list (the nose below: in 3D)
        else:
            page.mouse.click(*screen_point(page, app, point))  # in 3D: back
        wait_until(lambda: app.state.view().signs[k] == sign)
        wait_until(lambda: np.allclose(placed(handle), at))
        sign_of(page, segment).filter(has_text=SIGN_LOOK[sign][0]).wait_for()

        head = SEGMENT_INDEX["head"]
        was = app.state.view().signs[head]
        page.mouse.click(*screen_point(page, app, unhidden_point(app, mark=NOSE)))  # the nose: the head
        wait_until(lambda: app.state.view().signs[head] == -was)
        sign_of(page, "head").filter(has_text="set here").wait_for()
    finally:
        context.close()


def test_controls_that_cannot_act_are_disabled(browser, tmp_path, monkeypatch):  # noqa: F811
    """Before the fit: no sign, keyframe, download or review; a frame where nobody is:
    no sign nor keyframe; each enabled again when it can act."""
    from app.serve import create

    render_walk_with_exit(tmp_path / "exit.mp4", gone=slice(12, 18))
    gate = threading.Event()
    hold_fitting(monkeypatch, 20, gate)
    app = create(tmp_path / "exit.mp4", port=0)
    try:
        app.state.start()
        page = open_page(browser, app.server.get_port())
        wait_until(lambda: app.state.view(0).fitted)
        for segment in SEGMENT_NAMES:  # fitted in 2D, not yet lifted
            sync_api.expect(sign_of(page, segment)).to_be_disabled()
        sync_api.expect(button(page, "Unmark keyframe")).to_be_enabled()  # every frame, until the fit proposes
        expect_enabled(page, False, *AFTER_THE_FIT, ("Joints", "Clear override"))
        app.state.go_to(25)  # not fitted yet
        sync_api.expect(keyframe_button(page)).to_be_disabled()
        shot(page, "signs_disabled_preprocessing")
        gate.set()
        assert app.state.ready.wait(60)
        sync_api.expect(keyframe_button(page)).to_be_enabled()
        expect_enabled(page, True, *AFTER_THE_FIT)
        fbx = sync_api.expect(button(page, "FBX"))  # only with Blender installed (the fbx extra)
        fbx.to_be_enabled() if FORMATS["fbx"].available() else fbx.to_be_disabled()
        page.get_by_role("tab", name="Body").click()
        check_list(page, app.state.view())
        app.state.go_to(14)  # the performer is out of the frame
        assert app.state.view().fitted and app.state.view().joints2d is None
        for segment in SEGMENT_NAMES:
            sync_api.expect(sign_of(page, segment)).to_be_disabled()
            sync_api.expect(sign_of(page, segment)).to_have_text(re.compile(rf"^\s*{segment_label(segment)}: –$"))
        sync_api.expect(keyframe_button(page)).to_be_disabled()
        shot(page, "signs_disabled_nobody")
    finally:
        gate.set()
        app.server.stop()
