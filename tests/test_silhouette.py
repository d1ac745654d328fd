"""Background estimation and silhouette extraction: synthetic scenes with known truth,
and the real dog_walker clip (skipped when ../shared/data is absent)."""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from helpers import DOG_WALKER

from mocap.errors import MocapError
from mocap.io.video import iter_frames, open_video
from mocap.silhouette import background as background_module
from mocap.silhouette.background import estimate_background, exposure_gain, extract_silhouette
from mocap.silhouette.cleaning import clean_mask

EXPOSURE = {4: 1.3, 9: 0.75}  # frame index -> global exposure factor of that frame


def synthetic_scene(height: int = 240, width: int = 320, n: int = 14, seed: int = 0):
    """A textured static background, a coloured stick figure walking across it with a
    soft shadow (background darkened to 0.6, same hue) beside its feet, exposure
    jumps on the frames of EXPOSURE, sensor noise.

    Returns (background, frames, figure masks, shadow masks) as uint8 arrays.
    """
    rng = np.random.default_rng(seed)
    background = _texture(height, width, rng)
    frames, figures, shadows = [], [], []
    for i, t in enumerate(np.linspace(0.0, 1.0, n)):
        figure, colour = _figure(height, width, t)
        darkening = _shadow(height, width, t)
        frame = background * (1.0 - 0.4 * darkening)[..., None]
        frame[figure > 0] = colour[figure > 0]
        frame = frame * EXPOSURE.get(i, 1.0) + rng.normal(0.0, 2.0, frame.shape)
        frames.append(np.clip(frame + 0.5, 0, 255).astype(np.uint8))
        figures.append(figure)
        shadows.append(((darkening > 0.5) & (figure == 0)).astype(np.uint8) * 255)
    return np.clip(background + 0.5, 0, 255).astype(np.uint8), frames, figures, shadows


