"""A person model's sight over a clip, steadied. A body it keeps for less than MIN_RUN_S is a patch of the scene
it took for one (on a clip whose performer it does not see, bent over and head down, it finds such patches), and a
body it keeps is looked for backward from where it was first found: a model that tracks in video mode follows a
body it could not have found. (MediaPipe Pose finds a body by its face and then follows it: from behind it finds
nobody until the performer turns, then follows them turned away again.)"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterable, Iterator
from dataclasses import replace
from typing import TypeVar

import numpy as np

from mocap.person import PersonModel, PersonView

MIN_RUN_S = 0.5  # seconds a body must be kept for the model's sight of it to count
LOOK_BACK_S = 10.0  # seconds of frames without a body kept for a backward look
LOOK_BACK_BYTES = 300 << 20  # ... and at most this much memory of them (3.6 s of 1280x720 frames at 30/s)

Seen = tuple[np.ndarray, PersonView | None]
T = TypeVar("T")


def steadied(seen: Iterable[Seen], fps: float, fresh: Callable[[], PersonModel]) -> Iterator[Seen]:
    """Each (frame, view) of ``seen`` in order, later than it came: views in a run of seen frames shorter than
    MIN_RUN_S dropped, unless the run touches the clip's start or end (cut by it, its length tells nothing); and
    before each run kept, up to LOOK_BACK_S (and LOOK_BACK_BYTES) of frames seen as nobody given the views of a
    ``fresh`` model fed the run's first frame and then those frames backward, until it too sees nobody."""
    seen = iter(seen)
    first = next(seen, None)
    if first is None:
        return
    least = max(1, round(MIN_RUN_S * fps))
    most = max(1, min(round(LOOK_BACK_S * fps), LOOK_BACK_BYTES // max(first[0].nbytes, 1)))
    held: list[list] = []  # [frame, view] not yet given out: frames seen as nobody, then the current run
    run = 0  # frames of the run at held's end, not yet kept
    kept = False  # whether the run going on is kept (its frames go out as they come)
    start = True  # whether held begins at the clip's first frame
    for frame, view in itertools.chain([first], seen):
        if view is not None and kept:
            yield frame, view
            continue
        if view is None:
            if run and not (start and run == len(held)):  # a short run ended, not at the clip's start: a mistake
                for item in held[-run:]:
                    item[1] = None
            run, kept = 0, False
            held.append([frame, view])
        else:
            run += 1
            held.append([frame, view])
            if run >= least or start and run == len(held):
                looked_back(held, run, fresh)
                yield from map(tuple, held)
                held, run, kept, start = [], 0, True, False
                continue
        while len(held) - run > most:
            yield tuple(held.pop(0))
            start = False
    yield from map(tuple, held)


def looked_back(held: list[list], run: int, fresh: Callable[[], PersonModel]) -> None:
    """``held``'s frames before its last ``run`` (seen) given the views of a ``fresh`` model fed the run's first
    frame, then them from the last back, until it sees nobody."""
    first = len(held) - run
    if first == 0:
        return
    model = fresh()
    try:
        if model.observe(held[first][0]) is None:
            return
        for item in reversed(held[:first]):
            item[1] = model.observe(item[0])
            if item[1] is None:
                return
            item[1] = replace(item[1], looked_back=True)
    finally:
        model.close()


def short_runs_dropped(
    items: Iterable[T], fps: float, seen: Callable[[T], bool], dropped: Callable[[T], T]
) -> Iterator[T]:
    """Each of ``items`` in order, later than it came (by at most MIN_RUN_S): those ``seen`` in a run shorter than
    MIN_RUN_S given as ``dropped`` makes them. For a model's sight of a figure already cut out from the scene
    (person.isolated): a body it finds and loses from frame to frame is one it is not sure is a body."""
    least = max(1, round(MIN_RUN_S * fps))
    run: list[T] = []  # the seen items of a run not yet long enough
    kept = False  # whether the run going on is long enough (its items go out as they come)
    for item in items:
        if not seen(item):
            yield from map(dropped, run)
            run, kept = [], False
            yield item
        elif kept:
            yield item
        else:
            run.append(item)
            if len(run) >= least:
                yield from run
                run, kept = [], True
    yield from map(dropped, run)
