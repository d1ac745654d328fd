"""`mocap serve`: the app on a viser server at a checked address, serving until interrupted."""

from __future__ import annotations

import errno
import socket
import sys
import time
from collections.abc import Callable
from pathlib import Path

import viser

from app.main import App
from app.state import AppState
from mocap.errors import MocapError
from mocap.pipeline import Focal

SAMPLE = Path(__file__).resolve().parents[1] / "sample_videos" / "walk.mp4"


def create(
    video: str | Path | None = None,
    *,
    host: str = "127.0.0.1",
    port: int = 8080,
    annotations: str | Path | None = None,
    person: str | None = None,
    focal: Focal | None = None,
) -> App:
    """The app on ``video`` (default: the sample) on a new viser server, edits saved to ``annotations``
    (default: beside the video), ``person`` and ``focal`` as AppState takes them; start with
    ``app.state.start()``."""
    state = AppState(video or SAMPLE, annotations, person, focal)
    check_port(host, port)
    server = viser.ViserServer(host=host, port=port, verbose=False)
    if port and server.get_port() != port:  # taken between the check and viser's bind
        server.stop()
        raise MocapError(_taken(host, port))
    return App(server, state)


def _taken(host: str, port: int) -> str:
    return (
        f"port {port} on {host} is taken (another program listens there): stop it, "
        "or choose another with --port (--port 0: any free one)"
    )


def check_port(host: str, port: int) -> None:
    """Refuse an address the server cannot have: viser would move to another port (the user's address
    showing another program's page) or, for a host not of this machine, try a thousand ports."""
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, proto) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the server binds
            probe.bind(address)
    except OSError as exc:
        if exc.errno == errno.EADDRINUSE:
            raise MocapError(_taken(host, port)) from None
        raise MocapError(f"cannot listen on {host} port {port}: {exc.strerror or exc}") from None


def main(
    video: str | None = None,
    port: int = 8080,
    host: str = "127.0.0.1",
    progress: Callable[[int, int], None] | None = None,
    annotations: str | Path | None = None,
    person: str | None = None,
    focal: Focal | None = None,
) -> None:
    """Serve until interrupted: print the page's address, then preprocess with
    ``progress(done, total)`` reporting each step."""
    app = create(video, host=host, port=port, annotations=annotations, person=person, focal=focal)
    print(f"mocap: serving {app.state.info.path} at http://{host}:{app.server.get_port()}/", flush=True)
    app.state.start(progress)
    try:
        app.state.ready.wait()
        if app.state.progress.error is not None:
            print(f"mocap: {app.state.progress.error}", file=sys.stderr, flush=True)
        else:
            print(f"mocap: ready, {app.state.n_frames} frames fitted; edits are saved to {app.state.path}", flush=True)
        while True:
            time.sleep(3600)
    except KeyboardInterrupt:
        pass
    finally:
        app.server.stop()
