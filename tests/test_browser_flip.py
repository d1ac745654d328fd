"""A flipped segment is shown, in a real browser: the far-side lower arm, hidden behind
the torso in the camera's view, flipped by its button, flashes in both 3D views (drawn in
the flash colour, its place before the flip as a ghost, the rest of the body seen through),
so that both 3D views' pixels change, and the side view turns to the arm's side for good;
the flash ends on its own. Screenshots: artifacts/browser/flip_far_*.png."""

from __future__ import annotations

import re

import cv2
import numpy as np
import pytest
from app_helpers import app, tiny_video  # noqa: F401
from browser_helpers import (
    SKIP_WITHOUT_CHROMIUM,
    TIMEOUT_MS,
    fitted_camera,
    open_page,
    panel_boxes,
    shot,
    visible_point,
    wait_until,
)

from app.main import FLASH_S
from app.scene import side_seen_from
from app.signs import segment_label

pytestmark = [pytest.mark.browser, SKIP_WITHOUT_CHROMIUM]
sync_api = pytest.importorskip("playwright.sync_api")


def far_arm(app) -> tuple[int, str]:
    """(frame, segment): a lower arm hidden in the camera's 3D view on a frame, nearest the middle."""
    n = app.state.n_frames
    for frame in sorted(range(n), key=lambda k: abs(k - n // 2)):
        app.state.go_to(frame)
        app.refresh()
        for segment in ("lower_arm_l", "lower_arm_r"):
            if visible_point(app, segment, views=(0,)) is None:
                return frame, segment
    raise AssertionError("no frame hides a lower arm behind the body")


def crops(page, boxes) -> dict[str, np.ndarray]:
    """The 3D views' pixels (grey) in a screenshot."""
    image = cv2.imdecode(np.frombuffer(page.screenshot(), np.uint8), cv2.IMREAD_GRAYSCALE).astype(np.float32)
    return {name: image[round(b[1]) : round(b[3]), round(b[0]) : round(b[2])] for name, b in boxes.items()}


def test_a_far_side_flip_shows_in_both_3d_views(browser, app):  # noqa: F811
    before_clients = set(app.server.get_clients())
    page = open_page(browser, app.server.get_port())
    fitted_camera(app, page, before_clients)
    frame, segment = far_arm(app)
    page.get_by_text(f"Frame {frame}").first.wait_for()
    page.wait_for_timeout(600)  # the canvas has drawn the frame
    boxes = {name: box for name, box in panel_boxes(page, app, caption=False).items() if name in ("front", "side")}
    before = crops(page, boxes)
    shot(page, "flip_far_before")
    button = page.get_by_role("button", name=re.compile(f"^{segment_label(segment)}:"))
    button.click()
    button.filter(has_text="set here").wait_for()
    wait_until(lambda: app.scene.flashing == segment)
    page.wait_for_timeout(400)
    during = crops(page, boxes)
    shot(page, "flip_far_flashing")
    for name in boxes:  # the flip shows in both 3D views, the camera's where the arm is hidden too
        change = np.abs(during[name] - before[name]).mean()
        assert change > 1.0, f"{name}: the flip of the hidden {segment} changed too little ({change:.2f})"
    # the side view looks from the arm's side, after the flash too; the flash ends on its own
    assert app.scene.side_from == side_seen_from(app.state.view().pose3d, segment)
    wait_until(lambda: app.scene.flashing is None, timeout=FLASH_S + TIMEOUT_MS / 1000)
    assert app.scene.side_from == side_seen_from(app.state.view().pose3d, segment)
    shot(page, "flip_far_after")
