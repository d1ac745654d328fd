"""Perspective reconstruction (tracking paper, Eq. 6-11): calibration from exact
projections, the key joints of later frames, joints on their rays, and whole clips
reconstructed from exact projections of the model's own walk."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from mocap.body import JOINT_INDEX, SEGMENT_INDEX
from mocap.camera import Pinhole, default_camera
from mocap.errors import MocapError
from mocap.synth import RenderOptions, plan_scene, scene_truth
from mocap.synth.metrics import pa_mpjpe
from mocap.synth.walk import walk_cycle
from mocap.track import calibration as C
from mocap.track import keydepths as K
from mocap.track import perspective as P
from mocap.track.marks import shoulders_as_hips, turned_apart
from mocap.track.rays import choose_limb, ray_roots

CAMERA = Pinhole(800.0, 320.0, 240.0)


def known_pose(yaw_deg: float, span: float = 0.36, chest: float = C.MODEL[C.KEY[2], 1]) -> C.Calibration:
    """A body turned by ``yaw_deg`` (and slightly tilted), 6 m in front of CAMERA."""
    turn = Rotation.from_euler("y", np.radians(yaw_deg)) * Rotation.from_euler("x", 0.05)
    rotation = Rotation.from_matrix(C.FACING_CAMERA) * turn
    return C.Calibration(rotation.as_rotvec(), np.array([0.4, -0.3, 6.0]), span, chest)


@pytest.mark.parametrize("yaw, span, chest", [(35.0, 0.36, 0.31), (-50.0, 0.30, 0.27), (20.0, 0.42, 0.34)])
def test_calibration_recovers_a_known_camera(yaw, span, chest):
    """The pose, the shoulder span and the chest's height of a trunk seen exactly."""
    truth = known_pose(yaw, span, chest)
    marks = CAMERA.project(truth.to_camera(truth.model()))
    found = C.calibrate(marks, CAMERA, "right" if yaw > 0 else "left")
    turn = Rotation.from_rotvec(found.rotvec).inv() * Rotation.from_rotvec(truth.rotvec)
    assert np.degrees(turn.magnitude()) < 1e-3
    assert np.abs(found.translation - truth.translation).max() < 1e-4
    assert found.span == pytest.approx(span, abs=1e-5)
    assert found.chest == pytest.approx(chest, abs=1e-5)
    assert found.yaw == pytest.approx(yaw, abs=0.2)  # the slight tilt moves it a little
    assert np.abs(C.line_distances(found.params, CAMERA, marks)).max() < 1e-6


def test_the_key_triangle_keeps_the_marked_chest():
    """A trunk whose chest sits lower than the model's (0.63 of the shoulders' height,
    as in the shared motion capture, against the model's 0.68): the calibration
    finds its chest, and so the key triangle that later frames keep (Eq. 10-11) is
    the marked body's; held at the model's chest, its sides from the shoulders to
    the chest come out more than 5% short."""
    truth = known_pose(30.0, 0.30, 0.63 * C.MODEL[C.KEY[0], 1])
    marks = CAMERA.project(truth.to_camera(truth.model()))
    sides = truth.key_triangle()[1]
    found = C.calibrate(marks, CAMERA, "right")
    held = C.calibrate(marks, CAMERA, "right", chest=C.MODEL[C.KEY[2], 1])
    assert found.yaw == pytest.approx(30.0, abs=0.3)
    assert np.allclose(found.key_triangle()[1], sides, atol=1e-4)
    assert (held.key_triangle()[1][1:] < 0.95 * sides[1:]).all()


def test_the_turn_picks_between_the_two_fits():
    truth = known_pose(40.0)
    marks = CAMERA.project(truth.to_camera(truth.model()))
    assert C.calibrate(marks, CAMERA, "right").yaw > 0
    assert C.calibrate(marks, CAMERA, "left").yaw < 0


