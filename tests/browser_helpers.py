"""Driving the app in Debian's chromium with Python playwright: the browser
fixtures, opening a page, screenshots, and where a scene point shows on the page
(import the fixtures by name into a test module)."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from app.layout import GAP

CHROMIUM = Path("/usr/bin/chromium")
SKIP_WITHOUT_CHROMIUM = pytest.mark.skipif(not CHROMIUM.exists(),
                                       reason="Debian's chromium is not installed (apt-get install chromium)")

try:
    from playwright import sync_api
except ImportError:         # the tests that need it are skipped
    sync_api = None

ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts" / "browser"
CHROMIUM_ARGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
                 "--disable-background-networking", "--disable-component-update", "--disable-sync"]
VIEWPORT = {"width": 1280, "height": 800}
TIMEOUT_MS = 20_000
PANELS = ("video", "silhouette", "front", "side")


@pytest.fixture(scope="module")
def chromium():
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=str(CHROMIUM), args=CHROMIUM_ARGS)
        yield browser
        browser.close()


@pytest.fixture
def browser(chromium):
    """A fresh browser context per test, closed after it (closed tabs stop drawing)."""
    context = chromium.new_context(viewport=VIEWPORT, accept_downloads=True)
    yield context
    context.close()


def open_page(browser, port: int):
    """A new tab on the app, once its controls are up; the headless WebGL warning closed."""
    page = browser.new_page()
    page.set_default_timeout(TIMEOUT_MS)
    page.goto(f"http://127.0.0.1:{port}/")
    page.get_by_text(re.compile("frames fitted|Preprocessing")).first.wait_for()
    warning = page.get_by_text("Software WebGL rendering detected")
    if warning.count():
        warning.locator("xpath=../..").get_by_role("button").first.click()
    return page


def shot(page, name: str) -> None:
    """Save a screenshot of the page as a test artifact."""
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    page.wait_for_timeout(400)          # let the canvas draw the last update
    page.screenshot(path=str(ARTIFACTS / f"{name}.png"))


def wait_until(condition, timeout: float = TIMEOUT_MS / 1000) -> None:
    """Poll the server-side ``condition`` until it holds."""
    end = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < end, "timed out"
        time.sleep(0.05)


def screen_point(page, app, world) -> tuple[float, float]:
    """Where a scene point appears on the page, from the tab's camera."""
    box = page.locator("canvas[data-engine]").bounding_box()
    camera = next(iter(app.server.get_clients().values())).camera
    local = Rotation.from_quat(camera.wxyz, scalar_first=True).inv().apply(np.asarray(world) - camera.position)
    focal = box["height"] / 2 / np.tan(camera.fov / 2)
    return (box["x"] + box["width"] / 2 + focal * local[0] / local[2],
            box["y"] + box["height"] / 2 + focal * local[1] / local[2])


def panel_boxes(page, app, caption: bool = True) -> dict[str, tuple[float, float, float, float]]:
    """name -> (left, top, right, bottom) page pixels of each panel, with the caption
    band above it (or the panel's image alone: ``caption`` False)."""
    layout, boxes = app.layout, {}
    top = layout.height / 2 + (GAP if caption else 0.0)
    for name in PANELS:
        x, y = getattr(layout, name)
        corners = [screen_point(page, app, (x + dx * layout.width / 2, y + dy, 0.0))
                   for dx in (-1, 1) for dy in (-layout.height / 2, top)]
        xs, ys = zip(*corners)
        boxes[name] = (min(xs), min(ys), max(xs), max(ys))
    return boxes


def box_of(locator) -> tuple[float, float, float, float]:
    b = locator.bounding_box()
    return b["x"], b["y"], b["x"] + b["width"], b["y"] + b["height"]


def fitted_camera(app, page, before: set[int]) -> None:
    """Wait until the page is the app's only tab (not one of the ids ``before``) and its
    camera looks from where its canvas shows every panel."""
    wait_until(lambda: len(app.server.get_clients()) == 1 and not set(app.server.get_clients()) & before)
    camera = next(iter(app.server.get_clients().values())).camera

    def fitted() -> bool:
        canvas = page.locator("canvas[data-engine]").bounding_box()
        size = (camera.image_width, camera.image_height)
        position, look_at = app.layout.camera(*size, camera.fov)
        return (np.allclose(size, (canvas["width"], canvas["height"]), atol=1.0)
                and np.allclose(camera.position, position, atol=1e-3)
                and np.allclose(camera.look_at, look_at, atol=1e-3))
    wait_until(fitted)


def body_axes(app) -> list[tuple[list, list]]:
    """Per 3D view (the camera's, the side), the scene's (centre, unit axis, scale) of
    every cylinder and of every facing mark (its centre halfway up the cone)."""
    from app.views import SIDE
    views = []
    for body, marks, at, frame in zip(app.scene.bodies, app.scene.marks, (app.layout.front, app.layout.side),
                                      ((1.0, 0.0, 0.0, 0.0), SIDE)):
        turn, origin = Rotation.from_quat(frame, scalar_first=True), np.array(at + (0.0,))

        def axes(handles, lift: float) -> list:
            out = []
            for h in handles:
                axis = turn.apply(Rotation.from_quat(h.wxyz, scalar_first=True).apply([0.0, 0.0, 1.0]))
                out.append((origin + turn.apply(h.position) + lift * h.scale[2] * axis, axis, h.scale))
            return out
        views.append((axes(body, 0.0), axes(marks, 0.5)))
    return views


def unhidden_point(app, segment: str | None = None, mark: int | None = None) -> np.ndarray:
    """A scene point on a segment's cylinder (or on facing mark number ``mark``), in the
    camera or the side view, that no other cylinder hides from the tab's camera (points
    along the axis, middle first)."""
    from mocap.body import SEGMENT_INDEX
    eye = next(iter(app.server.get_clients().values())).camera.position
    k = None if segment is None else SEGMENT_INDEX[segment]
    for cylinders, marks in body_axes(app):
        centre, axis, scale = cylinders[k] if mark is None else marks[mark]
        for t in ((0.0, -0.2, 0.2, -0.35, 0.35) if mark is None else (0.0,)):
            point = centre + t * scale[2] * axis
            ray = (point - eye) / np.linalg.norm(point - eye)
            if not any(_hides(eye, ray, np.linalg.norm(point - eye), other)
                       for j, other in enumerate(cylinders) if j != k):
                return point
    raise AssertionError(f"{segment or mark} is hidden in both 3D views")


def _hides(eye, ray, depth: float, cylinder) -> bool:
    """Whether a cylinder (centre, axis, scale) crosses the ray before ``depth``, or
    passes within half its radius of it (a click there may land on its outline)."""
    centre, axis, scale = cylinder
    samples = centre + np.linspace(-0.5, 0.5, 21)[:, None] * scale[2] * axis
    along = (samples - eye) @ ray
    off = np.linalg.norm(samples - eye - along[:, None] * ray, axis=1)
    radius = max(scale[0], scale[1])
    return bool(np.any((off < 1.5 * radius) & (along < depth - radius)))
