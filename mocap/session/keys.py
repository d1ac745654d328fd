"""Keyframes proposed for a fitted clip (the app's default, in place of every frame): the review's
doubtful frames, lifted exactly since the user checks them, and the fewest frames more (where the
pose changes) for the export's interpolation (``mocap.lift.motion``) to keep every frame's joints
within KEY_TOLERANCE_M, on average, of lifting each frame (the fit's frame-to-frame jitter smoothed
out first: it is no change of pose). Sparse keys lose no accuracy against the truth:
benchmarks/RESULTS.md."""

from __future__ import annotations

import numpy as np
from scipy.ndimage import gaussian_filter1d

from mocap.lift.motion import build_motion

KEY_TOLERANCE_M = 0.03  # mean joint distance from the every-frame motion, smoothed
NOISE_S = 0.06  # the smoothing's sigma (seconds)


def propose_keyframes(session, tolerance: float = KEY_TOLERANCE_M) -> list[int]:
    """Sorted keyframes of a ``mocap.session.Session``: its first and last frames with a person, those
    beside a stretch without one, its review stops, then the frame farthest from the interpolation in
    each stretch between keyframes while that is more than ``tolerance`` (metres, mean over joints)."""
    poses = {int(k): session.pose3d(int(k)) for k in np.flatnonzero(session.person)}
    poses = {k: p for k, p in poses.items() if p is not None and np.isfinite(p).all()}  # (a lost frame's are not)
    person = np.zeros(session.n_frames, bool)
    person[list(poses)] = True
    frames = np.flatnonzero(person)
    if not len(frames):
        return []
    n, fps, root = session.n_frames, session.info.fps, session.root()
    every = gaussian_filter1d(build_motion(poses, n, fps, root=root).joints3d, NOISE_S * fps, axis=0)
    edges = np.flatnonzero(np.diff(person.astype(int)))  # the last frame before a change of person
    keys = {int(frames[0]), int(frames[-1])}
    keys |= {int(k) for k in np.concatenate([edges, edges + 1]) if person[k]}
    keys |= {d.frame for d in session.review_stops() if person[d.frame]}
    while True:
        motion = build_motion({k: poses[k] for k in keys}, n, fps, root=root).joints3d
        error = np.where(person, np.linalg.norm(motion - every, axis=-1).mean(axis=-1), 0.0)
        ordered = sorted(keys)
        worst = [a + 1 + int(np.argmax(error[a + 1 : b])) for a, b in zip(ordered, ordered[1:]) if b - a > 1]
        more = {k for k in worst if error[k] > tolerance}
        if not more:
            return ordered
        keys |= more