@pytest.mark.parametrize("apart_px", [2.0, 3.0])
def test_a_body_seen_nearly_from_the_side_calibrates_despite_marks_a_few_pixels_off(apart_px):
    """10 degrees from profile, shoulders marked 2-3 px farther apart than the
    model's: the free fit's span leaves its range (0.54-0.66 m), the fit with the
    span held at the range's end finds the turn."""
    truth = known_pose(80.0)
    marks = CAMERA.project(truth.to_camera(truth.model()))
    marks[JOINT_INDEX["shoulder_l"], 0] += apart_px
    marks[JOINT_INDEX["shoulder_r"], 0] -= apart_px
    found = C.calibrate(marks, CAMERA, "right")
    assert found.span in C.SPAN_RANGE and found.yaw == pytest.approx(80.0, abs=7.0)


def test_marks_that_fit_no_view_are_refused():
    truth = known_pose(30.0)
    marks = CAMERA.project(truth.to_camera(truth.model()))
    marks[JOINT_INDEX["chest"]] += (60.0, 0.0)  # the chest beside the body
    with pytest.raises(MocapError, match="cannot calibrate"):
        C.calibrate(marks, CAMERA)


@pytest.mark.parametrize("yaw", [60.0, -120.0])
def test_shoulders_marked_against_the_hips_are_refused_with_the_fix(yaw):
    truth = known_pose(yaw)
    marks = CAMERA.project(truth.to_camera(truth.model()))
    assert not turned_apart(marks) and shoulders_as_hips(marks) is marks
    pair = [JOINT_INDEX["shoulder_l"], JOINT_INDEX["shoulder_r"]]
    swapped = marks.copy()
    swapped[pair] = marks[pair[::-1]]
    assert turned_apart(swapped)
    with pytest.raises(MocapError, match="turned opposite ways: swap shoulder_l and shoulder_r"):
        C.calibrate(swapped, CAMERA)
    assert np.array_equal(shoulders_as_hips(swapped), marks)
    assert C.calibrate(shoulders_as_hips(swapped), CAMERA, "right" if yaw > 0 else "left").yaw == pytest.approx(
        yaw, abs=0.2
    )


def test_key_depths_follow_the_moving_triangle():
    """Eq. 10-11: from the previous depths to the new frame's, sides kept."""
    before, after = known_pose(30.0), known_pose(38.0)
    triangle = before.model()[C.KEY]
    sides = [np.linalg.norm(triangle[i] - triangle[j]) for i, j in C.KEY_LINES]
    moved = after.to_camera(triangle) + [0.05, 0.0, -0.1]
    rays = CAMERA.rays(CAMERA.project(moved))
    depths = K.key_depths(rays, before.to_camera(triangle)[:, 2], np.array(sides))
    assert np.allclose(depths, moved[:, 2], atol=1e-7)


def test_key_joints_solve_again_only_the_frames_that_moved(monkeypatch):
    """After a joint override the key joints equal a full solve, with only the
    moved frames solved again."""
    scene = plan_scene(walk_cycle(1.2, 30.0), RenderOptions(size=(320, 240), perspective=400.0, yaw=50.0))
    joints2d = scene_truth(scene, "walk", np.arange(len(scene.joints_cam))).joints2d
    camera = default_camera(320, 240)
    first = K.key_joints(joints2d, camera, "right")
    moved = joints2d.copy()
    moved[12:15, JOINT_INDEX["chest"]] += [3.0, -2.0]
    calls, solve = [], K.key_depths
    monkeypatch.setattr(K, "key_depths", lambda *args: calls.append(1) or solve(*args))
    again = K.key_joints(moved, camera, "right", before=(joints2d, first))
    assert len(calls) == 3
    assert np.allclose(again, K.key_joints(moved, camera, "right"), atol=1e-6)
    assert np.array_equal(again[:12], first[:12])


def test_key_joints_followed_turned_the_wrong_way_are_turned_back_by_the_limbs():
    """The model's walk seen from yaw 50: its key joints followed on the wrong side
    (every frame's mirror image, turned about -40 degrees instead of 40) come back on
    every frame, where the knees and elbows bend the way they can."""
    scene = plan_scene(walk_cycle(1.2, 30.0), RenderOptions(size=(320, 240), perspective=400.0, yaw=50.0))
    joints2d = scene_truth(scene, "walk", np.arange(len(scene.joints_cam))).joints2d
    camera = default_camera(320, 240)
    right = K.key_joints(joints2d, camera, "right")
    wrong = K.mirror_images(right)
    assert (K.triangle_yaw(wrong) < -25.0).all() and (K.triangle_yaw(right) > 25.0).all()
    assert np.allclose(P.sided_key(joints2d, wrong, camera), right, atol=1e-6)
    assert np.allclose(P.sided_key(joints2d, right, camera), right)


