"""The first guess where the user said nothing: orientation, sides, signs (against the
exact truth of the model's own walk and, when present, real motion capture)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import SHARED_DATA

from mocap import body, synth
from mocap.body import BODY_HEIGHT, JOINT_INDEX, MIRROR_JOINTS
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.lift import taylor as lift
from mocap.lift.inputs import Said, resolve_inputs
from mocap.lift.orientation import (
    GROWTH,
    NEGLIGIBLE,
    PROFILE_SPREAD,
    facing_evidence,
    guess_orientations,
    guess_signs,
    held_user_signs,
    legs_crossed,
    merge_short_runs,
)
from mocap.lift.sides import SEPARATED, known_sides, naming_path, track_sides
from mocap.lift.taylor import runs
from mocap.smoothest import smoothest_states
from mocap.synth.walk import walk_cycle

CMU_WALK = SHARED_DATA / "bvh" / "cmu_walk.bvh"


def seen(joints_world: np.ndarray, view: str, fps: float = 15.0):
    scene = synth.plan_scene(joints_world, synth.RenderOptions(view=view, size=(640, 480), fps=fps))
    return synth.scene_truth(scene, "test", np.arange(len(joints_world)))


def true_inputs(truth):
    ppu = np.full(len(truth.joints2d), truth.body_height_px / BODY_HEIGHT)
    yaw = np.array([lift.yaw_of(p) for p in truth.joints3d])
    names = [lift.orientation_of_yaw(y) for y in yaw]
    yaw = np.array([lift.facing_yaw(n, abs(np.cos(np.radians(y)))) for n, y in zip(names, yaw)])
    signs = np.array([lift.signs_of(p) for p in truth.joints3d])
    visible = np.array([lift.depth_fractions(p) for p in truth.joints3d]) > NEGLIGIBLE
    return ppu, yaw, names, signs, visible


def test_second_order_viterbi_keeps_crossing_tracks_apart():
    t = np.arange(11.0)
    a, b = t - 5, 5 - t  # two tracks crossing at t = 5
    low, high = np.minimum(a, b), np.maximum(a, b)  # what a sorting observer sees
    states = np.stack([np.stack([low, high], -1), np.stack([high, low], -1)], axis=1)  # (F, 2, 2)
    allowed = np.ones((11, 2), bool)
    allowed[0, 1] = False
    path = smoothest_states(states, np.zeros((11, 2)), allowed)
    follows = np.where(path[:, None] == 0, states[:, 0], states[:, 1])
    assert np.allclose(follows[:, 0], a) or np.allclose(follows[:, 0], b)
    assert np.allclose(follows[:, 0], a)


@pytest.mark.parametrize("view", ["three-quarter", "side"])
def test_signs_of_the_models_walk_are_guessed(view):
    truth = seen(walk_cycle(2.2, 15.0), view)
    ppu, yaw, _, signs, visible = true_inputs(truth)
    guess = guess_signs(truth.joints2d, ppu, yaw, fps=15.0)
    if visible.any():
        assert (guess == signs)[visible].mean() >= 0.9


def test_a_users_sign_holds_until_their_next_entry_and_the_guess_resumes_after():
    truth = seen(walk_cycle(2.2, 15.0), "three-quarter")
    ppu, yaw, _, signs, visible = true_inputs(truth)
    k = int(np.argmax(visible.sum(axis=0)))  # the segment most out of the image plane
    stretch = runs(visible[:, k])[0]
    values, since = np.zeros_like(signs), np.full(signs.shape, -1)
    values[stretch, k], since[stretch, k] = -signs[stretch.start, k], stretch.start  # the user insists
    fixed = held_user_signs(values, since)
    guess = guess_signs(truth.joints2d, ppu, yaw, fixed=fixed, fps=15.0)
    assert (guess[stretch, k] == -signs[stretch, k]).all()
    after = np.flatnonzero(visible[stretch.stop :, k]) + stretch.stop
    assert (guess[after, k] == signs[after, k]).mean() >= 0.9  # no entry there: the guess resumes


def test_real_walk_signs_from_true_2d():
    if not CMU_WALK.exists():
        pytest.skip(f"real data absent: {CMU_WALK} (../shared/data beside the checkout)")
    truth = seen(contract_joints(read_bvh(CMU_WALK))[::4], "three-quarter", fps=30.0)
    ppu, yaw, _, signs, visible = true_inputs(truth)
    guess = guess_signs(truth.joints2d, ppu, yaw, lift.clip_lengths(truth.joints2d, ppu), fps=30.0)
    assert (guess == signs)[visible].mean() >= 0.9


@pytest.mark.parametrize(
    "view, mirror, expected",
    [
        ("three-quarter", False, "forward_right"),
        ("side", False, "right"),
        ("three-quarter", True, "forward_left"),
        ("side", True, "left"),
    ],
)
def test_orientation_from_the_walking_direction(view, mirror, expected):
    truth = seen(walk_cycle(2.2, 15.0), view)
    joints = truth.joints2d[:, MIRROR_JOINTS]  # the fit's image sides, facing the camera
    spread = np.abs(np.cos(np.radians([lift.yaw_of(p) for p in truth.joints3d])))
    if mirror:  # the same walk seen in a mirror: to the left
        joints = joints.copy()
        joints[..., 0] = truth.width - joints[..., 0]
        joints = joints[:, MIRROR_JOINTS]
    body_px = np.full(len(joints), truth.body_height_px)
    names = guess_orientations(joints, body_px, spread, 15.0)
    assert names.count(expected) >= 0.9 * len(names)


def test_sides_follow_the_orientation_rule_where_it_is_known():
    truth = seen(walk_cycle(1.0, 15.0), "three-quarter")
    image_side = truth.joints2d[:, MIRROR_JOINTS]  # forward: image-left limbs are the right ones
    known = known_sides(["forward_right"] * len(image_side), {}, image_side)
    swap = track_sides(image_side, known, np.ones(len(image_side)), 15.0)
    assert swap[:, :2].all() and not swap[:, 2].any()
    backward = known_sides(["backward_right"] * len(image_side), {}, image_side)
    assert not track_sides(image_side, backward, np.ones(len(image_side)), 15.0).any()


def test_a_joint_override_decides_the_sides_in_a_profile():
    truth = seen(walk_cycle(1.0, 15.0), "side")
    joints = truth.joints2d.copy()  # anatomical: image-left is left, no swap
    frame = int(np.argmax(np.abs(joints[:, 12, 0] - joints[:, 15, 0])))  # ankles widest apart
    says = {frame: {"ankle_l": tuple(joints[frame, 12]), "wrist_l": tuple(joints[frame, 6])}}
    known = known_sides(["right"] * len(joints), says, joints)
    assert (known[frame] == 0).all() and (np.delete(known, frame, axis=0) == -1).all()
    swap = track_sides(joints, known, np.ones(len(joints)), 15.0)
    assert not swap[frame].any()


def profile_walk_by_image_side():
    """A walk seen in profile facing image right, its limbs named by image side as the
    fit names them; the truth and, per limb kind, whether the image-left one is the right."""
    truth = seen(walk_cycle(3.0, 30.0), "side")
    image_side, swapped = truth.joints2d.copy(), {}
    for kind in ("leg", "arm"):
        chain = [[JOINT_INDEX[f"{n}_{s}"] for n in body.LIMB_JOINTS[kind]] for s in "lr"]
        swapped[kind] = truth.joints2d[:, chain[0], 0].mean(1) > truth.joints2d[:, chain[1], 0].mean(1)
        image_side[np.ix_(swapped[kind], chain[0])] = truth.joints2d[np.ix_(swapped[kind], chain[1])]
        image_side[np.ix_(swapped[kind], chain[1])] = truth.joints2d[np.ix_(swapped[kind], chain[0])]
    return truth, image_side, swapped


def test_limbs_keep_their_sides_through_every_crossing_of_a_profile_walk():
    """In a profile the fit names the legs and the arms by their image order, which
    changes at every step; from a single joint override the legs are followed through
    the moments they pass each other, and the arms, swinging opposite to the legs
    (the arm in front is on the other side than the leg in front), get their sides
    wherever the hands are apart."""
    truth, image_side, swapped = profile_walk_by_image_side()
    for kind in ("leg", "arm"):
        assert 0.2 < swapped[kind].mean() < 0.8  # the image order changes
    ankles = truth.joints2d[:, [JOINT_INDEX["ankle_l"], JOINT_INDEX["ankle_r"]]]
    frame = int(np.argmax(np.abs(ankles[:, 0, 0] - ankles[:, 1, 0])))  # widest apart
    says = {frame: {"ankle_l": tuple(ankles[frame, 0])}}
    known = known_sides(["right"] * len(image_side), says, image_side)
    swap = track_sides(image_side, known, np.ones(len(image_side)), 30.0)
    assert np.mean(swap[:, 1] == swapped["leg"]) > 0.9  # the rest: legs level, either order
    arm = sum(body.LENGTH[body.SEGMENT_INDEX[s]] for s in ("upper_arm_l", "lower_arm_l"))
    wrists = truth.joints2d[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]], 0]
    apart = np.abs(wrists[:, 0] - wrists[:, 1]) > SEPARATED * arm * truth.body_height_px / BODY_HEIGHT
    assert apart.mean() > 0.5 and np.mean(swap[apart, 0] == swapped["arm"][apart]) > 0.9


def test_a_kicking_leg_keeps_its_name_through_the_crossing_its_thigh_swings_through():
    """A real kick fitted from its masks (kick_34's true masks, frames 40-79): the
    kicking leg swings forward past the standing one, ever faster, into a profile
    where the image sides say nothing. At the crossing the fit hands each leg's name
    to the other and draws the kicking shin folded back, so the joints' positions
    alone continue the legs the wrong way; the thighs' turning names them right."""
    data = json.loads((Path(__file__).parent / "data" / "kick_crossing.json").read_text())
    joints, truth = np.array(data["joints2d"]), np.array(data["right_is_image_left"], bool)
    known = np.full((len(joints), 2), -1, np.int8)
    known[:6] = 1  # turned toward the camera: the rule holds
    swap = track_sides(joints, known, np.ones(len(joints)), 25.0)[:, 1]
    assert truth[6:19].all() and not truth[19:].any()  # the fit exchanges the names at frame 59
    assert np.mean(swap[6:] == truth[6:]) > 0.9
    assert not swap[25:].any()  # named right after the crossing


def test_a_crossing_one_following_barely_tells_gives_way_to_the_evidence():
    """The same kick fitted with the crouching trunk (kick_34's true masks, frames
    40-99): the kicking leg swings past the standing one and its foot lands, where
    the fit draws the shin folded back. Carried on at its pace from before, the
    landing foot overshoots and barely tells the two orders apart; carried back
    from after, the misdrawn shin says surely that the legs kept their order. A
    crossing is as sure as the less sure of the two, so the weak image-side evidence
    of the profile after it, over 40 frames, renames the legs."""
    data = json.loads((Path(__file__).parent / "data" / "kick_crouch_crossing.json").read_text())
    joints, truth = np.array(data["joints2d"]), np.array(data["right_is_image_left"], bool)
    known = np.full((len(joints), 2), -1, np.int8)
    swap = track_sides(joints, known, np.ones(len(joints)), 25.0, rule=np.array(data["rule"]))[:, 1]
    assert truth[5:19].all() and not truth[19:].any()  # the legs pass each other at frame 59
    assert swap[5:19].all()  # turned toward the camera: the rule
    assert not swap[27:].any()  # named right from the next stretch apart on


def test_legs_the_fit_draws_with_crossed_thighs_are_named_by_where_they_lie():
    """A real turn from a profile into a back view (salsa_spin_left's true masks, frames
    40-71): the legs are crossed in a cross-step, and the fit, which orders the hips by
    image side, draws the thighs crossed, its image-left leg lying on the image right
    (frames 53-61). The image-side rule names the legs by where they lie, so there
    the knees and ankles are exchanged between the hips: named as they lie, they are
    the truth's."""
    data = json.loads((Path(__file__).parent / "data" / "salsa_crossed_thighs.json").read_text())
    joints = np.array(data["joints2d"])
    known = np.full((len(joints), 2), -1, np.int8)
    names = track_sides(
        joints, known, np.array(data["facing_x"]), 25.0, np.array(data["away"]), rule=np.array(data["rule"])
    )
    named = lift.exchange_legs(lift.anatomical_joints(joints, names[:, :2]), names[:, 2])
    kinds = ("knee_l", "ankle_l", "knee_r", "ankle_r")
    legs = named[:, [JOINT_INDEX[k] for k in kinds]]
    truth = np.stack([np.array(data["true_legs"][k]) for k in kinds], axis=1)
    error = np.linalg.norm(legs - truth, axis=-1).sum(1)
    other = np.linalg.norm(legs[:, [2, 3, 0, 1]] - truth, axis=-1).sum(1)
    assert (error[13:22] < other[13:22]).all()  # the thighs drawn crossed
    assert np.mean(error < other) > 0.9


def waving_in_place(seconds: float, fps: float) -> np.ndarray:
    """(F, 16, 3) world joints of a performer standing with the feet apart and waving
    both arms, stretched out to the sides, up and down out of phase (model proportions)."""
    stand = walk_cycle(1.0 / fps, fps, in_place=True)[0]
    frames = np.repeat(stand[None], max(1, int(round(seconds * fps))), axis=0)
    t = np.arange(len(frames)) / fps
    arm = np.linalg.norm(stand[JOINT_INDEX["elbow_l"]] - stand[JOINT_INDEX["shoulder_l"]])
    for side, out in (("l", 1.0), ("r", -1.0)):  # the performer's left is +x
        frames[:, [JOINT_INDEX[f"knee_{side}"], JOINT_INDEX[f"ankle_{side}"]], 0] += out * 0.15
        lift = np.radians(20.0 + 40.0 * np.sin(2 * np.pi * t + (0.0 if side == "l" else np.pi)))
        reach = np.stack([out * np.cos(lift), np.sin(lift), np.zeros_like(lift)], axis=-1) * arm
        shoulder = frames[:, JOINT_INDEX[f"shoulder_{side}"]]
        frames[:, JOINT_INDEX[f"elbow_{side}"]] = shoulder + reach
        frames[:, JOINT_INDEX[f"wrist_{side}"]] = shoulder + 2 * reach
    return frames


def test_arms_take_the_legs_sides_where_the_performer_does_not_step():
    """A performer waving in place, facing the camera, the legs' sides known (as from
    the user's knee marks) and the arms' not, as in a profile: there are no steps for
    the arms to swing against, and each arm hangs from the shoulder above its own
    side's hip, so the arms take the legs' sides (swung opposite to the legs, as in a
    walk, each arm was named the other)."""
    truth = seen(waving_in_place(2.0, 30.0), "front", fps=30.0)
    image_side = truth.joints2d[:, MIRROR_JOINTS]  # facing the camera: image-left is right
    known = np.full((len(image_side), 2), -1, np.int8)
    known[:, 1] = 1
    assert track_sides(image_side, known, np.ones(len(image_side)), 30.0)[:, 0].all()


def test_the_heads_look_names_the_limbs_of_a_profile_where_nothing_else_does():
    """A performer seen from behind, feet and arms apart, taken for a profile (as a
    narrow torso is) with nothing known: where the head's look says they face away,
    the backward-facing rule (image-left limbs are the left ones) names the limbs;
    without it, the forward-facing convention names each the other."""
    behind = synth.RenderOptions(yaw=-90.0, size=(640, 480), fps=30.0)
    scene = synth.plan_scene(waving_in_place(2.0, 30.0), behind)
    joints = synth.scene_truth(scene, "test", np.arange(60)).joints2d  # anatomical names
    assert (joints[:, JOINT_INDEX["ankle_l"], 0] < joints[:, JOINT_INDEX["ankle_r"], 0]).all()  # image-left
    known = np.full((len(joints), 2), -1, np.int8)
    assert not track_sides(joints, known, np.ones(len(joints)), 30.0, np.ones(len(joints), bool)).any()
    assert track_sides(joints, known, np.ones(len(joints)), 30.0)[:, :2].all()


def test_the_near_arm_names_the_limbs_of_a_profile_where_nothing_else_does():
    """A profile walk with nothing known: the naming is the one whose arms agree with
    the near arm (mocap.silhouette.facing.near_arm; facing image right the near arm is the
    performer's right). Told the image-left arm is the near one where it is the right
    one, every limb is named right; told the other, every limb the other way."""
    truth, image_side, swapped = profile_walk_by_image_side()
    known = np.full((len(image_side), 2), -1, np.int8)
    near = np.stack([np.where(swapped["arm"], 0.2, -0.2), np.zeros(len(image_side))], axis=1)  # the right arm's
    right = track_sides(image_side, known, np.ones(len(image_side)), 30.0, near=near)
    wrong = track_sides(image_side, known, np.ones(len(image_side)), 30.0, near=-near)
    arm = sum(body.LENGTH[body.SEGMENT_INDEX[s]] for s in ("upper_arm_l", "lower_arm_l"))
    wrists = truth.joints2d[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]], 0]
    apart = np.abs(wrists[:, 0] - wrists[:, 1]) > SEPARATED * arm * truth.body_height_px / BODY_HEIGHT
    assert np.mean(right[:, 1] == swapped["leg"]) > 0.9 and np.mean(wrong[:, 1] == swapped["leg"]) < 0.1
    assert np.mean(right[apart, 0] == swapped["arm"][apart]) > 0.9
    assert np.mean(wrong[apart, 0] == swapped["arm"][apart]) < 0.1


