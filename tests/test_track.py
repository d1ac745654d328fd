"""The tracking method's 2D side: the marks, morph blocks (block-matching Eq. 3-5,
sub-pixel sampling, the search path), the head's image difference (Eq. 1-5), the
reliability fill, and tracking a rendered walk over a moving, cluttered background."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from helpers import render_tracked_walk
from scipy.spatial.transform import Rotation

from mocap import synth
from mocap.body import JOINT_INDEX, JOINTS, unit
from mocap.camera import Pinhole
from mocap.errors import MocapError
from mocap.image.edges import Edges
from mocap.io.video import iter_frames
from mocap.synth.walk import walk_cycle
from mocap.track import blocks
from mocap.track.calibration import FACING_CAMERA, KEY, Calibration
from mocap.track.headmotion import adapt_threshold, head_displacement, two_peak_displacement
from mocap.track.limbs import (
    ARM_M,
    FOLD_COST,
    JUMP_COST,
    KNEE_STEP,
    LIMITS_COST,
    OUTLINE_COST,
    added,
    arm_limits_cost,
    around_root,
    leg_limits_cost,
    limb_penalty,
    marked_lengths,
    outline_cost,
    overlap,
    settled_knee,
    twin_overlap,
)
from mocap.track.marks import check_marks
from mocap.track.parts import PARTS, beside, far_arm, far_forearm, mirrored_model, own_colour, told_apart
from mocap.track.tracker import FAR_UPPER_SCALES, FAR_UPPER_WEIGHT, BodyTracker
from mocap.track.tracking import (
    LOW_RELIABILITY,
    carried_pins,
    fill_unreliable,
    joint_reliability,
    spread_corrections,
    track_clip,
)


@pytest.fixture(scope="module")
def walk(tmp_path_factory):
    """A 320x240 three-quarter walk, pinhole camera, panning cluttered background."""
    video = tmp_path_factory.mktemp("track") / "walk.mp4"
    truth = render_tracked_walk(video)
    return video, truth


# -- marks --------------------------------------------------------------------------------


def test_good_marks_pass_as_array_or_mapping(walk):
    marks = walk[1].joints2d[0]
    assert np.array_equal(check_marks(marks, 320, 240), marks)
    as_dict = {name: tuple(xy) for name, xy in zip(JOINTS, marks)}
    assert np.array_equal(check_marks(as_dict, 320, 240), marks)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda m: m.pop("wrist_r"), "joint wrist_r is not marked"),
        (lambda m: m.update(knee_l=(np.nan, 10.0)), "joint knee_l is not marked"),
        (lambda m: m.update(ankle_l=(100.0, 240.0)), r"joint ankle_l at \(100.0, 240.0\) is outside the 320x240"),
        (lambda m: m.update(elbow_x=(1.0, 1.0)), "unknown joint 'elbow_x'"),
        (lambda m: m.update(shoulder_l=m["shoulder_r"]), "shoulder_l and shoulder_r nearly coincide"),
        (
            lambda m: m.update(chest=tuple((np.add(m["shoulder_l"], m["shoulder_r"])) / 2 + [0.5, 0.0])),
            "chest is nearly on the line",
        ),
    ],
)
def test_bad_marks_name_the_joint(walk, change, message):
    marks = {name: tuple(xy) for name, xy in zip(JOINTS, walk[1].joints2d[0])}
    change(marks)
    with pytest.raises(MocapError, match=message):
        check_marks(marks, 320, 240)


def test_marks_of_the_wrong_shape_are_refused():
    with pytest.raises(MocapError, match="expected 16 marked joints"):
        check_marks(np.zeros((15, 2)), 320, 240)


# -- morph blocks -------------------------------------------------------------------------


def test_similarity_is_the_weighted_difference_of_eq_3_to_5():
    grid = blocks.make_grid(8, 6)  # centre b1, the middle half: rows 2-5, columns 1-4
    model = np.zeros((8, 6, 3), np.float32)
    seen = np.zeros((1, 8, 6, 3), np.float32)
    seen[0, :, :, 0] = 30.0  # one channel off by 30 everywhere
    seen[0, 3, 3] = [30.0, 60.0, 90.0]  # one centre sub-pixel off more
    diff = np.full((8, 6), 10.0)  # W_R = W_G = W_B = 1/3
    diff[3, 3] = 60.0
    weights = np.full((8, 6), blocks.MARGIN_WEIGHT)
    weights[2:6, 1:5] = blocks.CENTRE_WEIGHT
    expected = weights.sum() / (weights * diff).sum()
    assert blocks.similarity(model, seen, grid)[0] == pytest.approx(expected, rel=1e-5)


def test_a_model_of_alternatives_scores_the_best_one():
    grid = blocks.make_grid(8, 6)
    seen = np.stack([np.full((8, 6, 3), 100.0, np.float32), np.full((8, 6, 3), 20.0, np.float32)])
    near_first, near_second = np.full((8, 6, 3), 90.0, np.float32), np.full((8, 6, 3), 25.0, np.float32)
    both = blocks.similarity(np.stack([near_first, near_second]), seen, grid)
    assert both == pytest.approx([1 / 10.0, 1 / 5.0])
    assert blocks.similarity(near_first, seen, grid) == pytest.approx([1 / 10.0, 1 / 70.0])


def test_the_far_forearm_and_its_twins_mirrored_colours():
    """The forearm of the arm whose shoulder lies deeper (key depths: left shoulder,
    right shoulder, chest) is the far one; none for a body square to the camera. The
    twin's model is mirrored across the block and resampled to the forearm's grid."""
    part = {p.segment: k for k, p in enumerate(PARTS)}
    assert far_forearm(np.array([6.3, 6.0, 6.1])) == part["lower_arm_l"]
    assert far_forearm(np.array([6.0, 6.3, 6.1])) == part["lower_arm_r"]
    assert far_forearm(np.array([6.0, 6.05, 6.1])) is None
    assert [far_arm(np.array(d)) for d in ([6.3, 6.0, 6.1], [6.0, 6.3, 6.1], [6.0, 6.05, 6.1])] == ["l", "r", None]
    twin = np.zeros((14, 7, 3), np.float32)
    twin[:, 0] = 200.0  # lit on its first column
    mirrored = mirrored_model(twin, (10, 7, 3))
    assert mirrored.shape == (10, 7, 3)
    assert (mirrored[:, -1] == 200.0).all() and (mirrored[:, 0] == 0.0).all()


def test_sub_pixel_sampling_is_bilinear():
    y, x = np.mgrid[0:60, 0:80].astype(np.float32)
    image = np.dstack([x, y, x + y]).astype(np.float32)  # a linear ramp: bilinear is exact
    block = np.array([20.3, 15.7, np.radians(33.0), 21.4, 6.6])
    grid = blocks.make_grid(block[blocks.M], block[blocks.N])
    xs, ys = blocks.block_points(block[None], grid)
    seen = blocks.sample_blocks(image, block, grid)[0]
    assert np.allclose(seen[..., 0], xs, atol=0.01) and np.allclose(seen[..., 1], ys, atol=0.01)


def test_rings_of_the_search_path():
    for r in range(4):
        ring = blocks.ring(r)
        assert len({tuple(p) for p in ring}) == max(1, 8 * r)
        assert np.all(np.abs(ring).max(axis=1) == r)


def test_search_finds_a_moved_turned_block():
    rng = np.random.default_rng(1)
    image = rng.integers(0, 255, (120, 120, 3)).astype(np.uint8)
    image = cv2.GaussianBlur(image, (5, 5), 2)
    true = np.array([50.0, 30.0, np.radians(70.0), 40.0, 12.0])
    along = np.array([np.cos(true[2]), np.sin(true[2])])
    across = np.array([-along[1], along[0]])
    corners = [true[:2] + s * 6 * across + t * 40 * along for s, t in ((1, 0), (1, 1), (-1, 1), (-1, 0))]
    cv2.fillConvexPoly(image, np.round(corners).astype(np.int32), (40, 90, 200))
    grid = blocks.make_grid(40, 12, beyond=0.3)
    model = blocks.sample_blocks(image, true, grid)[0]
    start = true + [3.0, -2.0, np.radians(6.0), 0.0, 0.0]
    found, s = blocks.search(image, model, grid, start, np.radians(np.arange(-8, 9, 2.0)), np.array([0.0]), max_ring=5)
    assert np.hypot(*(found[:2] - true[:2])) <= 1.0
    assert abs(np.degrees(found[2] - true[2])) <= 1.0
    assert s == pytest.approx(1.0)  # exact match: 1 / MIN_DIFF


def test_a_penalty_moves_the_search_off_the_best_match():
    image = np.zeros((80, 80, 3), np.uint8)
    root = np.array([20.0, 10.0])
    for angle, grey in ((45.0, 150), (90.0, 200)):  # two like bars from one root
        end = root + 50 * np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])
        cv2.line(image, tuple(np.int32(root)), tuple(np.int32(end)), (grey,) * 3, 5)
    start = np.array([*root, np.radians(90.0), 40.0, 5.0])
    grid = blocks.make_grid(40, 5)
    model = blocks.sample_blocks(image, start, grid)[0]
    turns = np.radians(np.arange(-60.0, 61.0, 5.0))
    down = lambda cands: 100.0 * (np.abs(cands[:, 2] - np.pi / 2) < 0.2)  # noqa: E731
    found, _ = blocks.search(image, model, grid, start, turns, np.array([0.0]))
    kept_off, _ = blocks.search(image, model, grid, start, turns, np.array([0.0]), penalty=down)
    assert np.degrees(found[2]) == pytest.approx(90.0)
    assert np.degrees(kept_off[2]) == pytest.approx(45.0)


def test_overlap_of_blocks_and_the_limbs_kept_off():
    other = np.array([0.0, 0.0, 0.0, 40.0, 10.0])  # along x, 10 px wide
    lowers = np.array(
        [
            [0.0, 0.0, 0.0, 40.0, 10.0],  # on it
            [0.0, 5.0, 0.0, 40.0, 10.0],  # half a width beside it
            [0.0, 30.0, 0.0, 40.0, 10.0],
        ]
    )  # clear of it
    assert np.allclose(overlap(lowers, other), [1.0, 0.5, 0.0])
    assert twin_overlap(lowers[0], lowers[2]) == 0.0
    folded = np.array(
        [
            [40.0, 0.0, np.pi, 40.0, 10.0],  # back along its upper part
            [40.0, 0.0, np.pi / 2, 40.0, 10.0],
        ]
    )  # bent at a right angle
    penalty = limb_penalty(np.zeros(2), 10.0, folded[0], 40.0, ((7.0, other),))
    assert penalty(folded)[0] == pytest.approx(FOLD_COST + 7.0)  # where it was
    assert penalty(folded)[1] == pytest.approx((FOLD_COST + 7.0) / 8 + JUMP_COST * np.sqrt(2))


def arm_over_trunk() -> tuple[np.ndarray, np.ndarray]:
    """A frame whose trunk (grey 150) has an arm of nearly its colour (156) over it,
    from the shoulder (60, 20) down at 60 degrees, outlined by its shadow; and the
    arm's colour model, the trunk's colour."""
    image = np.full((120, 120, 3), 60, np.uint8)
    image[10:110, 30:90] = 150
    end = np.int32(np.array([60.0, 20.0]) + 60 * np.array([np.cos(np.radians(60)), np.sin(np.radians(60))]))
    cv2.line(image, (60, 20), tuple(end), (90,) * 3, 15)  # the shadow
    cv2.line(image, (60, 20), tuple(end), (156,) * 3, 8)  # the arm
    return image, np.full((blocks.ROWS, 4, 3), 150.0, np.float32)


def test_an_arm_over_a_trunk_of_its_colour_follows_its_outline():
    """Colour alone rates any placement over the flat trunk above the arm itself
    (a shade off its model); the arm's outline decides it."""
    image, model = arm_over_trunk()
    root, part = np.array([60.0, 20.0]), (model, blocks.make_grid(30, 4), 8.0, 30.0)
    outline = outline_cost(Edges.of_frame(image))
    nothing = lambda candidates: np.zeros(len(candidates))  # noqa: E731
    by_colour = around_root(image, root, part, part, nothing)
    by_outline = around_root(image, root, part, part, added(nothing, outline), outline)
    assert abs(np.degrees(by_colour[2]) - 60.0) > 10.0
    assert np.degrees(by_outline[2]) == pytest.approx(60.0)
    on_arm, on_trunk = outline(
        np.array([[60.0, 20.0, np.radians(60), 50.0, 8.0], [45.0, 20.0, np.radians(90), 50.0, 8.0]])
    )
    assert on_arm < 0.2 * OUTLINE_COST
    assert on_trunk == pytest.approx(OUTLINE_COST)


