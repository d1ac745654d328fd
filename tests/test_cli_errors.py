"""The command line on a new user's mistakes and broken files: each ends with exit code 2
and one line, `mocap: error: ...`, that names the file (or port) and the problem, never a
traceback."""

from __future__ import annotations

import socket

import pytest
from helpers import render_walk

from mocap.cli import main


def run(capsys, *argv) -> tuple[int, list[str]]:
    """Exit code and stderr lines of `mocap ARGV` run in this process."""
    code = main([str(a) for a in argv])
    return code, capsys.readouterr().err.splitlines()


def assert_one_line_error(err: list[str], *words: str) -> None:
    assert len(err) == 1, err
    assert err[0].startswith("mocap: error: "), err
    assert not any("Traceback" in line for line in err)
    for word in words:
        assert word in err[0], err


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    video = tmp_path_factory.mktemp("walk") / "walk.avi"
    render_walk(video, seconds=1.0)
    return video


# -- mocap serve ----------------------------------------------------------------------

def test_serve_on_a_taken_port_is_an_error_naming_it(walk, capsys):
    pytest.importorskip("viser")
    with socket.socket() as other:
        other.bind(("127.0.0.1", 0))
        other.listen()
        port = other.getsockname()[1]
        code, err = run(capsys, "serve", walk, "--port", port)
    assert code == 2
    assert_one_line_error(err, f"port {port}", "taken", "--port 0")


def test_serve_on_port_0_takes_any_free_one(walk):
    create = pytest.importorskip("app.main").create
    app = create(walk, port=0)
    try:
        assert app.server.get_port() > 0
    finally:
        app.server.stop()
