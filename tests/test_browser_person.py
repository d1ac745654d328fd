"""The learned eyes (mocap.person) in a real browser (Debian's chromium, playwright):
the status line names the eyes the fit used, the Stage tab's checkbox of the person
model's joints shows and hides them on the silhouette panel, and its Learned eyes
checkbox refits by the silhouettes alone. Screenshots go to artifacts/browser/."""

from __future__ import annotations

import time

import cv2
import numpy as np
import pytest
from app_helpers import tiny_video  # noqa: F401
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    fitted_camera,
    open_page,
    panel_boxes,
    shot,
    wait_until,
)
from test_app_person import NEEDS_MEDIAPIPE, app, seen_frame  # noqa: F401

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM, NEEDS_MEDIAPIPE]
sync_api = pytest.importorskip("playwright.sync_api")


def panel_pixels(page, box) -> np.ndarray:
    """The page's pixels (BGR) inside ``box``, a little inset from its edges."""
    image = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_COLOR)
    x0, y0, x1, y1 = box
    dx, dy = 0.02 * (x1 - x0), 0.02 * (y1 - y0)
    return image[round(y0 + dy) : round(y1 - dy), round(x0 + dx) : round(x1 - dx)].astype(int)


def magenta(pixels: np.ndarray) -> np.ndarray:
    """Where pixels (BGR) are the landmarks' magenta: red and blue high, green low."""
    b, g, r = pixels[..., 0], pixels[..., 1], pixels[..., 2]
    return (r > 150) & (b > 150) & (g < 120)


def settled(page, box, changed, timeout: float = 15.0) -> np.ndarray:
    """The panel's pixels once ``changed(pixels)`` holds (the canvas redraws a moment
    after the server sends the image)."""
    end = time.monotonic() + timeout
    while True:
        pixels = panel_pixels(page, box)
        if changed(pixels):
            return pixels
        assert time.monotonic() < end, "the silhouette panel did not change"
        page.wait_for_timeout(200)


def test_status_names_the_eyes_and_the_joints_checkbox_shows_them(browser, app):
    state = app.state
    state.go_to(seen_frame(state))
    before = set(app.server.get_clients())
    page = open_page(browser, app.server.get_port())
    fitted_camera(app, page, before)
    page.get_by_text("Eyes: person model (MediaPipe) + silhouettes").wait_for()
    box = panel_boxes(page, app, caption=False)["silhouette"]
    page.get_by_role("tab", name="Stage").click()
    joints = page.get_by_label("Show the person model's joints")
    assert joints.is_checked()
    shown = settled(page, box, lambda p: magenta(p).sum() > 30)
    shot(page, "person_joints_shown")

    joints.click()  # off: the magenta dots and bones go
    wait_until(lambda: app.controls.show_landmarks.value is False)
    hidden = settled(page, box, lambda p: magenta(p).sum() < 0.2 * magenta(shown).sum())
    differ = np.abs(shown - hidden).max(axis=2) > 60
    assert differ.sum() > 30 and magenta(shown)[differ].mean() > 0.3
    joints.click()  # on again: back as they were
    wait_until(lambda: app.controls.show_landmarks.value is True)
    settled(page, box, lambda p: magenta(p).sum() > 0.8 * magenta(shown).sum())

    eyes = page.get_by_label("Learned eyes (person model)")
    assert eyes.is_checked() and eyes.is_enabled()
    eyes.click()  # off: refitted by the silhouettes alone
    page.get_by_text("Eyes: silhouettes only").wait_for(timeout=60_000)
    wait_until(lambda: state.ready.is_set() and state.progress.ready, timeout=60)
    assert state._fitted.person_model == "none" and not eyes.is_checked()
    settled(page, box, lambda p: magenta(p).sum() < 0.2 * magenta(shown).sum())
    shot(page, "person_eyes_off")
