"""The keyframes the fit proposes (mocap.session.propose_keyframes, the app's default): a
sparse set, not every frame, holding the first and last frames and the review's stops, whose
interpolated motion stays within the tolerance of the every-frame one (smoothed) and is as
near the truth."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import render_walk
from scipy.ndimage import gaussian_filter1d

from mocap.lift.motion import build_motion
from mocap.pipeline import fit_video
from mocap.session import SilhouetteSession, propose_keyframes
from mocap.session.keys import KEY_TOLERANCE_M, NOISE_S
from mocap.synth.metrics import pa_mpjpe


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    """(session, truth): the three-quarter walk of helpers.render_walk, fitted once."""
    video = tmp_path_factory.mktemp("keys") / "walk.mp4"
    truth = render_walk(video, view="three-quarter", seconds=3.0)
    info, fits = fit_video(video)
    return SilhouetteSession(info, fits), truth


def test_the_proposal_is_sparse_and_keeps_the_motion(walk):
    session, truth = walk
    keys = propose_keyframes(session)
    person = np.flatnonzero(session.person)
    assert keys == sorted(set(keys)) and set(keys) <= set(person.tolist())
    assert {person[0], person[-1]} <= set(keys) and {d.frame for d in session.review_stops()} <= set(keys)
    assert len(keys) < 0.6 * len(person), f"{len(keys)} keyframes of {len(person)} frames"
    n, fps, root = session.n_frames, session.info.fps, session.root()
    every = build_motion({k: session.pose3d(k) for k in person}, n, fps, root=root).joints3d
    sparse = build_motion({k: session.pose3d(k) for k in keys}, n, fps, root=root).joints3d
    smooth = gaussian_filter1d(every, NOISE_S * fps, axis=0)
    assert np.linalg.norm(sparse - smooth, axis=-1).mean(axis=-1)[person].max() <= KEY_TOLERANCE_M + 1e-9
    # as near the truth as lifting every frame
    assert pa_mpjpe(sparse, truth.joints3d) <= pa_mpjpe(every, truth.joints3d) + 0.01