def turning_trunk(yaws: np.ndarray, span: float) -> tuple[np.ndarray, np.ndarray]:
    """Rays (F, 3, 3) of the key joints of known_pose turning through ``yaws``, and
    the key triangle's sides with a shoulder span ``span``."""
    poses = [known_pose(yaw) for yaw in yaws]
    rays = np.array([CAMERA.rays(CAMERA.project(p.to_camera(p.model()[C.KEY]))) for p in poses])
    triangle = known_pose(0.0, span).model()[C.KEY]
    return rays, np.array([np.linalg.norm(triangle[i] - triangle[j]) for i, j in C.KEY_LINES])


def followed_yaws(rays: np.ndarray, sides: np.ndarray, depths: np.ndarray, turns) -> np.ndarray:
    """The key triangle's yaw on each frame, chained by frame_key_depths."""
    out = []
    for frame_rays, turn in zip(rays, turns):
        depths = K.frame_key_depths(frame_rays, depths, sides, turn)
        out.append(float(K.triangle_yaw(depths[:, None] * frame_rays)))
    return np.array(out)


def test_a_trunk_turning_through_the_frontal_view_follows_the_held_side():
    """A trunk turning from 40 degrees right to 60 left, its key triangle's sides 7%
    long (as a calibration from real bodies reads them): the solution nearest the
    last frame turns back near the frontal view; with the user's held orientation
    (right, then left from the frame it faces the camera) it turns on."""
    yaws = np.linspace(40.0, -60.0, 26)
    rays, sides = turning_trunk(yaws, 0.36 * 1.07)
    start = known_pose(yaws[0]).to_camera(known_pose(yaws[0]).model()[C.KEY])[:, 2]
    alone = followed_yaws(rays, sides, start, [None] * len(yaws))
    assert alone[-1] > 40.0  # turned back
    held = followed_yaws(rays, sides, start, ["right" if y > 0 else "left" for y in yaws])
    clear = np.abs(yaws) > 20.0
    assert np.array_equal(np.sign(held[clear]), np.sign(yaws[clear]))
    assert np.abs(held - yaws)[yaws < -20.0].max() < 10.0  # the long sides read more turn
    assert np.allclose(followed_yaws(rays, sides, start, ["right"] * len(yaws)), alone)


def test_the_triangle_yaw_is_the_calibrations():
    for yaw in (35.0, -50.0, 120.0):
        pose = known_pose(yaw)
        assert K.triangle_yaw(pose.to_camera(pose.model()[C.KEY])) == pytest.approx(pose.yaw, abs=0.5)


def test_ray_roots_lie_on_the_ray_at_the_bone_length():
    known, ray = np.array([0.1, -0.2, 5.0]), np.array([0.05, 0.01, 1.0])
    roots = ray_roots(known, ray, 0.4)
    assert np.allclose(np.linalg.norm(roots - known, axis=-1), 0.4)
    assert np.allclose(np.cross(roots, ray), 0.0, atol=1e-12)
    assert roots[0, 2] < roots[1, 2]
    miss = ray_roots(known, ray, 0.01)  # the ray passes farther away
    assert np.allclose(miss[0], miss[1])
    assert np.allclose(np.cross(miss[0] - known, ray) @ ray, 0.0)


def test_the_limb_choice_goes_on_through_the_image_plane():
    """A bone swinging through the image plane: its two roots meet there; the
    smallest-acceleration path keeps swinging instead of turning back."""
    t = np.linspace(0.0, 1.0, 30)
    true = np.stack([np.full_like(t, 0.2), -0.4 * np.ones_like(t), 0.5 * (t - 0.45)], axis=1)
    mirror = true * [1.0, 1.0, -1.0]
    cands = np.stack([true, mirror, true, mirror], axis=1)[:, :, None, :].repeat(2, axis=2)
    picked = choose_limb(cands, np.zeros((len(t), 4)))
    assert np.allclose(cands[np.arange(len(t)), picked, 0], true)