def _texture(height: int, width: int, rng: np.random.Generator) -> np.ndarray:
    coarse = rng.uniform(50, 200, (height // 16 + 1, width // 16 + 1, 3)).astype(np.float32)
    image = cv2.resize(coarse, (width, height), interpolation=cv2.INTER_CUBIC)
    image += rng.normal(0.0, 10.0, image.shape).astype(np.float32)
    for _ in range(10):
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        size = rng.integers(8, width // 5, 2)
        cv2.rectangle(image, (x, y), (x + int(size[0]), y + int(size[1])), rng.uniform(40, 210, 3).tolist(), -1)
    return np.clip(image, 10, 240)


def _joints(height: int, width: int, t: float) -> dict[str, tuple[int, int]]:
    s = height / 240
    x, top, swing = width * (0.08 + 0.84 * t), 30 * s, np.sin(t * 9) * 20 * s
    return {
        name: (int(x + dx), int(top + dy * s))
        for name, (dx, dy) in {
            "head": (0, 12),
            "neck": (0, 25),
            "hip": (0, 100),
            "shoulder": (0, 35),
            "foot_a": (swing, 185),
            "foot_b": (-swing, 185),
            "hand_a": (-swing - 24 * s, 95),
            "hand_b": (swing + 24 * s, 95),
        }.items()
    }


def _figure(height: int, width: int, t: float) -> tuple[np.ndarray, np.ndarray]:
    """Mask and colour image of the stick figure (skin head, red shirt, blue legs,
    green arms)."""
    j, s = _joints(height, width, t), height / 240
    mask = np.zeros((height, width), np.uint8)
    colour = np.zeros((height, width, 3), np.float32)
    parts = [
        ("circle", j["head"], None, int(11 * s), (140, 170, 230)),
        ("line", j["neck"], j["hip"], int(30 * s), (40, 40, 200)),
        ("line", j["hip"], j["foot_a"], int(14 * s), (150, 70, 20)),
        ("line", j["hip"], j["foot_b"], int(14 * s), (150, 70, 20)),
        ("line", j["shoulder"], j["hand_a"], int(8 * s), (60, 180, 60)),
        ("line", j["shoulder"], j["hand_b"], int(8 * s), (60, 180, 60)),
    ]
    for kind, p, q, size, bgr in parts:
        for image, value in ((mask, 255), (colour, bgr)):
            if kind == "circle":
                cv2.circle(image, p, size, value, -1)
            else:
                cv2.line(image, p, q, value, size)
    return mask, colour


def _shadow(height: int, width: int, t: float) -> np.ndarray:
    """Soft darkening weight in [0, 1], a blurred ellipse on the ground beside the feet."""
    j, s = _joints(height, width, t), height / 240
    weight = np.zeros((height, width), np.float32)
    centre = (j["hip"][0] + int(30 * s), j["foot_a"][1])
    cv2.ellipse(weight, centre, (int(26 * s), int(8 * s)), 0, 0, 360, 1.0, -1)
    return cv2.GaussianBlur(weight, (0, 0), 2.0 * s)


def iou(a: np.ndarray, b: np.ndarray) -> float:
    a, b = a > 0, b > 0
    return float((a & b).sum() / max((a | b).sum(), 1))


@pytest.fixture(scope="module")
def scene():
    background, frames, figures, shadows = synthetic_scene()
    model = estimate_background(frames)
    masks = [extract_silhouette(f, model) for f in frames]
    return background, frames, figures, shadows, model, masks


def test_background_is_the_empty_scene(scene):
    background, _, _, _, model, _ = scene
    error = cv2.absdiff(model.image, background)
    assert np.median(error) <= 2 and np.percentile(error, 99) <= 10


def test_silhouette_matches_the_figure_on_every_frame(scene):
    _, _, figures, _, _, masks = scene
    scores = [iou(m, f) for m, f in zip(masks, figures)]
    assert min(scores) > 0.9, scores


def test_exposure_jump_does_not_flood_the_frame(scene):
    _, frames, figures, _, model, masks = scene
    for i in EXPOSURE:
        assert iou(masks[i], figures[i]) > 0.9
        naive = cv2.absdiff(frames[i], model.image).max(axis=2) > model.threshold
        assert naive.mean() > 0.3  # the jump is real: without compensation it floods


def test_soft_shadow_is_not_person(scene):
    _, frames, _, shadows, model, masks = scene
    for frame, shadow, mask in zip(frames, shadows, masks):
        same_exposure = cv2.transform(frame, np.diag(exposure_gain(frame, model.image)))
        naive = cv2.absdiff(same_exposure, model.image).max(axis=2) > model.threshold
        assert naive[shadow > 0].mean() > 0.5  # a plain difference would take it
        assert (mask[shadow > 0] > 0).mean() < 0.05


def _bricks(height: int = 240, width: int = 320) -> np.ndarray:
    """A grey brick wall: flat bricks (grey 130..150) between light mortar lines."""
    rng = np.random.default_rng(1)
    wall = np.full((height, width, 3), 215, np.uint8)
    for top in range(0, height, 30):
        shift = 30 if top % 60 else 0
        for left in range(-shift, width, 60):
            grey = int(rng.integers(130, 150))
            cv2.rectangle(wall, (left + 2, top + 2), (left + 57, top + 27), (grey, grey, grey), -1)
    return wall


def test_grey_trousers_over_bricks_are_not_shadow_and_a_shadow_is():
    """Grey cloth as dark as a shadow, of the wall's own grey, over flat bricks passes
    every pixel test of a shadow; the mortar lines it hides tell them apart (bricks wider than the legs)."""
    legs, shadow, mask = _legs_and_shadow(_bricks(), 2, lambda cloth: np.full_like(cloth, 80), 0.6)
    assert iou(mask, legs) > 0.9  # the cloth about 0.55 as bright as the bricks
    assert (mask[shadow > 0] > 0).mean() < 0.05


def test_grey_trousers_the_mortar_shows_through_faintly_are_not_shadow():
    """The bricks' pattern showing through the cloth at a twentieth of its contrast
    (thin cloth, the codec's ringing) correlates with the wall as a shadow does, but
    a shadow keeps far more of the contrast: without that, the legs went whole."""
    legs, shadow, mask = _legs_and_shadow(_bricks(), 2, lambda cloth: 80 + (cloth - 140) * 0.05, 0.6)
    assert iou(mask, legs) > 0.9
    assert (mask[shadow > 0] > 0).mean() < 0.05


def _legs_and_shadow(scene: np.ndarray, seed: int, dress, shadow_level: float):
    """Two legs, coloured by ``dress`` (the scene's pixels under them -> theirs), and a
    shadow of ``shadow_level`` beside them, over ``scene`` (float BGR) with noise:
    (legs, shadow, the silhouette against the background of five noisy scenes)."""
    rng = np.random.default_rng(seed)
    model = estimate_background(
        [np.clip(scene + rng.normal(0, 2, scene.shape), 0, 255).astype(np.uint8) for _ in range(5)]
    )
    frame = scene.astype(np.float32)
    legs = np.zeros(scene.shape[:2], np.uint8)
    cv2.line(legs, (150, 50), (130, 200), 255, 22)
    cv2.line(legs, (150, 50), (175, 200), 255, 22)
    frame[legs > 0] = dress(frame[legs > 0])
    shadow = np.zeros_like(legs)
    cv2.ellipse(shadow, (240, 212), (50, 12), 0, 0, 360, 255, -1)
    frame[shadow > 0] *= shadow_level
    frame = np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)
    return legs, shadow, extract_silhouette(frame, model)


def test_empty_scene_gives_empty_mask(scene):
    background, _, _, _, model, _ = scene
    assert not extract_silhouette(model.image, model).any()
    rng = np.random.default_rng(5)
    noisy = np.clip(background * 1.2 + rng.normal(0, 2, background.shape), 0, 255)
    assert not extract_silhouette(noisy.astype(np.uint8), model).any()


def test_background_from_a_video_file(tmp_path):
    _, frames, figures, _ = synthetic_scene(n=10)
    path = str(tmp_path / "walk.avi")
    writer = cv2.VideoWriter(path, cv2.VideoWriter_fourcc(*"MJPG"), 25, (320, 240))
    for frame in frames:
        writer.write(frame)
    writer.release()
    info = open_video(path)
    model = estimate_background(info, n_samples=10, scale=0.5)
    assert model.image.shape == (120, 160, 3)
    for (i, frame), figure in zip(iter_frames(info, scale=0.5), figures):
        small = cv2.resize(figure, (160, 120), interpolation=cv2.INTER_AREA) > 127
        assert iou(extract_silhouette(frame, model), small) > 0.8, i


@pytest.mark.parametrize("n", [1, 2, 12, 30, 33])
def test_the_sorting_network_gives_numpys_median_and_quartile(n):
    stack = np.random.default_rng(n).integers(0, 256, (n, 37, 41, 3)).astype(np.uint8)
    assert np.array_equal(background_module._median(stack), (np.median(stack, axis=0) + 0.5).astype(np.uint8))
    assert np.allclose(background_module._quantile(stack, 0.25), np.quantile(stack, 0.25, axis=0))
    assert background_module.median_level(stack[..., 0]) == np.median(stack[..., 0])


def test_foreground_is_where_the_largest_channel_difference_exceeds_the_threshold():
    rng = np.random.default_rng(4)
    image, frame = rng.integers(0, 256, (2, 47, 61, 3)).astype(np.uint8)
    threshold = rng.integers(0, 256, (47, 61)).astype(np.uint8)
    largest = np.abs(frame.astype(int) - image).max(axis=2)
    mask = background_module.foreground(frame, background_module.Background(image, threshold, 1.0))
    assert mask.dtype == np.uint8 and np.array_equal(mask, np.where(largest > threshold, 255, 0))
    assert 0 < np.count_nonzero(mask) < mask.size


def test_no_frames_is_refused():
    with pytest.raises(MocapError, match="no frames"):
        estimate_background([])


def test_clean_mask_keeps_split_leg_and_drops_far_blobs():
    mask = np.zeros((240, 320), np.uint8)
    cv2.rectangle(mask, (150, 40), (175, 150), 255, -1)  # head and body
    cv2.rectangle(mask, (152, 154), (160, 200), 255, -1)  # a leg, 4 px below the body
    cv2.rectangle(mask, (20, 20), (28, 28), 255, -1)  # a far small blob
    cv2.rectangle(mask, (166, 120), (171, 124), 0, -1)  # a small hole
    cv2.rectangle(mask, (260, 60), (290, 90), 255, -1)  # a large piece, far away
    person = clean_mask(mask)
    assert person[180, 156] and person[122, 168]  # leg kept, hole filled
    assert not person[24, 24] and not person[75, 275]  # far pieces dropped


def test_clean_mask_drops_a_piece_apart_where_the_median_showed_the_performer():
    """A performer who stood on the spot jumps: where their feet stood, the floor
    uncovered differs from the background's guess of it, a piece apart below the
    body. The median showed the performer there (``stood``), whose parts there joined
    their body: that piece goes; an arm cut off by a gap, outside it, stays."""
    mask = np.zeros((240, 320), np.uint8)
    cv2.rectangle(mask, (150, 20), (175, 175), 255, -1)  # the body in the air
    cv2.rectangle(mask, (180, 60), (186, 120), 255, -1)  # an arm, 4 px beside it
    cv2.rectangle(mask, (145, 185), (180, 200), 255, -1)  # the floor where the feet stood
    stood = np.zeros(mask.shape, bool)
    stood[100:201, 140:179] = True
    assert clean_mask(mask)[192, 160]
    person = clean_mask(mask, stood=stood)
    assert not person[192, 160] and person[90, 183] and person[100, 160]


def test_clean_mask_keeps_large_holes_open():
    mask = np.zeros((240, 320), np.uint8)
    cv2.rectangle(mask, (100, 30), (200, 210), 255, -1)
    cv2.rectangle(mask, (130, 80), (170, 160), 0, -1)  # a gap between arm and body
    person = clean_mask(mask)
    assert not person[120, 150] and person[50, 150]


@pytest.fixture(scope="module")
def dog_walker():
    if not DOG_WALKER.exists():
        pytest.skip(f"real data absent: {DOG_WALKER}")
    info = open_video(DOG_WALKER)
    model = estimate_background(info)
    return [extract_silhouette(frame, model) for _, frame in iter_frames(info)]


def test_dog_walker_has_a_person_on_every_frame(dog_walker):
    assert len(dog_walker) == 54
    areas = np.array([cv2.countNonZero(m) for m in dog_walker])
    median = np.median(areas)
    for i, mask in enumerate(dog_walker):
        count, _, stats, _ = cv2.connectedComponentsWithStats(mask)
        largest = stats[1:, cv2.CC_STAT_AREA].max()
        x, y, w, h = stats[1:][np.argmax(stats[1:, cv2.CC_STAT_AREA]), :4]
        assert largest >= 0.95 * areas[i], f"frame {i}: not one main component"
        assert 0.6 * median <= areas[i] <= 1.5 * median, f"frame {i}: area {areas[i]}"
        assert 60 <= h <= 80, f"frame {i}: height {h}"
        assert w <= 50, f"frame {i}: width {w} (background chunk?)"


def test_dog_walker_first_frame_despite_its_exposure(dog_walker):
    first, second = (cv2.countNonZero(m) for m in dog_walker[:2])
    assert abs(first - second) <= 0.2 * second


def test_frame_of_another_size_is_a_programming_error(scene):
    model = scene[4]
    with pytest.raises(ValueError, match="does not match"):
        extract_silhouette(model.image[:100], model)