def raised_far_arm() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A red trunk on grey and an arm raised beside it from the shoulder (78, 50): its
    sleeve lit brighter than the trunk, 36 px to the elbow, a skin forearm 30 px up
    and out; the shoulder, elbow and wrist."""
    image = np.full((160, 200, 3), 110, np.uint8)
    image[20:140, 40:80] = (40, 40, 160)
    root, elbow = np.array([78.0, 50.0]), np.array([114.0, 50.0])
    wrist = elbow + 30 * np.array([np.cos(np.radians(-45)), np.sin(np.radians(-45))])
    cv2.line(image, tuple(np.int32(root)), tuple(np.int32(elbow)), (90, 90, 250), 8)
    cv2.line(image, tuple(np.int32(elbow)), tuple(np.int32(wrist)), (120, 140, 200), 8)
    return image, np.stack([root, elbow, wrist])


def test_a_far_arm_is_found_by_its_forearm_where_its_sleeve_matches_the_trunk():
    """The far arm's upper arm, its colours marked as the trunk's shaded shirt, matches
    the trunk better than its own lit sleeve; weighed FAR_UPPER_WEIGHT and tried
    FAR_UPPER_SCALES shorter than its usual 40 px, the forearm's skin places the arm."""
    image, (root, elbow, wrist) = raised_far_arm()
    grid = blocks.make_grid(40, 8)
    sleeve = np.full((len(grid.along), len(grid.across), 3), (40, 40, 160), np.float32)
    upper, lower = (sleeve, grid, 8.0, 40.0), (np.full_like(sleeve, (120, 140, 200)), grid, 8.0, 30.0)
    nothing = lambda candidates: np.zeros(len(candidates))  # noqa: E731
    by_sleeve = around_root(image, root, upper, lower, nothing, nothing)
    weighed = around_root(image, root, upper, lower, nothing, nothing, FAR_UPPER_WEIGHT)
    found = around_root(image, root, upper, lower, nothing, nothing, FAR_UPPER_WEIGHT, FAR_UPPER_SCALES)
    assert np.linalg.norm(blocks.block_end(by_sleeve) - wrist) > 40.0  # the sleeve on the trunk
    assert np.linalg.norm(weighed[:2] - elbow) > 3.0  # at the usual length only
    assert np.linalg.norm(found[:2] - elbow) < 1.0
    assert np.linalg.norm(blocks.block_end(found) - wrist) < 1.0