@pytest.mark.parametrize(
    "yaw, bound_mm, pulled_mm",
    [(30.0, 4.0, 7.0), (60.0, 4.0, 10.0), (120.0, 3.0, 10.0), (140.0, 2.5, 7.0), (20.0, 7.0, 8.0), (40.0, 5.5, 8.0)],
)
def test_exact_projections_of_the_models_walk_are_reconstructed(yaw, bound_mm, pulled_mm, monkeypatch):
    """The walk of the model's own proportions seen at its true bone lengths. The
    joint limits (limbs near the sagittal plane) tell a leg from its mirror image
    (without them: 10-48 mm at 20, 30, 40 and 140 degrees). They come before
    smoothness (rays.LIMIT_WEIGHT), which real tracked motion needs; on this
    synthetic walk they take the mirror image of a nearly straight arm swinging out
    of the sagittal plane on a few frames (3.5 mm at 30 and 60 degrees; 0.5 and 0.0 mm
    with smoothness first). The pull toward the limbs' swing planes, made for tracked
    2D, costs exact 2D a few millimetres: this walk's limbs swing a little out of
    their planes (5.3 to 8.2 mm with the pull). At 120 degrees 2.6 mm since the camera
    frames the feet too (a little farther off)."""
    scene = plan_scene(walk_cycle(1.2, 30.0), RenderOptions(size=(320, 240), perspective=400.0, yaw=yaw))
    truth = scene_truth(scene, "walk-cycle", np.arange(len(scene.joints_cam)))
    camera = Pinhole(truth.camera.scale, truth.camera.cx, truth.camera.cy)
    turn = "right" if yaw < 90 else "left"
    monkeypatch.setattr(P, "GUIDE", C.MODEL)  # the model walk's head is upright
    pulled = P.reconstruct(truth.joints2d, camera, turn, P.bone_lengths(truth.joints3d[0]))
    monkeypatch.setattr(P, "SWING_PLANE_WEIGHT", {False: 0.0, True: 0.0})
    found = P.reconstruct(truth.joints2d, camera, turn, P.bone_lengths(truth.joints3d[0]))
    trunk = [
        JOINT_INDEX[j] for j in ("head_top", "neck", "chest", "pelvis", "shoulder_l", "shoulder_r", "hip_l", "hip_r")
    ]
    assert np.abs(found[:, trunk] - scene.joints_cam[:, trunk] * [1, -1, -1]).max() < 1e-6
    assert pa_mpjpe(P.to_contract(found), truth.joints3d) * 1000 < bound_mm
    assert pa_mpjpe(P.to_contract(pulled), truth.joints3d) * 1000 < pulled_mm
    assert np.allclose(P.to_contract(found)[:, JOINT_INDEX["pelvis"]], 0.0)
    assert np.allclose(camera.project(pulled), truth.joints2d)


@pytest.mark.parametrize("yaw", [0.0, 30.0, -60.0, 150.0, 180.0])
def test_a_head_leaning_forward_is_rebuilt_leaning_forward(yaw, monkeypatch):
    """Heads lean forward of the neck (the neck joint at the back of the neck): a head
    leant 25 degrees, seen from the front, turned or from behind, is rebuilt from its
    exact 2D leaning forward; the model's upright head as the guide takes the root
    leaning back, a decimetre off, where the body faces the camera."""
    pose = known_pose(yaw)
    body = pose.model()
    neck, top = JOINT_INDEX["neck"], JOINT_INDEX["head_top"]
    body[top] = body[neck] + 0.22 * np.array([0.0, np.cos(np.radians(25.0)), np.sin(np.radians(25.0))])
    true = pose.to_camera(body)[None]
    rays = CAMERA.rays(CAMERA.project(true))
    lengths = P.bone_lengths(true)[0]
    found = P.trunk_joints(true[:, C.KEY], rays, lengths)
    assert np.linalg.norm(found[0, top] - true[0, top]) < 1e-6
    monkeypatch.setattr(P, "GUIDE", C.MODEL)
    upright = P.trunk_joints(true[:, C.KEY], rays, lengths)
    if abs(yaw) <= 30.0:
        assert np.linalg.norm(upright[0, top] - true[0, top]) > 0.1


