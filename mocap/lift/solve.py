"""The clip-level 3D solve: every frame of a clip in one sparse least-squares problem
(``mocap.lift.problem``, solved by ``mocap.lift.levmar``), the per-frame lift (Eq. 4-5) its start,
then each segment's sign path over the clip (``mocap.lift.signpath``) and the problem again with
those signs (``lift_clip``). An edit re-solves windows around the frames it changed, the rest of
the clip held, from the nearest earlier solution (``resolve_edit``)."""

from __future__ import annotations

import time
from dataclasses import dataclass, replace

import numpy as np
from scipy.ndimage import binary_dilation

from mocap.body import SEGMENT_JOINTS
from mocap.lift.clipdata import (
    PER_FRAME,
    SEGMENT_CLASS,
    ClipArrays,
    Weights,
    clip_bone_lengths,
    start_pose,
    to_contract,
    with_signs,
)
from mocap.lift.levmar import MAX_ITERATIONS, levenberg_marquardt
from mocap.lift.problem import Problem
from mocap.lift.signpath import sign_paths
from mocap.lift.taylor import runs, signs_of

# seconds each side of an edited frame that its re-solve frees (the acceleration ties a frame to
# its neighbours, the sign path to the stretch around it)
WINDOW_S = 0.2
# frames either side of a window held in its problem: the acceleration reaches two frames
CONTEXT = 2
FOCUS_ITERATIONS = 20  # Levenberg-Marquardt iterations an edit's own window is given at once (a page's answer
# within the app's 100 ms); the window is solved on to convergence with the windows left for later
LATER_FRAMES = 30  # frames of the windows left for later solved at a time: about 60 ms, which the app
# holds its lock for (a frame change waits no longer)


@dataclass(frozen=True, eq=False)
class Solution:
    """A solved clip: ``joints3d`` (F, 16, 3) metres about the pelvis, contract axes (NaN: nobody);
    ``model`` (F, 16, 3) model units about each frame's observed 2D pelvis; ``lengths``
    (len(clipdata.CLASSES),) model units; ``seconds`` the solve's wall time."""

    joints3d: np.ndarray
    model: np.ndarray
    lengths: np.ndarray
    seconds: float

    @property
    def signs(self) -> np.ndarray:
        """(F, 10) +1 toward / -1 away: each segment's sign in the solved poses."""
        return signs_of(self.model)


def solve_clip(
    clip: ClipArrays,
    weights: Weights = Weights(),
    start: np.ndarray | None = None,
    bones: np.ndarray | None = None,
) -> Solution:
    """Every person stretch of ``clip`` solved at once from ``start`` ((F, 16, 3) model units;
    None: ``start_pose``) and first lengths ``bones`` (None: ``clip_bone_lengths``). Under scaled
    orthography the lengths are held: a bone in the image plane shows its length, which the 2D
    measures. Through a known camera's pinhole, where a limb near the camera reads long, they are
    solved too where the person model gives depths on most frames (without an independent depth,
    2D noise only ever lengthens a free bone); shared by the stretches, they are solved on the
    longest and held on the others."""
    t0 = time.perf_counter()
    bones = clip_bone_lengths(clip) if bones is None else np.asarray(bones, float)
    start = start_pose(clip, bones) if start is None else start
    seen = np.zeros(0, bool) if clip.depths is None else np.isfinite(clip.depths[clip.person]).all(axis=1)
    free_lengths = clip.camera is not None and bool(seen.size) and seen.mean() > 0.5
    model = np.full_like(start, np.nan)
    for k, r in enumerate(sorted(runs(clip.person), key=lambda r: r.start - r.stop)):
        free = np.ones(r.stop - r.start, bool)
        problem = Problem(clip, r, start[r], free, bones, free_lengths and k == 0, weights)
        x = levenberg_marquardt(problem, problem.x0(start[r]))
        model[r] = problem.positions(x)
        bones = problem.lengths(x).copy()
    return Solution(to_contract(model), model, bones, time.perf_counter() - t0)


def solve_signs(clip: ClipArrays, solution: Solution, weights: Weights = Weights()) -> Solution:
    """``solve_clip`` again from ``solution`` with each segment's sign path (``sign_paths``) as the
    clip's signs, the start's depths turned to them (the user's held signs kept)."""
    t0 = time.perf_counter()
    paths = sign_paths(clip, solution.model, solution.lengths, weights)
    start = with_signs(solution.model, paths)
    out = solve_clip(replace(clip, signs=paths), weights, start=start, bones=solution.lengths)
    return replace(out, seconds=solution.seconds + time.perf_counter() - t0)


def lift_clip(clip: ClipArrays, weights: Weights = Weights()) -> Solution:
    """The clip's 3D: ``solve_clip``, then ``solve_signs``."""
    return solve_signs(clip, solve_clip(clip, weights), weights)


