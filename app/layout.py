"""Where the four panels sit in the y-up scene's plane z = 0 (a 2 x 2, 4 x 1 or 1 x 4 grid, whichever
shows them largest) and where each tab's camera looks from: +z, as close as its canvas allows, with
a top band left free for notifications."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

PANEL_HEIGHT = 1.9  # scene units (metres) of each panel: a 1.75 m body fits
GAP = 0.3  # between panels, and above each row: room for its captions
CAMERA_FOV = math.radians(30.0)
# (columns, rows), in the order the panels fill them: video, silhouette, front, side
ARRANGEMENTS = ((2, 2), (4, 1), (1, 4))
# width / height of a usual window's 3D canvas less the notification band
USUAL_CANVAS = 1.45
USUAL_CANVAS_PX = (892, 720)  # a new tab's camera before its canvas's size is known
NOTICE_PX = 110  # the canvas's top band where a notification (3 lines) appears
MARGIN_PX = 6  # around the panels, inside the canvas
SETTLE_S = 3.0  # a new tab's camera is fitted on every update this long
CAPTION_CHARS = 30  # the longest caption fits a panel's width in this many characters


@dataclass(frozen=True)
class Layout:
    """The panels' centres (x, y) in the scene, their size, and the grid they are on."""

    width: float
    height: float
    columns: int
    rows: int
    video: tuple[float, float]
    silhouette: tuple[float, float]
    front: tuple[float, float]
    side: tuple[float, float]

    @classmethod
    def for_video(cls, width_px: int, height_px: int, canvas: float = USUAL_CANVAS) -> "Layout":
        """The grid that shows panels of the video's aspect largest on a canvas of aspect ``canvas``."""
        w = PANEL_HEIGHT * width_px / height_px

        def panel_size(grid: tuple[int, int]) -> float:
            extent_w, extent_h = _extent(w, *grid)
            return min(canvas / extent_w, 1.0 / extent_h)

        columns, rows = max(ARRANGEMENTS, key=panel_size)
        centres = [
            (
                (k % columns - (columns - 1) / 2) * (w + GAP),
                ((rows - 1) / 2 - k // columns) * (PANEL_HEIGHT + GAP) - GAP / 2,
            )
            for k in range(4)
        ]
        return cls(w, PANEL_HEIGHT, columns, rows, *centres)

    @property
    def extent(self) -> tuple[float, float]:
        """Width and height of the panels with their captions, centred on the origin."""
        return _extent(self.width, self.columns, self.rows)

    @property
    def caption_height(self) -> float:
        """Caption text height (scene units): at most GAP / 3, with CAPTION_CHARS fitting a panel's width."""
        return min(GAP / 3, self.width / (0.6 * CAPTION_CHARS))

    def camera(
        self, image_width: int, image_height: int, fov: float = CAMERA_FOV
    ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(position, look_at) of a camera on +z that shows every panel and caption on a
        canvas of ``image_width`` x ``image_height`` pixels, below its notification band."""
        free_w = max(image_width - 2 * MARGIN_PX, 1)
        free_h = max(image_height - NOTICE_PX - 2 * MARGIN_PX, 1)
        extent_w, extent_h = self.extent
        per_px = max(extent_w / free_w, extent_h / free_h)
        distance = per_px * image_height / (2 * math.tan(fov / 2))
        y = per_px * NOTICE_PX / 2  # the panels' centre sits below the band
        return (0.0, y, distance), (0.0, y, 0.0)

    def video_pixel(self, origin, direction, size: tuple[int, int]) -> tuple[float, float] | None:
        """Where a click ray meets the video panel, in pixels of an image of ``size`` (w, h); None if not."""
        o, d = np.asarray(origin, float), np.asarray(direction, float)
        if abs(d[2]) < 1e-9:
            return None
        p = o - o[2] / d[2] * d
        u = (p[0] - self.video[0]) / self.width + 0.5
        v = 0.5 - (p[1] - self.video[1]) / self.height
        if not (0 <= u <= 1 and 0 <= v <= 1):
            return None
        return u * size[0], v * size[1]


def _extent(width: float, columns: int, rows: int) -> tuple[float, float]:
    """(width, height) of a grid of ``width`` x PANEL_HEIGHT panels, a GAP caption band above each row."""
    return columns * width + (columns - 1) * GAP, rows * (PANEL_HEIGHT + GAP)


def place_cameras(server, layout: Layout) -> None:
    """Look at the panels from +z: a new tab from where a usual canvas shows them all,
    then from where its own canvas does, again whenever that canvas is resized."""
    camera = server.initial_camera
    camera.fov = CAMERA_FOV
    camera.position, camera.look_at = layout.camera(*USUAL_CANVAS_PX)
    camera.up = (0.0, 1.0, 0.0)
    server.on_client_connect(lambda client: _fit_camera_of(client, layout))


def _fit_camera_of(client, layout: Layout) -> None:
    """Fit the tab's camera to its canvas on resize, and on every update in its first SETTLE_S (a new
    page's start-up may put back an earlier pose)."""
    fitted: list[tuple[int, int]] = []
    settling_until = time.monotonic() + SETTLE_S

    def fit(_camera) -> None:
        camera = client.camera
        size = (camera.image_width, camera.image_height)
        if min(size) <= 0 or (fitted and fitted[-1] == size and time.monotonic() > settling_until):
            return
        fitted.append(size)
        position, look_at = layout.camera(*size, fov=camera.fov)
        if not (np.allclose(camera.position, position) and np.allclose(camera.look_at, look_at)):
            with client.atomic():  # position moves look_at along: set it after
                camera.position, camera.look_at = position, look_at

    client.camera.on_update(fit)