def swing_case(yaw: float, pixel_error: float, across: bool = False) -> tuple:
    """A body turned ``yaw`` degrees (known_pose) whose left thigh swings 0.6 rad
    forward and whose knee is seen ``pixel_error`` px off along the thigh's image
    (or ``across`` it):
    (joints as the ray-sphere root places them, rays, lengths, the true knee)."""
    pose = known_pose(yaw)
    body = pose.model()
    hip, knee = JOINT_INDEX["hip_l"], JOINT_INDEX["knee_l"]
    body[knee] = body[hip] + np.array([0.0, -np.cos(0.6), np.sin(0.6)]) * 0.45  # z forward
    true = pose.to_camera(body)
    seen = CAMERA.project(true)
    along = (seen[knee] - seen[hip]) / np.linalg.norm(seen[knee] - seen[hip])
    seen[knee] += pixel_error * (np.array([-along[1], along[0]]) if across else along)
    rays = CAMERA.rays(seen)[None]
    lengths = np.full(len(P.BONES), 0.45)
    roots = ray_roots(true[hip], rays[0, knee], lengths[0])
    placed = true[None].copy()
    placed[0, knee] = roots[np.argmin(np.abs(roots[:, 2] - true[knee, 2]))]
    return placed, rays, lengths, true[knee]


def test_a_knee_near_the_image_plane_is_pulled_toward_its_swing_plane():
    """A thigh swung forward in its sagittal plane, nearly square to the line of sight
    (the body turned 45 degrees): 3 px of 2D error move the ray-sphere root by over
    a decimetre in depth; the pull toward the plane takes off half of that. It moves
    the knee along its ray only, and not where the user fixed the thigh's
    foreshortening."""
    knee = JOINT_INDEX["knee_l"]
    placed, rays, lengths, true = swing_case(45.0, 3.0)
    pulled = P.toward_swing_planes(placed.copy(), rays, lengths)
    before, after = (np.linalg.norm(j[0, knee] - true) for j in (placed, pulled))
    assert before > 0.1 and after < 0.6 * before
    assert np.allclose(CAMERA.project(pulled[0, knee]), CAMERA.project(placed[0, knee]))
    fixed = np.zeros((1, 10), int)
    fixed[0, SEGMENT_INDEX["upper_leg_l"]] = -1
    kept = P.toward_swing_planes(placed.copy(), rays, lengths, fixed)
    assert np.allclose(kept[0, knee], placed[0, knee])


def test_a_body_facing_the_camera_sees_its_swing_planes_edge_on():
    """Facing the camera, a knee's ray runs nearly in its swing plane: seen a few
    pixels beside the plane, the ray meets it far away, off the thigh's length, and
    the knee keeps its ray-sphere root."""
    knee = JOINT_INDEX["knee_l"]
    placed, rays, lengths, true = swing_case(0.0, 3.0, across=True)
    pulled = P.toward_swing_planes(placed.copy(), rays, lengths)
    assert np.linalg.norm(pulled[0, knee] - placed[0, knee]) < 0.01


def test_measured_lengths_read_bones_seen_side_on():
    scene = plan_scene(walk_cycle(1.2, 30.0), RenderOptions(size=(320, 240), perspective=400.0, yaw=90.0))
    truth = scene_truth(scene, "walk-cycle", np.arange(len(scene.joints_cam)))
    camera = Pinhole(truth.camera.scale, truth.camera.cx, truth.camera.cy)
    depth = -truth.pelvis_camera[:, 2]
    found = P.measured_lengths(truth.joints2d, depth, camera)
    true = P.bone_lengths(truth.joints3d[0])
    trunk = [P.BONE_INDEX[JOINT_INDEX["chest"], JOINT_INDEX["pelvis"]]]
    assert found[trunk] == pytest.approx(true[trunk], rel=0.05)
    assert np.all(found <= true * 1.05)


