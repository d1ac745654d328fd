"""Learned eyes: a person model that sees the performer's mask, 2D joints and 3D joints on each frame, for the
silhouette method's fit and lift. ``PersonModel`` is the interface, ``MODELS`` the registry by name
(``open_person_model``); another model is a module with a ``Model(filtered, masked)`` class and a line in
``MODELS``."""

from __future__ import annotations

import contextlib
import multiprocessing
import os
from collections.abc import Iterator
from dataclasses import dataclass

from mocap.errors import MocapError
from mocap.person.opening import instance
from mocap.person.views import Landmarks as Landmarks
from mocap.person.views import PersonModel
from mocap.person.views import PersonView as PersonView
from mocap.person.views import watched as watched

DEFAULT_MODEL = "mediapipe"
NONE = "none"  # the paper's classical path: no person model
SURE = 0.5  # a landmark confidence from which it is taken as seen


@dataclass(frozen=True)
class Entry:
    """A registry entry: the module holding the ``Model`` class, the package it needs, its install command."""

    module: str
    package: str
    install: str


MODELS = {
    "mediapipe": Entry("mocap.person.mediapipe_pose", "mediapipe", ".venv/bin/pip install --no-deps mediapipe==0.10.14")
}
CHOICES = (*MODELS, NONE)


def check_name(name: str, where: str = "") -> str:
    """``name`` if it names a person model or "none", else a one-line MocapError (``where``: its source)."""
    if name not in CHOICES:
        raise MocapError(f"unknown person model {name!r}{where}: choose one of {', '.join(CHOICES)}")
    return name


def open_person_model(
    name: str = DEFAULT_MODEL, filtered: bool = True, apart: bool = False, with_mirror: bool = False
) -> PersonModel | None:
    """A fresh person model by name (None for "none"); a one-line MocapError if unknown or absent. ``filtered``:
    its landmarks smoothed by the model's own one-way filter, for a reader of one frame at a time (the tracker);
    off, each frame read alone, for one who smooths the clip's both ways (lift.cues). ``apart``: in a process of
    its own (person.worker) where there is a core to spare and this process may start one. ``with_mirror``: a
    second instance looking at the frames' mirror images, the two answering as one (person.mirrored)."""
    if check_name(name) == NONE:
        return None
    if not available(name):
        raise MocapError(install_hint(name))
    if with_mirror:
        from mocap.person.mirrored import WithMirror

        return WithMirror(_instance(name, filtered, apart, False), _instance(name, filtered, apart, True))
    return _instance(name, filtered, apart, False)


def _instance(name: str, filtered: bool, apart: bool, mirror: bool) -> PersonModel:
    """One instance of the named model, in this process or ``apart``; ``mirror``: looking at mirror images."""
    if apart and (os.cpu_count() or 1) > 1 and not multiprocessing.current_process().daemon:
        from mocap.person.worker import Apart

        return Apart(name, MODELS[name].module, filtered, mirror)
    return instance(MODELS[name].module, filtered, mirror)


@contextlib.contextmanager
def opened_model(
    name: str, filtered: bool = True, apart: bool = False, with_mirror: bool = False
) -> Iterator[PersonModel | None]:
    """``open_person_model(name, filtered, apart, with_mirror)`` for a ``with`` block, closed after it."""
    model = open_person_model(name, filtered, apart, with_mirror)
    try:
        yield model
    finally:
        if model is not None:
            model.close()


def available(name: str = DEFAULT_MODEL) -> bool:
    """Whether the named person model's package is installed (without importing it)."""
    import importlib.util

    return name == NONE or importlib.util.find_spec(MODELS[name].package) is not None


def install_hint(name: str) -> str:
    """One line: the person model's package is missing, and how to install it."""
    entry = MODELS[name]
    return f"the person model {name!r} needs {entry.package}, not installed here: {entry.install}"