def sleeve_scene(arm_x: int, sleeve: tuple) -> np.ndarray:
    """A red trunk on grey and an arm hanging at ``arm_x``: a ``sleeve`` over its upper
    part, skin at its end."""
    image = np.full((120, 200, 3), (110, 110, 110), np.uint8)
    image[10:110, 20:55] = (40, 40, 160)
    image[20:65, arm_x - 5 : arm_x + 5] = sleeve
    image[65:80, arm_x - 4 : arm_x + 4] = (150, 180, 220)
    return image


def test_an_arm_is_matched_by_what_tells_it_from_its_surroundings():
    """Marked hanging beside a shirt of its colour, then raised over the background and
    lit brighter, the arm's place wins over the shirt where it hung only when its
    sub-pixels weigh as much as they tell it from what lay beside it (the sleeve
    little, the skin fully)."""
    marked = sleeve_scene(60, (40, 40, 160))
    hung, raised = np.array([[60.0, 20.0, np.pi / 2, 60.0, 10.0], [140.0, 20.0, np.pi / 2, 60.0, 10.0]])
    later = sleeve_scene(140, (70, 70, 200))
    later[20:80, 55:65] = (40, 40, 160)
    grid = blocks.make_grid(60, 10, 0.3)
    model = blocks.sample_blocks(marked, hung, grid)[0]
    told = told_apart(marked, hung, grid)
    assert told.weights.sum() == pytest.approx(1.0)
    skin, sleeve = told.weights[9:11, 1:].mean(), told.weights[5:9, 2:5].mean()
    assert skin > 5 * sleeve
    on_shirt, in_place = 1.0 / blocks.score(later, model, grid, np.stack([hung, raised]))
    assert on_shirt < in_place
    on_shirt, in_place = 1.0 / blocks.score(later, model, told, np.stack([hung, raised]))
    assert in_place < 0.5 * on_shirt


