"""Each tab's camera on the panels, and the one layout of the shared scene (``app.layout``): the layout
follows the canvas of the tab opened or resized last, and every tab's camera is fitted to it. The page's
style moves viser's notifications over the controls, off the views; a phone's control sheet spans the
window's width below the views (``Layout.sheet_top``)."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

import numpy as np

from app.layout import CAMERA_FOV, MOBILE_PX, USUAL_CANVAS_PX, Layout, is_phone

SETTLE_S = 3.0  # a new tab's camera is fitted on every update this long
# viser's notifications (top left of the canvas) go to the window's top right, over the docked
# controls; on a phone, to its bottom, over the sheet. The sheet is the page's one fixed Paper.
SHEET = '.mantine-Paper-root[style*="position: fixed"]'
PAGE_STYLE = (
    "<style>.mantine-Notifications-root{position:fixed!important;left:auto!important;right:1em!important;"
    "transform:none!important}"
    f"@media (max-width:{MOBILE_PX}px){{.mantine-Notifications-root{{top:auto!important;bottom:1em!important}}"
    f"{SHEET}{{left:0!important;width:100%!important;max-height:none!important}}"
    f'{SHEET} [style*="width: 20em"]{{width:100%!important}}}}</style>'
)


def sheet_style(top: int) -> str:
    """A phone tab's style: its control sheet from pixel row ``top`` to the bottom."""
    return f"<style>@media (max-width:{MOBILE_PX}px){{{SHEET}{{top:{top}px!important}}}}</style>"


class Framing:
    """The layout for the tabs' canvases; ``on_layout(layout)`` moves the panels when it changes;
    ``pair`` is the two views a phone shows when it cannot show four."""

    def __init__(self, server, video_size: tuple[int, int], on_layout: Callable[[Layout], None]):
        self.server, self.video_size, self._on_layout = server, video_size, on_layout
        self._lock = threading.RLock()
        self._sizes: dict[int, tuple[int, int]] = {}  # client id -> its canvas, last seen
        self._sheets: dict[int, object] = {}  # client id -> its sheet's style
        self._canvas = USUAL_CANVAS_PX
        self.pair = 0
        self.layout = Layout.for_video(*video_size, USUAL_CANVAS_PX)
        server.gui.add_html(PAGE_STYLE, order=1e9)
        camera = server.initial_camera
        camera.fov = CAMERA_FOV
        camera.position, camera.look_at = self.layout.camera(*USUAL_CANVAS_PX)
        camera.up = (0.0, 1.0, 0.0)
        server.on_client_connect(self._connect)
        server.on_client_disconnect(self._disconnect)

    def show_pair(self, pair: int) -> None:
        """Show the views of PAIRS[pair] where two are shown at a time."""
        with self._lock:
            self.pair = pair
            self._choose(self._canvas)

    def _connect(self, client) -> None:
        settling_until = time.monotonic() + SETTLE_S

        def fit(_camera) -> None:
            camera = client.camera
            size = (camera.image_width, camera.image_height)
            if min(size) <= 0:
                return
            with self._lock:
                resized = self._sizes.get(client.client_id) != size
                self._sizes[client.client_id] = size
                if resized:
                    self._choose(size)
                    self._style(client, size)
                if resized or time.monotonic() < settling_until:
                    self._fit(client)

        client.camera.on_update(fit)

    def _disconnect(self, client) -> None:
        with self._lock:
            self._sizes.pop(client.client_id, None)
            self._sheets.pop(client.client_id, None)

    def _choose(self, canvas: tuple[int, int]) -> None:
        """Lay the panels out for ``canvas``; every tab's camera follows a change."""
        self._canvas = canvas
        layout = Layout.for_video(*self.video_size, canvas, self.pair)
        if layout == self.layout:
            return
        self.layout = layout
        self._on_layout(layout)
        for client in self.server.get_clients().values():
            self._fit(client)
            if client.client_id in self._sizes:
                self._style(client, self._sizes[client.client_id])

    def _style(self, client, size: tuple[int, int]) -> None:
        """A phone tab's sheet starts below its views (or nowhere special elsewhere)."""
        content = sheet_style(self.layout.sheet_top(*size)) if is_phone(*size) else ""
        handle = self._sheets.get(client.client_id)
        if handle is None:
            self._sheets[client.client_id] = client.gui.add_html(content, order=1e9)
        elif handle.content != content:
            handle.content = content

    def _fit(self, client) -> None:
        camera = client.camera
        size = (camera.image_width, camera.image_height)
        if min(size) <= 0:
            return
        position, look_at = self.layout.camera(*size, fov=camera.fov)
        if not (np.allclose(camera.position, position) and np.allclose(camera.look_at, look_at)):
            with client.atomic():  # position moves look_at along: set it after
                camera.position, camera.look_at = position, look_at
