"""The silhouette written out (mocap.silhouette.blend's cover): shadows told by their
hue, and the pixels where body and scene blend read as a matte, on synthetic scenes
with their exact coverage."""

from __future__ import annotations

import cv2
import numpy as np
from test_silhouette import iou, synthetic_scene

from mocap.silhouette.background import estimate_background, extract_silhouette
from mocap.silhouette.blend import silhouette_and_cover

SUPER = 8  # subpixels per pixel side of the drawn coverage


def _model(scene: np.ndarray, rng: np.random.Generator):
    """The background estimated from five noisy views of ``scene`` (float BGR)."""
    return estimate_background(
        [np.clip(scene + rng.normal(0, 2, scene.shape), 0, 255).astype(np.uint8) for _ in range(5)]
    )


def _composite(scene: np.ndarray, cover: np.ndarray, colour, rng: np.random.Generator) -> np.ndarray:
    """``colour`` over ``scene`` where the body ``cover``s each pixel (alpha in [0, 1]), with noise."""
    frame = cover[..., None] * np.float32(colour) + (1.0 - cover[..., None]) * scene
    return np.clip(frame + rng.normal(0, 2, frame.shape), 0, 255).astype(np.uint8)


def _figure_coverage(height: int = 240, width: int = 320) -> np.ndarray:
    """The share of each pixel a figure covers (drawn at SUPER times the size): a
    torso and head, two legs with a 3-pixel slit between them, and an arm 3 pixels
    wide held out from the body; its outline falls anywhere within the pixels."""
    big = np.zeros((height * SUPER, width * SUPER), np.uint8)
    s = SUPER
    cv2.rectangle(big, (140 * s + 3, 50 * s + 5), (181 * s + 2, 130 * s + 6), 255, -1)
    cv2.circle(big, (160 * s + 4, 36 * s + 1), 13 * s + 3, 255, -1)
    cv2.rectangle(big, (140 * s + 3, 130 * s), (158 * s + 6, 215 * s), 255, -1)
    cv2.rectangle(big, (161 * s + 6, 130 * s + 20 * s), (181 * s + 2, 215 * s), 255, -1)
    cv2.line(big, (182 * s, 60 * s), (240 * s, 100 * s + 5), 255, 3 * s)
    return cv2.resize(big.astype(np.float32) / 255, (width, height), interpolation=cv2.INTER_AREA)


def test_the_cover_keeps_the_pixels_the_body_covers_half_of():
    """Thresholded, every outline pixel the body touches a little is taken, and the
    closing bridges the slit between the legs; the cover is the pixels covered at
    least half (the masks' own definition), the thin arm whole."""
    rng = np.random.default_rng(4)
    scene = cv2.resize(rng.uniform(60, 220, (16, 21, 3)).astype(np.float32), (320, 240), interpolation=cv2.INTER_CUBIC)
    coverage = _figure_coverage()
    frame = _composite(scene, coverage, (150, 60, 40), rng)
    truth = coverage >= 0.5
    model = _model(scene, rng)
    fit, cover = silhouette_and_cover(frame, model)
    assert np.array_equal(fit, extract_silhouette(frame, model))  # what the 2D fit reads
    assert iou(fit, truth) < 0.95
    assert iou(cover, truth) > 0.98
    slit = truth[150:215, 159:162] == 0
    assert (fit[150:215, 159:162][slit] > 0).mean() > 0.5 and not cover[150:215, 159:162][slit].any()
    arm = truth[:, 186:236]
    assert (cover[:, 186:236][arm] > 0).mean() > 0.95


def test_dark_cloth_of_the_scenes_hue_is_body_and_its_shadow_is_not():
    """Dark blue trousers against a flat blue dusk sky pass every one-pixel test of a
    shadow (darker by one factor within the noise of the hue) and the flat sky has
    no texture to tell; their hue over 5x5 pixels is a few degrees off the sky's, a
    shadow's is not."""
    rng = np.random.default_rng(7)
    sky = np.float32([110, 75, 55]) * np.linspace(1.1, 0.9, 240, dtype=np.float32)[:, None, None]
    scene = np.broadcast_to(sky, (240, 320, 3)).copy()
    legs = np.zeros((240, 320), np.uint8)
    cv2.line(legs, (150, 60), (130, 200), 255, 22)
    cv2.line(legs, (150, 60), (175, 200), 255, 22)
    shadow = np.zeros_like(legs)
    cv2.ellipse(shadow, (250, 215), (50, 12), 0, 0, 360, 255, -1)
    lit = scene.copy()
    lit[shadow > 0] *= 0.6
    frame = _composite(lit, (legs > 0).astype(np.float32), (84, 56, 32), rng)
    fit, cover = silhouette_and_cover(frame, _model(scene, rng))
    assert iou(fit, legs) < 0.5  # the one-pixel tests take them for a shadow
    assert iou(cover, legs) > 0.9
    assert not cover[shadow > 0].any()


def test_a_shadow_on_a_textured_floor_stays_out_of_the_cover():
    _, frames, figures, shadows = synthetic_scene()
    model = estimate_background(frames)
    for frame, figure, shadow in zip(frames, figures, shadows):
        _, cover = silhouette_and_cover(frame, model)
        assert (cover[shadow > 0] > 0).mean() < 0.05
        assert iou(cover, figure) > 0.9