def test_a_forearm_s_own_colour_leaves_out_the_sleeve_at_its_elbow():
    """A forearm marked with its elbow end in a sleeve of the shirt's colour: between
    the joints only its skin is its own colour; past the joints all of it counts."""
    image = np.full((120, 200, 3), (110, 110, 110), np.uint8)
    image[10:110, 20:55] = (40, 40, 160)  # the shirt
    image[20:35, 55:65] = (40, 40, 160)  # the sleeve over the elbow
    image[35:80, 56:64] = (150, 180, 220)  # the skin
    block = np.array([60.0, 20.0, np.pi / 2, 60.0, 10.0])
    grid = blocks.make_grid(60, 10, 0.3)
    model = blocks.sample_blocks(image, block, grid)[0]
    around = blocks.sample_blocks(image, np.stack([beside(block, -1.0), beside(block, 1.0)]), grid)
    own = own_colour(model, around, grid)
    y = 20 + 60 * grid.along
    assert own[(y < 0) | (y > 80)].all()
    assert not own[(y > 22) & (y < 33)].any()
    assert own[(y > 38) & (y < 78)][:, 1:-1].all()
    told = told_apart(image, block, grid, own=True)
    assert told.weights[(y > 22) & (y < 33)].sum() == 0.0


def test_a_body_in_other_clothes_is_told_from_the_marked_one(walk):
    """BodyTracker.dressed_alike: the marked body ten frames on wears its clothes, in shade too; the same marks on
    that frame with red and blue swapped (other clothes) or moved beside the body (the background) do not."""
    video, truth = walk
    frames = [frame for _, frame in iter_frames(video)]
    tracker = BodyTracker(frames[0], truth.joints2d[0])
    later, frame = truth.joints2d[10], frames[10]
    assert tracker.dressed_alike(frame, later)
    assert tracker.dressed_alike((frame * 0.6).astype(np.uint8), later)
    assert not tracker.dressed_alike(np.ascontiguousarray(frame[..., ::-1]), later)
    assert not tracker.dressed_alike(frame, later + (60.0, 0.0))
    assert not tracker.dressed_alike(frame, later - (60.0, 0.0))