def test_arms_take_the_legs_sides_in_a_real_laugh():
    """The same for a real performer laughing on the spot (CMU 13_14: arms thrown up
    and out, feet apart) seen from the front, wherever the hands are apart."""
    laugh = SHARED_DATA / "bvh" / "cmu_13_14_laugh.bvh"
    if not laugh.exists():
        pytest.skip(f"real data absent: {laugh} (../shared/data beside the checkout)")
    truth = seen(contract_joints(read_bvh(laugh))[1080:1560:4], "front", fps=30.0)
    image_side = truth.joints2d[:, MIRROR_JOINTS]
    known = np.full((len(image_side), 2), -1, np.int8)
    known[:, 1] = 1
    swap = track_sides(image_side, known, np.ones(len(image_side)), 30.0)
    arm = sum(body.LENGTH[body.SEGMENT_INDEX[s]] for s in ("upper_arm_l", "lower_arm_l"))
    wrists = truth.joints2d[:, [JOINT_INDEX["wrist_l"], JOINT_INDEX["wrist_r"]], 0]
    apart = np.abs(wrists[:, 0] - wrists[:, 1]) > SEPARATED * arm * truth.body_height_px / BODY_HEIGHT
    assert apart.mean() > 0.5 and swap[apart, 0].all()


def test_users_leg_signs_tell_which_leg_is_which_where_the_legs_cross():
    """Turned toward the camera the legs cross in the image at every step, and a fit
    that names the legs by image side hands each hip the other's knee and ankle
    there. The user's thigh and shin signs name the legs back; with no signs
    nothing is exchanged."""
    truth = seen(walk_cycle(3.0, 30.0), "three-quarter", fps=30.0)
    ppu, yaw, _, signs, _ = true_inputs(truth)
    lower = [[JOINT_INDEX[f"{n}_{s}"] for n in ("knee", "ankle")] for s in "lr"]
    # the left hip is on the image right: a fit by image side crosses where the left leg is left of the right
    crossed = truth.joints2d[:, lower[0], 0].mean(1) < truth.joints2d[:, lower[1], 0].mean(1)
    assert 0.1 < crossed.mean() < 0.9
    by_image_side = lift.exchange_legs(truth.joints2d, crossed)
    none = np.zeros(len(crossed), bool)
    found = legs_crossed(by_image_side, signs, yaw, ppu, body.LENGTH, none)
    assert np.mean(found == crossed) > 0.9
    assert not legs_crossed(by_image_side, np.zeros_like(signs), yaw, ppu, body.LENGTH, none).any()


