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