LIMB_POSES = {  # limb -> (directions of its upper and lower bone: allowed poses, poses out of range)
    "arm": (
        [((0, -1, 0), (0, -1, 0)), ((0, -1, 0), (0, 0, 1))],  # hanging, bent forward
        [((-1, 0, 0), (-1, 0, 0))],
    ),  # through the trunk
    "leg": (
        [((0, -1, 0), (0, -1, 0)), ((0, -0.9, 0.44), (0, -0.7, -0.7))],  # standing, mid-stride
        [((-0.7, -0.7, 0), (0, -1, 0)), ((0, -1, 0), (0.8, 0.6, 0))],
    ),  # across the other leg,
}  # a shin out sideways


@pytest.mark.parametrize("kind", LIMB_POSES)
def test_a_limb_out_of_its_range_costs_more_than_one_in_it(kind):
    """The limbs' joint limits in 3D (arm_limits_cost, leg_limits_cost): the model's
    left arm hanging or bent forward at the elbow, its left leg standing or in
    mid-stride, cost only the little they leave their rest; the arm reaching through
    the trunk to the right, the thigh across the other leg or the shin sticking out
    sideways cost many times more."""
    camera = Pinhole(800.0, 320.0, 240.0)
    turned = Rotation.from_matrix(FACING_CAMERA) * Rotation.from_euler("y", np.radians(30.0))
    pose = Calibration(turned.as_rotvec(), np.array([0.4, -0.3, 6.0]), 0.36)
    model = pose.model()
    key = pose.to_camera(model[KEY])
    if kind == "arm":
        root, lengths, cost = model[JOINT_INDEX["shoulder_l"]], ARM_M, arm_limits_cost(camera, key, 0)
    else:
        root, lengths = (
            model[JOINT_INDEX["hip_l"]],
            marked_lengths(camera.project(pose.to_camera(model)), camera, 6.0, "leg"),
        )
        cost = leg_limits_cost(camera, key, camera.project(pose.to_camera(root)), 0, lengths)

    def limb_cost(upper_dir, lower_dir) -> float:
        middle = root + lengths[0] * unit(np.asarray(upper_dir, float))
        end = middle + lengths[1] * unit(np.asarray(lower_dir, float))
        pixels = camera.project(pose.to_camera(np.array([middle, end])))
        return float(cost(blocks.between(pixels[:1], pixels[1:], 5.0))[0])

    allowed, out_of_range = LIMB_POSES[kind]
    assert max(limb_cost(*p) for p in allowed) < 0.15 * LIMITS_COST
    assert min(limb_cost(*p) for p in out_of_range) > 0.8 * LIMITS_COST


