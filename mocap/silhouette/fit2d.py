"""Fitting the 2D cylinder model to a normalised silhouette (``pose.scale`` pixels per model unit): the paper's
Algorithms 1-6 (section 3.3), left and right being image sides. Torso and head, legs, then arms, each by the
narrowing search; beyond the paper, searches centred on the previous frame (temporal coherence)."""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from mocap.body import BODY_HEIGHT, FOOT_LENGTH, SEGMENT_INDEX
from mocap.silhouette.arms import facing_of_knees, fit_arms
from mocap.silhouette.legs import LEGS, leg_hypotheses
from mocap.silhouette.model2d import Pose2D, forward_kinematics_2d
from mocap.silhouette.raster import Canvas, draw_model, pose_quads, similarity
from mocap.silhouette.torso import TORSO_HEAD, fit_torso_head, initial_pose

FIT_BODY_PX = 96.0  # height of the normalised standing silhouette the fit works on
FIT_SCALE = FIT_BODY_PX / (BODY_HEIGHT + FOOT_LENGTH)  # the silhouette is the body and its feet


@dataclass(frozen=True)
class Fit2D:
    """A fitted 2D pose, its joints (16, 2; fitted-silhouette pixels), its S, and the other leg hypotheses."""

    pose: Pose2D
    joints: np.ndarray
    score: float
    alternatives: tuple["Fit2D", ...] = ()


def fit_frame(
    silhouette: np.ndarray,
    scale: float,
    prev: Pose2D | None = None,
    spread: float | None = None,
    grey: np.ndarray | None = None,
    targets=None,
) -> Fit2D:
    """Fit the 10-cylinder model to one normalised silhouette (section 3.3), other leg hypotheses as
    ``alternatives``; ``spread``: the torso's if given; ``grey``: the frame's (edges guide the arms);
    ``targets``: landmarks (eyes.Targets) every search draws joints toward."""
    canvas = Canvas(silhouette, grey, targets)
    pose = initial_pose(canvas.sil, scale)
    if prev is not None:
        pose = replace(prev, pelvis=pose.pelvis, scale=scale)
    pose = fit_torso_head(canvas, pose, prev, spread)
    canvas.commit(pose_quads(pose, TORSO_HEAD))
    legs = leg_hypotheses(canvas, pose, prev)
    pose = legs[0]
    canvas.commit(pose_quads(pose, LEGS))
    pose = fit_arms(canvas, pose, prev, facing_of_knees(pose))
    others = tuple(with_legs(canvas.sil, pose, other) for other in legs[1:])
    return Fit2D(pose, forward_kinematics_2d(pose), canvas.score_model(), others)


def with_legs(silhouette: np.ndarray, pose: Pose2D, legs: Pose2D) -> Fit2D:
    """The fit of ``pose`` with the legs of ``legs``, scored on the whole silhouette (Eq. 3)."""
    k = [SEGMENT_INDEX[s] for s in LEGS]
    angle, ratio = pose.angle.copy(), pose.ratio.copy()
    angle[k], ratio[k] = legs.angle[k], legs.ratio[k]
    pose = replace(pose, angle=angle, ratio=ratio)
    return Fit2D(pose, forward_kinematics_2d(pose), similarity(silhouette, draw_model(pose, silhouette.shape)))