def solve_window(
    clip: ClipArrays, solution: Solution, window: slice, weights: Weights = Weights(), max_iter: int = MAX_ITERATIONS
) -> Solution:
    """``solution`` with frames ``window`` solved again for ``clip`` (edited there), every other frame
    and the lengths held: the window's sign paths first (``sign_paths``, the held frames around it
    keeping theirs), then its problem with CONTEXT held frames either side (``max_iter`` iterations at most)."""
    t0 = time.perf_counter()
    model = solution.model.copy()
    for r in runs(clip.person):
        a, b = max(r.start, window.start), min(r.stop, window.stop)
        if a >= b:
            continue
        around = slice(max(a - CONTEXT, r.start), min(b + CONTEXT, r.stop))
        free = np.zeros(around.stop - around.start, bool)
        free[a - around.start : b - around.start] = True
        part, base = clip.frames(around), model[around]
        walls = np.where(free[:, None], 0, signs_of(base))
        paths = sign_paths(part, base, solution.lengths, weights, walls)
        base = with_signs(base, paths)
        problem = Problem(replace(part, signs=paths), slice(0, len(free)), base, free, solution.lengths, False, weights)
        model[around] = problem.positions(levenberg_marquardt(problem, problem.x0(base), max_iter))
    return Solution(to_contract(model), model, solution.lengths, time.perf_counter() - t0)


def frames_to_solve(
    clip: ClipArrays, before: ClipArrays, solution: Solution, weights: Weights = Weights()
) -> np.ndarray | None:
    """(F,) bool: the frames an edit from ``before`` to ``clip`` asks to solve again: those with any
    input changed but the signs, and those with a sign (held or guessed) changed that ``solution``'s 3D
    does not already keep by ``sign_margin`` (a one-sided constraint it keeps leaves the optimum
    where it is); None when the person frames changed."""
    changed = clip.changed_frames(before, tuple(n for n in PER_FRAME if n not in ("signs", "held")))
    if changed is None:
        return None
    now = clip.held_or_guessed()
    said = (now != before.held_or_guessed()) | ((clip.held_signs() != 0) != (before.held_signs() != 0))
    z = solution.model[..., 2]
    depth = z[:, SEGMENT_JOINTS[:, 1]] - z[:, SEGMENT_JOINTS[:, 0]]
    kept = now * depth >= weights.sign_margin * solution.lengths[SEGMENT_CLASS]
    return (changed | (said & ~kept).any(axis=1)) & clip.person


def resolve_edit(
    clip: ClipArrays, solved: list[tuple[ClipArrays, Solution]], weights: Weights = Weights(), focus: int | None = None
) -> tuple[Solution, list[slice]]:
    """(solution, the windows left to solve) of ``clip`` after edits, from the earlier (clip, solution)
    of ``solved`` that asks the fewest frames to solve again (``frames_to_solve``; the first of equals):
    windows of WINDOW_S either side of those frames (``solve_window``), none when one already holds (an
    undo, a sign set back), the whole clip (``lift_clip``) when none has the same person frames. With
    ``focus`` (the frame the user looks at) only WINDOW_S either side of it is solved now, in FOCUS_ITERATIONS,
    the rest left (``solve_windows`` finishes them, that window first): a sign held from a frame on may ask for
    the rest of the clip."""
    best = None
    for before, solution in solved:
        frames = frames_to_solve(clip, before, solution, weights)
        if frames is not None and (best is None or frames.sum() < best[1].sum()):
            best = (solution, frames)
    if best is None:
        return lift_clip(clip, weights), []
    solution, frames = best
    reach = max(1, int(round(WINDOW_S * clip.fps)))
    windows = runs(binary_dilation(frames, iterations=reach) & clip.person) if frames.any() else []
    if focus is None:
        return solve_windows(clip, solution, windows, weights), []
    now, later = [], []
    for w in windows:
        if not w.start <= focus < w.stop:
            later.append(w)
            continue
        near = slice(max(w.start, focus - reach), min(w.stop, focus + reach + 1))
        now.append(near)
        later += [slice(w.start, near.start), slice(near.stop, w.stop)]
    pieces = [slice(a, min(a + LATER_FRAMES, w.stop)) for w in later for a in range(w.start, w.stop, LATER_FRAMES)]
    return solve_windows(clip, solution, now, weights, FOCUS_ITERATIONS), now + pieces


def solve_windows(
    clip: ClipArrays,
    solution: Solution,
    windows: list[slice],
    weights: Weights = Weights(),
    max_iter: int = MAX_ITERATIONS,
) -> Solution:
    """``solution`` with each of ``windows`` solved again in turn (``solve_window``)."""
    for window in windows:
        solution = solve_window(clip, solution, window, weights, max_iter)
    return solution