def test_a_knee_slid_up_a_thigh_of_its_colour_settles_back():
    """A leg of one colour bent at the knee (60, 70): a shin whose start slid 5 px up
    the thigh is settled back to the knee, to within the places tried, by the thigh's
    and shin's blocks together (settled_knee); a shin at the knee stays there."""
    image = np.full((140, 140, 3), 60, np.uint8)
    hip, knee, ankle = np.array([60.0, 20.0]), np.array([60.0, 70.0]), np.array([95.0, 110.0])
    cv2.line(image, (60, 20), (60, 70), (150,) * 3, 12)
    cv2.line(image, (60, 70), (95, 110), (150,) * 3, 12)
    image[66:75, 55:66] = 150  # the bend
    image = cv2.GaussianBlur(image, (5, 5), 1.0)
    parts = []
    for a, b in ((hip, knee), (knee, ankle)):
        block = blocks.between(a[None], b[None], 12.0)[0]
        grid = blocks.make_grid(block[3], 12.0, 0.3)
        parts.append((blocks.sample_blocks(image, block, grid)[0], grid))
    nothing = lambda candidates: np.zeros(len(candidates))  # noqa: E731
    for start in (knee + [0.0, -5.0], knee):
        shin = blocks.between(start[None], ankle[None], 12.0)[0]
        settled, s = settled_knee(image, hip, shin, (*parts[0], 12.0), parts[1], nothing, nothing)
        assert np.hypot(*(settled[:2] - knee)) < KNEE_STEP * shin[3]  # within a step
        assert blocks.block_end(settled) == pytest.approx(ankle)
        assert s > 0


# -- the head's image difference ------------------------------------------------------------


def test_two_peaks_give_the_displacement_and_its_direction():
    t = np.arange(-40.0, 41.0)
    profile = np.zeros_like(t)
    profile[(t >= -10) & (t < -4)] = 90.0  # H uncovered: 6 px wide
    profile[(t >= 10) & (t < 16)] = 90.0  # H' covers: 6 px farther out
    assert two_peak_displacement(t, profile, 0.5) == pytest.approx(6.0)
    assert two_peak_displacement(-t[::-1], profile[::-1], 0.5) == pytest.approx(-6.0)
    assert adapt_threshold(0.5, 8.0, 6.0) > 0.5 > adapt_threshold(0.5, 4.0, 6.0)


def test_head_motion_by_image_difference_on_a_still_background():
    rng = np.random.default_rng(2)
    room = cv2.GaussianBlur(rng.integers(60, 200, (160, 160, 3)).astype(np.uint8), (0, 0), 3)
    frames = []
    for centre in ((70, 80), (75, 77)):  # the head moves (5, -3)
        img = room.copy()
        cv2.circle(img, centre, 10, (140, 170, 220), -1)
        frames.append(img)
    moved = head_displacement(frames[0], frames[1], np.array([70.0, 70.0]), np.array([70.0, 90.0]), 0.5)
    assert np.hypot(*(moved.vector - [5.0, -3.0])) < 1.5


# -- reliability and filling ------------------------------------------------------------------


def test_unreliable_stretches_are_interpolated_between_reliable_frames():
    joints = np.zeros((6, 16, 2))
    joints[:, :, 0] = np.array([0.0, 1.0, 50.0, 60.0, 4.0, 70.0])[:, None]  # 2, 3 lost; 5 the end
    reliability = np.ones((6, 16))
    reliability[[2, 3, 5]] = LOW_RELIABILITY / 2
    filled = fill_unreliable(joints, reliability)
    assert np.allclose(filled[:, 0, 0], [0.0, 1.0, 2.0, 3.0, 4.0, 70.0])