LIFT_SPREAD_CLIPS = (
    "jump_balance_34b",
    "kick_34",
    "laugh_back",
    "punch_front",
    "run_across",
    "salsa_spin_left",
    "scoop_34",
    "walk_toward",
)


def lift_spreads_and_truth(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The lift's torso spread on every frame of a development clip's true masks, as
    pass two works it out (passes.FitStream), and the truth's |cos yaw|."""
    import cv2
    from helpers import DEV_CLIPS

    from mocap.io.video import iter_frames, open_video, processing_scale
    from mocap.silhouette.passes import SPREAD_WINDOW_S, Silhouette, body_heights, half_window, lift_spread, torso_reads

    clip = DEV_CLIPS / name
    if not (clip / "truth.json").is_file():
        pytest.skip(f"real data absent: {clip} (../shared/data beside the checkout)")
    info = open_video(clip / "video.mp4")
    silhouettes = []
    for index, frame in iter_frames(info, scale=processing_scale(info)):
        mask = cv2.imread(str(clip / "masks" / f"{index:06d}.png"), cv2.IMREAD_GRAYSCALE)
        silhouettes.append(Silhouette.from_mask(cv2.resize(mask, frame.shape[1::-1], interpolation=cv2.INTER_NEAREST)))
    _, raw, readable = zip(*(torso_reads(s, h) for s, h in zip(silhouettes, body_heights(silhouettes, info.fps))))
    half = half_window(SPREAD_WINDOW_S, info.fps)
    truth = json.loads((clip / "truth.json").read_text())["frames"]
    return (
        np.array([lift_spread(raw, readable, i, half) for i in range(len(raw))]),
        np.abs(np.cos(np.radians([f["facing_deg"] for f in truth]))),
    )


def test_lift_spread_follows_the_true_yaw_on_the_development_clips():
    """The torso spread the orientation guess reads (|cos yaw|, profile below 0.5),
    taken from the frames whose torso width is readable (upright, no arm raised over
    the head) at the processing resolution, against the truth's yaw on the eight
    development clips' true masks: mean error 0.15 and profile named as the truth
    names it on 82% of frames (at the fit's resolution 0.20 and 78%; the 5th
    percentile of all frames, which the fit draws the torso with: 0.27 and 65%, back
    views with arms raised and crouches read as profiles)."""
    errors, agree = [], []
    for name in LIFT_SPREAD_CLIPS:
        spread, truth = lift_spreads_and_truth(name)
        errors.append(np.mean(np.abs(spread - truth)))
        agree.append(np.mean((spread < PROFILE_SPREAD) == (truth < PROFILE_SPREAD)))
    assert np.mean(errors) < 0.17 and np.mean(agree) > 0.79, (errors, agree)
    assert min(agree) > 0.4, agree


def test_a_naming_holds_where_the_legs_are_followed_surely_and_gives_way_where_not():
    """naming_path: the legs followed through time (parity) cross at frame 10, surely
    (link 2.0), and seemingly at frame 30, across a long stretch close together (link
    0.3); the first ten frames are named (keep). Five frames of weak evidence
    against the naming (0.1 each) do not rename the legs across the sure crossing;
    twenty frames of it after the unsure one rename the legs there rather than
    follow them."""
    parity = np.r_[np.zeros(10), np.ones(20), np.zeros(20)].astype(int)
    links = np.full(49, 2.0)
    links[29] = 0.3
    costs = np.zeros((50, 2))
    costs[:10, 1] = 5.0  # keep
    costs[10:15, 1] = 0.1  # weakly against the crossing's swap
    swap = naming_path(costs, parity, links)
    assert not swap[:10].any() and swap[10:30].all() and not swap[30:].any()  # followed
    costs[30:, 0] = 0.1  # twenty frames against the crossing at 30
    swap = naming_path(costs, parity, links)
    assert not swap[:10].any() and swap[10:].all()


def stored_fit_named_right(file: str) -> tuple[np.ndarray, np.ndarray]:
    """(F,) bool per frame of a stored fit (tests/data: its image-side joints, body
    heights, spreads, heads' look and near limbs) resolved with no input: whether its
    legs are named as the truth names them, and whether that matters there."""
    data = json.loads((Path(__file__).parent / "data" / file).read_text())
    inputs = resolve_inputs(
        np.array(data["joints2d"]),
        np.array(data["body_px"]),
        np.array(data["spread"]),
        data["fps"],
        Said.nothing(len(data["joints2d"])),
        away=np.array(data["away"]),
        near=np.array(data["near"]),
    )
    return inputs.swap[:, 1] == np.array(data["right_is_image_left"]), np.array(data["clear"])


def test_a_turn_through_a_profile_and_back_keeps_the_legs_names():
    """A real turn (laugh_back on its true masks, the fit's image-side joints and its
    cues stored): seen from behind, the performer turns to a profile and back with the
    arms raised, which lowers the torso's spread into a profile's for most of the
    clip, and the legs stay close together for twenty frames where the fit's
    following of them sees a crossing that is not there. The naming holds the
    backward view's through it where the head's look says the performer faces away:
    the right leg named at the truth's on at least 3/4 of the frames where it matters
    (half before)."""
    named, clear = stored_fit_named_right("laugh_turn.json")
    assert clear.sum() > 50 and np.mean(named[clear]) >= 0.75


def test_a_three_quarter_view_read_narrow_takes_the_image_side_rule():
    """A real turn of a slim performer (salsa_spin_left fitted with no input, the
    fit's image-side joints and its cues stored): a three-quarter view from the front
    whose torso reads as narrow as a profile's of the model's build (spread about
    0.3), a turn through the profile (the clip's narrowest, 0.07) to a back view, and
    the legs followed through the turn without the crossing it makes. The image-side
    rule of the three-quarter view, ramped up from the clip's own profile read, names
    the legs there rather than the back view's naming followed back through the turn:
    the right leg named at the truth's on at least 4/5 of the frames where it matters
    (38% before)."""
    named, clear = stored_fit_named_right("salsa_spin.json")
    assert clear.sum() > 80 and np.mean(named[clear]) >= 0.8


def test_only_a_steady_growth_says_the_performer_walks_toward_the_camera():
    """The body's size (its image height, F,) growing by twice GROWTH a second says
    toward the camera on every frame, shrinking says away; the same growth over the
    clip's first five frames, as where a crouch leaves the body heights' window, and
    none after says nothing (pooled by its mean it said toward on the first fifteen
    frames of jump_balance_34b, seen from behind)."""
    fps, n = 25.0, 60
    joints = np.zeros((n, 16, 2))
    steady = 300.0 * np.exp(2 * GROWTH * np.arange(n) / fps)
    assert (facing_evidence(joints, steady, fps) == 1).all()
    assert (facing_evidence(joints, steady[::-1], fps) == -1).all()
    jump = np.r_[np.linspace(284.0, 306.0, 5), np.full(n - 5, 306.0)]
    assert not facing_evidence(joints, jump, fps).any()


def test_short_runs_at_the_start_take_the_first_long_runs_name():
    """Frames at the threshold of the torso's spread flicker between a profile and a
    turned view; at the start of a clip, where no run precedes them, they take the
    name of the first run that is long enough, not that of the short run after them
    (which named the first two frames of a profile run across the frame turned)."""
    names = ["right", "forward_right"] + ["right"] * 20 + ["forward_right"] * 3 + ["right"] * 20
    assert merge_short_runs(names, 12) == ["right"] * len(names)
    assert merge_short_runs([None, "left"] + ["backward_left"] * 15, 12) == [None] + ["backward_left"] * 16


def test_min_marginals_are_the_best_path_through_each_state():
    """signpath.min_marginals against every path of a small chain: the least total cost through each
    state on each frame, and its least over the states is the Viterbi path's cost."""
    import itertools

    from mocap.lift.signpath import min_marginals, viterbi

    rng = np.random.default_rng(3)
    emission, transition = rng.uniform(0, 5, (5, 3)), rng.uniform(0, 5, (4, 3, 3))

    def cost(path) -> float:
        return emission[np.arange(5), path].sum() + sum(transition[f, path[f], path[f + 1]] for f in range(4))

    paths = list(itertools.product(range(3), repeat=5))
    through = min_marginals(emission, transition)
    for f in range(5):
        for s in range(3):
            assert through[f, s] == pytest.approx(min(cost(p) for p in paths if p[f] == s))
    assert through.min(axis=1) == pytest.approx(np.full(5, cost(viterbi(emission, transition))))
