"""A person model in a process of its own (``Apart``), so that it looks at the next frames while this process
fits the last: the model's graph holds a core, the silhouette method's fit the other. The process is a fresh
interpreter running this module (never a fork of one that runs threads, nor a re-run of the caller's script);
frames go to it and views come back pickled through its standard input and output. It is started at once and
loads while the caller reads the background."""

from __future__ import annotations

import contextlib
import os
import pickle
import queue
import subprocess
import sys
import threading
from collections import deque
from collections.abc import Iterable, Iterator
from dataclasses import replace
from typing import Any

import numpy as np

from mocap.errors import MocapError
from mocap.person.opening import instance
from mocap.person.views import PersonView

AHEAD = 6  # frames sent before the first view is awaited: the model keeps busy while the fit looks again itself
PIPE_BYTES = 1 << 20  # Linux's default most for a pipe's buffer: a 640x480 frame, or its answer


class Apart:
    """The person model ``name``, the ``Model`` class of ``module`` opened with ``filtered`` (looking at mirror
    images: ``mirror``, mocap.person.opening.instance) in a child process (mocap.person.PersonModel; its views are
    mocap.person.PersonView)."""

    with_mirror = False

    def __init__(self, name: str, module: str, filtered: bool, mirror: bool = False):
        self.name, self.filtered = name, filtered
        self._child = subprocess.Popen(
            [sys.executable, "-m", __name__, name, module, str(int(filtered)), str(int(mirror))],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env={**os.environ, "PYTHONPATH": os.pathsep.join(p for p in sys.path if p)},  # the modules seen here
        )
        for pipe in (self._child.stdin, self._child.stdout):
            _widen(pipe)
        # frames are written by a thread of their own: a frame and an answer each fill a pipe, and the child
        # writing an answer while this process writes the next frame would wait on each other
        self._outbox: queue.Queue = queue.Queue()
        self._writer = threading.Thread(target=self._write, name=f"person-{name}", daemon=True)
        self._writer.start()

    def observe(self, frame: np.ndarray) -> Any:
        """Its view of the video's next BGR frame, None if it sees nobody."""
        self._send(frame)
        return self._receive()

    def watch(self, frames: Iterable[np.ndarray]) -> Iterator[tuple[np.ndarray, Any]]:
        """Each frame with its view, AHEAD frames sent before their views are awaited."""
        sent: deque = deque()
        for frame in frames:
            self._send(frame)
            sent.append(frame)
            if len(sent) > AHEAD:
                yield sent.popleft(), self._receive()
        while sent:
            yield sent.popleft(), self._receive()

    def close(self) -> None:
        """Its pipes closed (it reads the end of its input, or cannot write an answer left unread), and it is
        awaited by a thread of its own: the model's ending takes its process a sixth of a second that the caller
        need not wait."""
        self._outbox.put(None)
        with contextlib.suppress(OSError):
            self._child.stdout.close()
        self._writer.join(timeout=5.0)
        threading.Thread(target=_ended, args=(self._child,), name=f"person-{self.name}-end", daemon=True).start()

    def _send(self, frame: np.ndarray) -> None:
        self._outbox.put(np.ascontiguousarray(frame))

    def _write(self) -> None:
        """The writer thread: each frame put to the child's input, which is closed after the last (None)."""
        try:
            while (frame := self._outbox.get()) is not None:
                pickle.dump(frame, self._child.stdin, protocol=5)
                self._child.stdin.flush()
        except (OSError, ValueError):  # it ended: the reader hears why, or that it stopped
            pass
        finally:
            with contextlib.suppress(OSError):
                self._child.stdin.close()

    def _receive(self) -> Any:
        """The next answer; the child's failure as a one-line MocapError."""
        try:
            answer = pickle.load(self._child.stdout)
        except (EOFError, OSError, pickle.UnpicklingError):
            raise self._stopped() from None
        if isinstance(answer, MocapError):
            raise answer
        return unpacked(answer)

    def _stopped(self) -> MocapError:
        return MocapError(f"the person model {self.name!r} stopped (its process ended)")


def _ended(child: subprocess.Popen) -> None:
    """The child awaited, and killed if it has not ended within 5 seconds of its input's end."""
    try:
        child.wait(timeout=5.0)
    except subprocess.TimeoutExpired:
        child.kill()
        child.wait()


def _widen(pipe) -> None:
    """The pipe's buffer grown to PIPE_BYTES where the system allows (Linux): a frame then goes in one write,
    not in pieces, each of which the writer thread would wait for the interpreter to resume."""
    with contextlib.suppress(ImportError, AttributeError, OSError):
        import fcntl

        fcntl.fcntl(pipe.fileno(), fcntl.F_SETPIPE_SZ, PIPE_BYTES)


def packed(view: PersonView | None) -> PersonView | None:
    """A view with its mask's probabilities in bytes (levels of 1/255) for the pipe: a quarter of its float32."""
    if view is None or view.mask is None:
        return view
    return replace(view, mask=np.round(view.mask * 255).astype(np.uint8))


def unpacked(view: PersonView | None) -> PersonView | None:
    """A ``packed`` view with its mask in float32 probabilities again."""
    if view is None or view.mask is None:
        return view
    return replace(view, mask=view.mask.astype(np.float32) / 255)


def serve(name: str, module: str, filtered: bool, mirror: bool) -> None:
    """The child: open the model, then answer every frame read from standard input with its view on standard
    output, until the input ends; a failure is answered with a MocapError."""
    inbox, outbox = sys.stdin.buffer, os.fdopen(os.dup(1), "wb")
    os.dup2(2, 1)  # what else writes to standard output, Python or native, goes to standard error, not the answers
    sys.stdout = sys.stderr
    try:
        model = instance(module, filtered, mirror)
    except Exception as error:
        said = f"the person model {name!r} does not load: {error}"
        _answer(outbox, error if isinstance(error, MocapError) else MocapError(said))
        return
    try:
        while True:
            _answer(outbox, packed(model.observe(pickle.load(inbox))))
    except (EOFError, BrokenPipeError):
        pass
    except Exception as error:  # the parent says it in one line
        _answer(outbox, MocapError(f"the person model {name!r} failed: {error}"))
    finally:
        model.close()


def _answer(outbox, answer) -> None:
    pickle.dump(answer, outbox, protocol=5)
    outbox.flush()


if __name__ == "__main__":
    with contextlib.suppress(KeyboardInterrupt):  # Ctrl+C reaches the whole process group: the parent says it
        serve(sys.argv[1], sys.argv[2], *(bool(int(flag)) for flag in sys.argv[3:5]))