def forearms_forward_2d(forward: int, hanging: int) -> np.ndarray:
    """(forward + hanging, 16, 2) the model 5 m in front of CAMERA facing it, its
    forearms held forward (foreshortened to a third) on ``forward`` frames and hanging
    on ``hanging`` more."""
    held = C.MODEL.copy()
    for side in ("l", "r"):
        elbow, wrist = JOINT_INDEX[f"elbow_{side}"], JOINT_INDEX[f"wrist_{side}"]
        length = np.linalg.norm(C.MODEL[wrist] - C.MODEL[elbow])
        held[wrist] = C.MODEL[elbow] + length * np.array([0.0, -np.sin(0.35), np.cos(0.35)])
    pose = C.Calibration(Rotation.from_matrix(C.FACING_CAMERA).as_rotvec(), np.array([0.0, 0.0, 5.0]), 0.36)
    return CAMERA.project(pose.to_camera(np.array([held] * forward + [C.MODEL] * hanging)))


def test_forearms_foreshortened_more_often_than_not_measure_their_length():
    """The forearms held forward on six frames of eleven and hanging on the rest
    measure their length (their 60th percentile), not what the median frame shows."""
    found = P.measured_lengths(forearms_forward_2d(6, 5), np.full(11, 5.0), CAMERA)
    forearms = [fore for _, fore in P.ARM_BONES]
    assert found[forearms] == pytest.approx(P.bone_lengths(C.MODEL)[forearms], rel=0.02)


def test_forearms_never_seen_at_their_length_measure_their_least_share_of_the_upper_arm():
    """The forearms held forward on every frame each read FOREARM_PER_UPPER_ARM of
    their upper arm, not the third they show."""
    found = P.measured_lengths(forearms_forward_2d(3, 0), np.full(3, 5.0), CAMERA)
    for upper, fore in P.ARM_BONES:
        assert found[fore] == pytest.approx(P.FOREARM_PER_UPPER_ARM * found[upper])
        assert found[upper] == pytest.approx(P.bone_lengths(C.MODEL)[upper], rel=1e-3)


def test_frames_where_the_body_was_lost_measure_no_bones():
    """The walk seen side-on, the blocks of a third of its frames left on clutter (the
    joints there spread to twice their distance from the pelvis): the bones measured
    over the frames seen are those of the walk alone; over every frame, longer."""
    scene = plan_scene(walk_cycle(1.2, 30.0), RenderOptions(size=(320, 240), perspective=400.0, yaw=90.0))
    truth = scene_truth(scene, "walk-cycle", np.arange(len(scene.joints_cam)))
    camera = Pinhole(truth.camera.scale, truth.camera.cx, truth.camera.cy)
    depth = -truth.pelvis_camera[:, 2]
    seen = np.arange(len(depth)) % 3 != 0
    tracked = truth.joints2d.copy()
    pelvis = tracked[~seen, JOINT_INDEX["pelvis"], None]
    tracked[~seen] = pelvis + 2.0 * (tracked[~seen] - pelvis)
    walk = P.measured_lengths(truth.joints2d[seen], depth[seen], camera)
    assert np.allclose(P.measured_lengths(tracked, depth, camera, seen), walk)
    shins = list(P.BONE_PAIRS[-1])
    assert np.all(P.measured_lengths(tracked, depth, camera)[shins] > 1.05 * walk[shins])


def test_steady_depths_keep_joints_on_their_rays_and_take_out_jitter():
    n, fps = 60, 30.0
    depth = -4.0 + 0.01 * np.arange(n)  # walking away slowly
    jitter = 0.05 * (-1.0) ** np.arange(n)  # the ray roots' frame-to-frame noise
    points = np.zeros((n, 16, 3))
    points[..., 0], points[..., 1] = 0.3, -0.2
    points[..., 2] = (depth + jitter)[:, None]
    points[..., :2] *= -points[..., 2:] / 4.0  # on fixed rays through the centre
    out = P.steady_depths(points, fps)
    rays = points / np.linalg.norm(points, axis=-1, keepdims=True)
    assert np.allclose(np.cross(out, rays), 0.0, atol=1e-12)
    inner = slice(10, -10)
    assert np.abs(out[inner, 0, 2] - depth[inner]).max() < 0.1 * np.abs(jitter).max()
