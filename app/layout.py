"""Where the panels sit in the y-up scene's plane z = 0 and where a tab's camera looks from, for the
tab's canvas: the grid (2 x 2, 4 x 1 or 1 x 4) that shows the four panels largest. A window narrower
than viser's mobile breakpoint has the controls in a sheet along its bottom: the views fill the top,
two at a time (``PAIRS``) where four would each be narrower than ``MIN_SHARE`` of the window, and the
sheet starts below them (``sheet_top``), never over them."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

PANEL_HEIGHT = 1.9  # scene units (metres) of each panel: a 1.75 m body fits
GAP = 0.3  # between panels, and above each row: room for its captions
CAMERA_FOV = math.radians(30.0)
PANELS = ("video", "silhouette", "front", "side")
PAIRS = (("video", "front"), ("silhouette", "side"))  # what a phone shows two at a time
# (columns, rows), filled in PANELS order
GRIDS = ((2, 2), (4, 1), (1, 4))
PAIR_GRIDS = ((2, 1), (1, 2))
USUAL_CANVAS_PX = (892, 720)  # a new tab's camera before its canvas's size is known
MARGIN_PX = 6  # around the panels, inside the canvas
MOBILE_PX = 576  # viser's mobile breakpoint (36em): a window this narrow has the bottom sheet
MIN_SHEET = 0.38  # of a phone window's height, left to the control sheet at least
MIN_SHARE = 0.4  # of a phone window's width, the least each view shown gets
CAPTION_CHARS = 30  # the longest caption fits a panel's width in this many characters


@dataclass(frozen=True)
class Layout:
    """The panels' size in the scene, the grid, and each panel's centre (x, y); ``shown``: the
    panels on view (a pair's partners share its cells, hidden)."""

    width: float
    height: float
    columns: int
    rows: int
    centres: tuple[tuple[float, float], ...]  # in PANELS order
    shown: tuple[str, ...] = PANELS

    @classmethod
    def grid(cls, width_px: int, height_px: int, columns: int, rows: int, pair: int | None = None) -> "Layout":
        """Panels of the video's aspect on a ``columns`` x ``rows`` grid centred on the origin: all
        four, or with ``pair`` the two of PAIRS[pair] (the other two in their cells, hidden)."""
        w = PANEL_HEIGHT * width_px / height_px
        cells = [
            (
                (k % columns - (columns - 1) / 2) * (w + GAP),
                ((rows - 1) / 2 - k // columns) * (PANEL_HEIGHT + GAP) - GAP / 2,
            )
            for k in range(columns * rows)
        ]
        if pair is None:
            return cls(w, PANEL_HEIGHT, columns, rows, tuple(cells))
        centres = tuple(cells[next(p.index(n) for p in PAIRS if n in p)] for n in PANELS)
        return cls(w, PANEL_HEIGHT, columns, rows, centres, PAIRS[pair])

    @classmethod
    def for_video(cls, width_px: int, height_px: int, canvas: tuple[int, int] = USUAL_CANVAS_PX, pair: int = 0):
        """The layout that shows a video's panels largest on a canvas of ``canvas`` pixels (a phone's:
        ``pair`` is the two shown when four would be too small)."""
        grids = [cls.grid(width_px, height_px, *g) for g in GRIDS]
        best = max(grids, key=lambda g: g.panel_px(*canvas))
        if not is_phone(*canvas) or best.panel_px(*canvas) >= MIN_SHARE * canvas[0]:
            return best
        pairs = [cls.grid(width_px, height_px, *g, pair=pair) for g in PAIR_GRIDS]
        return max(pairs, key=lambda g: g.panel_px(*canvas))

    def __getattr__(self, name: str) -> tuple[float, float]:
        """``layout.video`` etc.: a panel's centre."""
        if name in PANELS:
            return self.centres[PANELS.index(name)]
        raise AttributeError(name)

    @property
    def extent(self) -> tuple[float, float]:
        """Width and height of the panels with their captions, centred on the origin."""
        return self.columns * self.width + (self.columns - 1) * GAP, self.rows * (PANEL_HEIGHT + GAP)

    @property
    def caption_height(self) -> float:
        """Caption text height (scene units): at most GAP / 3, with CAPTION_CHARS fitting a panel's width."""
        return min(GAP / 3, self.width / (0.6 * CAPTION_CHARS))

    def units_per_px(self, image_width: int, image_height: int) -> float:
        """Scene units per canvas pixel where the panels are as large as the canvas's free region allows."""
        free_w, free_h = views_region(image_width, image_height)
        extent_w, extent_h = self.extent
        return max(extent_w / free_w, extent_h / free_h)

    def panel_px(self, image_width: int, image_height: int) -> float:
        """A panel's width in canvas pixels on a canvas of that size."""
        return self.width / self.units_per_px(image_width, image_height)

    def sheet_top(self, image_width: int, image_height: int) -> int:
        """On a phone's canvas, the pixel row where the control sheet starts: just below the views."""
        return math.ceil(self.extent[1] / self.units_per_px(image_width, image_height)) + 2 * MARGIN_PX

    def camera(
        self, image_width: int, image_height: int, fov: float = CAMERA_FOV
    ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
        """(position, look_at) of a camera on +z that shows every panel and caption on a canvas of
        ``image_width`` x ``image_height`` pixels: centred, or on a phone along its top."""
        per_px = self.units_per_px(image_width, image_height)
        distance = per_px * image_height / (2 * math.tan(fov / 2))
        y = 0.0
        if is_phone(image_width, image_height):  # the views' centre sits above the canvas's
            y = (self.sheet_top(image_width, image_height) - image_height) / 2 * per_px
        return (0.0, y, distance), (0.0, y, 0.0)

    def video_pixel(self, origin, direction, size: tuple[int, int]) -> tuple[float, float] | None:
        """Where a click ray meets the video panel, in pixels of an image of ``size`` (w, h); None if not."""
        o, d = np.asarray(origin, float), np.asarray(direction, float)
        if abs(d[2]) < 1e-9 or "video" not in self.shown:
            return None
        p = o - o[2] / d[2] * d
        u = (p[0] - self.video[0]) / self.width + 0.5
        v = 0.5 - (p[1] - self.video[1]) / self.height
        if not (0 <= u <= 1 and 0 <= v <= 1):
            return None
        return u * size[0], v * size[1]


def is_phone(image_width: int, image_height: int) -> bool:
    """Whether a canvas is a window below viser's mobile breakpoint (its controls: a bottom sheet)."""
    return 0 < image_width <= MOBILE_PX


def views_region(image_width: int, image_height: int) -> tuple[float, float]:
    """The canvas pixels the panels may fill: all but a margin, on a phone above the sheet's least share."""
    height = image_height * (1 - MIN_SHEET) if is_phone(image_width, image_height) else image_height
    return max(image_width - 2 * MARGIN_PX, 1), max(height - 2 * MARGIN_PX, 1)