def test_a_correction_carries_to_the_frames_around_it():
    """A tracker 10 px off on frames 8-22; the user puts the ankle right on frame 15:
    the correction wins there and fades out over 0.2 s (5 frames at 25 fps) on either
    side; two corrections of a joint that near each other blend into one another."""
    tracked = np.zeros((30, 16, 2))
    ankle = JOINT_INDEX["ankle_l"]
    tracked[8:23, ankle, 0] = 10.0
    once = spread_corrections(tracked, {15: {"ankle_l": (0.0, 0.0)}}, 25.0)
    assert np.allclose(
        once[:, ankle, 0], np.r_[np.zeros(8), 10, 10, 10, 8, 6, 4, 2, 0, 2, 4, 6, 8, 10, 10, 10, np.zeros(7)]
    )
    assert np.array_equal(np.delete(once, ankle, axis=1), np.delete(tracked, ankle, axis=1))
    twice = spread_corrections(
        tracked, {15: {"ankle_l": (0.0, 0.0)}, 22: {"ankle_l": (4.0, 0.0)}, 3: {"knee_l": (1.0, 2.0)}}, 25.0
    )
    assert np.allclose(twice[15:23, ankle, 0], np.linspace(0.0, 4.0, 8))
    assert np.allclose(twice[23:28, ankle, 0], [-4.8, -3.6, -2.4, -1.2, 0])
    assert np.allclose(twice[3, JOINT_INDEX["knee_l"]], [1.0, 2.0])
    alone = spread_corrections(tracked, {15: {"ankle_l": (0.0, 0.0)}}, 25.0, spread_s=0.0)
    assert np.flatnonzero(alone[:, ankle, 0] != tracked[:, ankle, 0]).tolist() == [15]


def test_a_corrected_arm_moves_with_its_shoulder():
    """The body walks right 2 px a frame, bobbing; the tracker lost the left arm to
    clutter that stands still. The user pins the elbow and the wrist, hanging from the shoulder, on
    frames 12 and 17: between the pins (0.2 s at 25 fps) the arm hangs from the moving
    shoulder as pinned, not where the clutter is, and it fades back to the tracked
    arm beyond them. A pin where the tracker was (the marks) carries nothing."""
    j = JOINT_INDEX
    tracked = np.zeros((30, 16, 2))
    tracked[:, :, 0] = 2.0 * np.arange(30)[:, None]
    tracked[:, :, 1] = 4.0 * np.sin(np.arange(30))[:, None]
    tracked[:, [j["elbow_l"], j["wrist_l"]]] = (300.0, 50.0)
    hanging = {"elbow_l": (0.0, 30.0), "wrist_l": (5.0, 55.0)}
    pins = {
        f: {name: tuple(tracked[f, j["shoulder_l"]] + (dx, dy)) for name, (dx, dy) in hanging.items()} for f in (12, 17)
    }
    spread = spread_corrections(tracked, pins, 25.0)
    for name, (dx, dy) in hanging.items():
        assert np.allclose(spread[12:18, j[name]], tracked[12:18, j["shoulder_l"]] + (dx, dy))
        assert np.allclose(spread[23:, j[name]], tracked[23:, j[name]])
    assert np.array_equal(spread[:, j["shoulder_l"]], tracked[:, j["shoulder_l"]])
    where_tracked = {0: {"wrist_l": tuple(tracked[0, j["wrist_l"]])}}  # the marks
    assert np.array_equal(spread_corrections(tracked, where_tracked, 25.0), tracked)


def test_the_frames_a_pin_moves_are_the_ones_it_is_said_to_move():
    """carried_pins names a pin on exactly the frames spread_corrections moves (and not
    on the pinned frame itself), also where two pins' stretches meet."""
    tracked = np.zeros((40, 16, 2))
    for gap in (9, 10, 11):  # 2 x 5 frames of fade at 25 fps
        pins = {10: {"knee_r": (3.0, 0.0)}, 10 + gap: {"knee_r": (0.0, 4.0)}}
        moved = spread_corrections(tracked, pins, 25.0)[:, JOINT_INDEX["knee_r"]].any(axis=1)
        said = [bool(carried_pins(pins, f, 25.0)) or f in pins for f in range(40)]
        assert moved.tolist() == said, gap
    assert carried_pins({0: {"neck": (1.0, 1.0)}}, 1, 25.0) == {}  # the marks


