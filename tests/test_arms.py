"""The arms of the 2D fit on real motion capture rendered by an independent renderer
(capsule bodies with hands, ../shared/data/clips; skipped when absent): the fit's
own error, on the clips' true silhouettes."""

from __future__ import annotations

import json

import cv2
import numpy as np
import pytest
from helpers import SHARED_DATA

from mocap.body import JOINT_INDEX
from mocap.io.video import iter_frames, open_video, processing_scale
from mocap.silhouette.passes import Silhouette, iter_fits
from mocap.synth.metrics import side_matched_errors

CLIPS = SHARED_DATA / "clips"
FRAMES = 30


def true_mask_fits(name: str, frames: int = FRAMES) -> tuple[np.ndarray, np.ndarray, float]:
    """The fit's image-side joints (frames, 16, 2) on a clip's first ``frames`` true
    masks, with the frames' grey levels; the true joints; the body's height (px)."""
    clip = CLIPS / name
    if not (clip / "truth.json").is_file():
        pytest.skip(f"real data absent: {clip} (../shared/data beside the checkout)")
    info = open_video(clip / "video.mp4")
    scale = processing_scale(info)
    silhouettes = []
    for index, frame in iter_frames(info, scale=scale):
        if index == frames:
            break
        mask = cv2.imread(str(clip / "masks" / f"{index:06d}.png"), cv2.IMREAD_GRAYSCALE)
        silhouettes.append(
            Silhouette.from_mask(cv2.resize(mask, frame.shape[1::-1], interpolation=cv2.INTER_NEAREST), frame)
        )
    fits = list(iter_fits(silhouettes, scale, info.fps))
    truth = json.loads((clip / "truth.json").read_text())
    true_joints = np.array([f["joints2d"] for f in truth["frames"][:frames]])
    return np.array([f.joints2d for f in fits]), true_joints, truth["body_height_px"]


def true_mask_fit_errors(name: str) -> np.ndarray:
    """(FRAMES, 16) 2D errors (% of body height, image sides matched) of the fit of a
    clip's first FRAMES true masks."""
    fitted, true_joints, body_px = true_mask_fits(name)
    return side_matched_errors(fitted, true_joints) / body_px * 100


@pytest.mark.parametrize("name", ["walk_toward", "kick_34"])
def test_wrists_sit_at_the_wrist_not_at_the_end_of_the_hand(name):
    """Arms swinging beside the body, seen from the front (a walk toward the camera)
    and at 60 degrees (a run-up to a kick): the model's hand beyond the wrist keeps the
    wrists within 3% of body height on average (they were 5.3-5.7% off, at the
    silhouette's end), and the elbows within 4%."""
    errors = true_mask_fit_errors(name)
    wrists = errors[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]]]
    elbows = errors[:, [JOINT_INDEX["elbow_l"], JOINT_INDEX["elbow_r"]]]
    assert wrists.mean() < 3.0, wrists.mean()
    assert elbows.mean() < 4.0, elbows.mean()


def test_a_hand_raised_over_the_head_across_the_torsos_axis_is_its_own_sides_arm():
    """scoop_34 (seen at 45 degrees, facing the camera: the right arm is the image-left
    one) raises its right hand over the head, where it crosses the fitted torso's
    axis: the image-left arm reaches it (within 5% of body height) on at least half of
    the 22 frames the hand is above the head (59%; 9% when the axis's line split the
    silhouette above the head too, and the image-right arm took the hand)."""
    fitted, true_joints, body_px = true_mask_fits("scoop_34", 24)
    hand, head = true_joints[:, JOINT_INDEX["wrist_r"]], true_joints[:, JOINT_INDEX["head_top"]]
    raised = hand[:, 1] < head[:, 1]
    reached = np.linalg.norm(fitted[:, JOINT_INDEX["wrist_l"]] - hand, axis=-1) / body_px < 0.05
    assert raised.sum() >= 20 and reached[raised].mean() >= 0.5, reached[raised].mean()


def test_arms_held_up_in_a_back_view_keep_their_raised_forearms():
    """laugh_back (seen from behind) holds both hands up over its shoulders on frames
    12-21, where the raised arms narrow the torso's seen width into a profile's and the
    knees say which way a profile faces: the elbow-backward rule, which holds for a
    real profile, dropped the raised forearm and hung the arm down the back (wrists
    36-64% of body height off on five of those frames). An arm held up is not held to
    it: every wrist within 10% and elbow within 12% there (measured: 6.8% and 9.8% at most)."""
    fitted, true_joints, body_px = true_mask_fits("laugh_back", 22)
    errors = side_matched_errors(fitted, true_joints)[12:22] / body_px * 100
    wrists = errors[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]]]
    elbows = errors[:, [JOINT_INDEX["elbow_l"], JOINT_INDEX["elbow_r"]]]
    assert wrists.max() < 6.0 and elbows.max() < 8.0, (wrists.max(), elbows.max())


def test_both_arms_held_in_front_in_profile_are_both_fitted():
    """salsa_spin_left starts in profile facing image left with both arms held in
    front of the chest, one forearm across it with the hand showing beyond the chest's
    outline: both arms lie on one side of the torso's axis, and the arm of the other
    side, kept to its side, hung down the back (wrists 23-47% of body height off on
    frames 20-34). Near profile the arm on the side the performer faces is fitted
    first and the other may cross the axis: on at least 8 of those 15 frames both
    wrists lie within 5% (measured: 10; before: none)."""
    fitted, true_joints, body_px = true_mask_fits("salsa_spin_left", 35)
    errors = side_matched_errors(fitted, true_joints)[20:35] / body_px * 100
    wrists = errors[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]]].max(axis=1)
    assert (wrists < 5.0).sum() >= 8, wrists.round(1)
