"""Driving the app in Debian's chromium with Python playwright: the browser
fixtures, opening a page, screenshots, and where a scene point shows on the page
(import the fixtures by name into a test module)."""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from app.layout import GAP

CHROMIUM = Path("/usr/bin/chromium")
SKIP_WITHOUT_CHROMIUM = pytest.mark.skipif(
    not CHROMIUM.exists(), reason="Debian's chromium is not installed (apt-get install chromium)"
)

try:
    from playwright import sync_api
except ImportError:  # the tests that need it are skipped
    sync_api = None

ARTIFACTS = Path(__file__).resolve().parents[1] / "artifacts" / "browser"
CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
]
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
    page.wait_for_timeout(400)  # let the canvas draw the last update
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
    return (
        box["x"] + box["width"] / 2 + focal * local[0] / local[2],
        box["y"] + box["height"] / 2 + focal * local[1] / local[2],
    )


def panel_boxes(page, app, caption: bool = True) -> dict[str, tuple[float, float, float, float]]:
    """name -> (left, top, right, bottom) page pixels of each panel shown, with the caption
    band above it (or the panel's image alone: ``caption`` False)."""
    layout, boxes = app.layout, {}
    top = layout.height / 2 + (GAP if caption else 0.0)
    for name in layout.shown:
        x, y = getattr(layout, name)
        corners = [
            screen_point(page, app, (x + dx * layout.width / 2, y + dy, 0.0))
            for dx in (-1, 1)
            for dy in (-layout.height / 2, top)
        ]
        xs, ys = zip(*corners)
        boxes[name] = (min(xs), min(ys), max(xs), max(ys))
    return boxes


def box_of(locator) -> tuple[float, float, float, float]:
    b = locator.bounding_box()
    return b["x"], b["y"], b["x"] + b["width"], b["y"] + b["height"]


def controls_box(page) -> tuple[float, float, float, float]:
    """The box of the control panel (docked beside the canvas, or a phone's bottom sheet over it):
    the outermost element around the tabs that does not hold the canvas."""
    b = page.get_by_role("tablist").first.evaluate(
        """tabs => {
            const canvas = document.querySelector("canvas[data-engine]");
            let box = tabs;
            while (box.parentElement && !box.parentElement.contains(canvas)) box = box.parentElement;
            const r = box.getBoundingClientRect();
            return [r.left, r.top, r.right, r.bottom];
        }"""
    )
    return tuple(b)


def fitted_camera(app, page, before: set[int]) -> None:
    """Wait until the page is the app's only tab (not one of the ids ``before``) and its
    camera looks from where its canvas shows every panel."""
    wait_until(lambda: len(app.server.get_clients()) == 1 and not set(app.server.get_clients()) & before)
    camera = next(iter(app.server.get_clients().values())).camera

    def fitted() -> bool:
        canvas = page.locator("canvas[data-engine]").bounding_box()
        size = (camera.image_width, camera.image_height)
        position, look_at = app.layout.camera(*size, camera.fov)
        return (
            np.allclose(size, (canvas["width"], canvas["height"]), atol=1.0)
            and np.allclose(camera.position, position, atol=1e-3)
            and np.allclose(camera.look_at, look_at, atol=1e-3)
        )

    wait_until(fitted)


def scene_meshes(app) -> tuple[trimesh.Trimesh, np.ndarray, dict]:
    """Both 3D bodies as the page draws them, in scene coordinates: every cylinder (a
    unit cylinder along local z scaled by its handle's (x radius, y radius, length),
    as viser draws it) and every facing mark (views.CONE). One mesh; each face's owner,
    (view, segment index) for a cylinder or (view, -1 - mark number) for a mark; and
    each owner's 4x4 placing of its unit shape."""
    from app.scene import CONE

    cylinder = trimesh.creation.cylinder(radius=1.0, height=1.0, sections=20)
    meshes, owners, placings = [], [], {}
    for view, (body, marks, at, frame) in enumerate(
        zip(app.scene.bodies, app.scene.marks, (app.layout.front, app.layout.side), app.scene.turns)
    ):
        panel = _transform(frame, at + (0.0,), (1.0, 1.0, 1.0))
        for shape, handles, first in ((cylinder, body, 0), (CONE, marks, -1)):
            for i, h in enumerate(handles):
                if h.visible:
                    owner = (view, i if first == 0 else -1 - i)
                    placings[owner] = panel @ _transform(h.wxyz, h.position, h.scale)
                    meshes.append(shape.copy().apply_transform(placings[owner]))
                    owners.append(np.tile(owner, (len(shape.faces), 1)))
    return trimesh.util.concatenate(meshes), np.concatenate(owners), placings


def _transform(wxyz, position, scale) -> np.ndarray:
    """The 4x4 of a scene node: scaled, turned by ``wxyz``, then moved to ``position``."""
    out = np.eye(4)
    out[:3, :3] = Rotation.from_quat(wxyz, scalar_first=True).as_matrix() * np.asarray(scale, float)
    out[:3, 3] = position
    return out


def unhidden_point(app, segment: str | None = None, mark: int | None = None) -> np.ndarray:
    """``visible_point``, which must be found."""
    point = visible_point(app, segment, mark)
    if point is None:
        raise AssertionError(f"{segment if mark is None else f'mark {mark}'} is hidden in both 3D views")
    return point


def visible_point(
    app, segment: str | None = None, mark: int | None = None, views: tuple[int, ...] = (0, 1)
) -> np.ndarray | None:
    """A scene point on a segment's cylinder (along its axis, middle first) or on facing
    mark number ``mark`` (along the cone's axis, halfway up first), in the camera or the
    side view (``views``: 0, 1), that the tab's camera sees first: the ray from the camera
    through it, and rays a canvas pixel around it (where a click lands, rounded to the
    pixel), must each hit that mesh before any other of the scene's; None where there is none."""
    from mocap.body import SEGMENT_INDEX

    camera = next(iter(app.server.get_clients().values())).camera
    eye = np.asarray(camera.position, float)
    mesh, owners, placings = scene_meshes(app)
    want = SEGMENT_INDEX[segment] if mark is None else -1 - mark
    pixel = 2 * np.tan(camera.fov / 2) / camera.image_height  # a canvas pixel per unit of depth
    along = (0.0, -0.2, 0.2, -0.35, 0.35) if mark is None else (0.5, 0.3)
    for view in views:
        if (view, want) not in placings:
            continue
        for t in along:
            point = (placings[view, want] @ [0.0, 0.0, t, 1.0])[:3]
            rays = _rays_around(eye, point, pixel)
            first = mesh.ray.intersects_first(np.tile(eye, (len(rays), 1)), rays)
            if np.all(first >= 0) and np.all(owners[first] == (view, want)):
                return point
    return None


def _rays_around(eye: np.ndarray, point: np.ndarray, spread: float) -> np.ndarray:
    """Unit rays from ``eye`` through ``point`` and through four points ``spread`` per unit
    of depth beside it, across the ray."""
    ray = (point - eye) / np.linalg.norm(point - eye)
    across = np.linalg.svd(ray[None])[2][1:]  # two unit vectors normal to it
    rays = ray + spread * np.concatenate([np.zeros((1, 3)), across, -across])
    return rays / np.linalg.norm(rays, axis=1, keepdims=True)