def test_joint_reliability_follows_the_parts_that_placed_it():
    s = np.ones((5, 10)) * 0.2
    s[0] = np.inf  # the marked frame
    s[2, 3] = 0.05  # lower_arm_l matched 4x worse
    r = joint_reliability(s)
    assert np.all(r[0] == 1.0)
    assert r[2, JOINT_INDEX["wrist_l"]] == pytest.approx(0.25)
    assert r[2, JOINT_INDEX["elbow_l"]] == pytest.approx(0.25)
    assert r[2, JOINT_INDEX["wrist_r"]] == 1.0


# -- whole clips ---------------------------------------------------------------------------


def test_tracking_a_rendered_walk_on_a_moving_background(walk):
    video, truth = walk
    done = []
    result = track_clip(video, truth.joints2d[0], lambda d, t: done.append((d, t)), orientation="forward_right")
    n = len(truth.joints2d)
    assert result.joints2d.shape == (n, 16, 2) and result.reliability.shape == (n, 16)
    assert result.joints3d.shape == (n, 16, 3) and np.isfinite(result.joints3d).all()
    assert done[-1] == (n, n) and result.focal_px == 320.0
    err = np.linalg.norm(result.joints2d - truth.joints2d, axis=-1) / truth.body_height_px
    assert np.median(err) < 0.03
    trunk = [JOINT_INDEX[j] for j in ("head_top", "neck", "chest", "pelvis")]
    assert err[:, trunk].max() < 0.05


@pytest.mark.parametrize("shape", ["slim", "broad"])
def test_a_slim_or_broad_body_is_tracked(shape, tmp_path):
    """The walk of ``walk`` with the body slimmer or broader than the model's
    cylinders (synth.SHAPES), tracked with blocks of the model's widths: its joints
    stay on it (a slim body: median 0.8%, 90% within 3.1% of its height; a broad
    one 1.6% and 6.0%, its pelvis sliding up to 10% up the trunk over the last
    frames)."""
    video = tmp_path / f"{shape}.mp4"
    truth = render_tracked_walk(video, shape=shape)
    result = track_clip(video, truth.joints2d[0], orientation="forward_right")
    err = np.linalg.norm(result.joints2d - truth.joints2d, axis=-1) / truth.body_height_px
    trunk = [JOINT_INDEX[j] for j in ("head_top", "neck", "chest", "pelvis")]
    assert np.median(err) < 0.025 and np.percentile(err, 90) < 0.08
    assert err[:, trunk].max() < 0.12 and not result.lost.any()


def test_the_head_is_kept_where_the_image_difference_points_it_wrong(tmp_path):
    """A walk seen from the side over a panning background: on frame 1 the image
    difference sends the head's start onto the shirt, where it matches as badly as
    at the last place; searched from both, the head stays on the head (lost before:
    1.8 body heights off by the end, the whole body with it)."""
    truth = synth.render_clip(
        walk_cycle(2.0, 15.0),
        tmp_path / "side.mp4",
        size=(320, 240),
        fps=15.0,
        yaw=0.0,
        perspective=400.0,
        moving_background=True,
        seed=3,
    )
    result = track_clip(tmp_path / "side.mp4", truth.joints2d[0])
    err = np.linalg.norm(result.joints2d - truth.joints2d, axis=-1) / truth.body_height_px
    head = [JOINT_INDEX[j] for j in ("head_top", "neck")]
    assert err[:, head].max() < 0.03 and np.median(err) < 0.03


def test_track_video_refuses_bad_marks_before_tracking(walk):
    video, truth = walk
    marks = truth.joints2d[0].copy()
    marks[JOINT_INDEX["hip_r"]] = (400.0, 10.0)
    with pytest.raises(MocapError, match="hip_r"):
        track_clip(video, marks)
    with pytest.raises(MocapError, match="orientation"):
        track_clip(video, truth.joints2d[0], orientation="upside_down")
