"""`mocap synth`: render the 10-cylinder body (Table 1 widths, lengths from the joints) into a
video with exact ground truth, each cylinder the hull of its projected end circles, back to front.

Input joints: metres, right-handed, y up (BVH axes). Scaled orthographic projection unless a
focal length is given. Yaw 0 looks from the performer's right side (they face image right);
45 is three-quarter (turned toward the camera), 90 the front view.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import cv2
import numpy as np

from mocap import body
from mocap.errors import MocapError
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.io.video import write_video
from mocap.synth.hair import draw_hair
from mocap.synth.truth import Camera, Truth, save_truth
from mocap.synth.walk import walk_cycle

WALK_CYCLE = "walk-cycle"  # the source name of the procedural walk
VIEWS = {"side": 0.0, "three-quarter": 45.0, "front": 90.0}
_UP = np.array([0.0, 1.0, 0.0])
_RING = np.exp(2j * np.pi * np.arange(24) / 24)  # 24 samples on each end ellipse
_TORSO, _HEAD = body.SEGMENT_INDEX["torso"], body.SEGMENT_INDEX["head"]
_LIGHT = np.array([-0.5, 0.6, 0.62]) / np.linalg.norm([-0.5, 0.6, 0.62])  # camera frame
# shading layers: (radius fraction, shift toward the light in radii, brightness)
_LAYERS = np.array([[1.0, 0.0, 0.72], [0.62, 0.3, 1.0], [0.25, 0.55, 1.18]])
_COLOURS = np.array(
    [  # BGR per piece: body.SEGMENT_NAMES order, then the feet (shoes)
        (60, 70, 165),
        (135, 165, 220),
        (80, 95, 190),
        (125, 160, 215),
        (55, 60, 145),
        (110, 145, 200),
        (145, 100, 60),
        (160, 115, 75),
        (120, 80, 45),
        (135, 92, 55),
        (50, 55, 62),
        (60, 66, 75),
    ]
)
_SHINS = [body.SEGMENT_INDEX["lower_leg_l"], body.SEGMENT_INDEX["lower_leg_r"]]
# Feet (body units, of 175): soles body.FOOT_LENGTH under the ankles, heels 6 behind
# and toes 22 ahead (anthropometric tables: foot 0.152 of the stature, ankle at a fifth)
_HEEL, _TOE, _FOOT_R = 6.0, 22.0, body.FOOT_LENGTH / 2 / body.BODY_HEIGHT  # round feet
_SHADES = np.clip(_COLOURS[:, None, :] * _LAYERS[None, :, 2:], 0, 255).tolist()
_NOISE_PAD = 32
_PAN_SPEED = 3  # px/frame, moving background
# body shapes: each kind of segment's widths (lateral and front to back) against the
# model's (body.WIDTH), so that a method can be tried on a body other than its own model
SHAPES = {
    "model": {},
    "slim": {"head": 0.95, "torso": 0.8, "upper_arm": 0.75, "lower_arm": 0.75, "upper_leg": 0.75, "lower_leg": 0.8},
    "broad": {"head": 1.05, "torso": 1.3, "upper_arm": 1.3, "lower_arm": 1.2, "upper_leg": 1.3, "lower_leg": 1.2},
}


@dataclass(frozen=True)
class RenderOptions:
    """How to film the body. ``yaw`` (degrees) overrides ``view`` when given."""

    view: str = "side"
    yaw: float | None = None
    pitch: float = 0.0  # degrees, positive looks down
    size: tuple[int, int] = (640, 480)
    fps: float = 30.0
    perspective: float | None = None  # focal length in pixels; None = orthographic
    body_fraction: float = 0.6  # body height / frame height, if the path fits
    margin: float = 0.05  # free border, fraction of the frame
    moving_background: bool = False
    antialias: bool = True
    noise: float = 2.0  # sensor noise sigma, grey levels
    seed: int = 0
    shape: str = "model"  # a key of SHAPES: the body's widths
    hair: bool = False  # hair over the back of the head and the crown

    @property
    def yaw_deg(self) -> float:
        """The camera yaw in degrees from ``yaw`` or the named ``view``."""
        if self.yaw is not None:
            return float(self.yaw)
        if self.view not in VIEWS:
            raise MocapError(f"unknown view {self.view!r} (choose {', '.join(VIEWS)})")
        return VIEWS[self.view]


# -- camera ---------------------------------------------------------------------------


def _rotation(yaw_deg: float, pitch_deg: float, joints0: np.ndarray) -> np.ndarray:
    """World -> camera rotation for a yaw from the performer's initial lateral axis."""
    left = body.left_direction(joints0)
    left = _unit(left - _UP * left[1], np.array([1.0, 0.0, 0.0]))
    yaw, pitch = np.radians(yaw_deg), np.radians(pitch_deg)
    look = np.cos(yaw) * left - np.sin(yaw) * np.cross(left, _UP)
    right = np.cross(look, _UP)
    up = np.cos(pitch) * _UP + np.sin(pitch) * look
    look = np.cos(pitch) * look - np.sin(pitch) * _UP
    return np.stack([right, up, -look])


def frame_camera(joints_world: np.ndarray, radii: np.ndarray, opts: RenderOptions) -> Camera:
    """The fixed camera keeping every frame's body inside the margins, ``opts.body_fraction`` tall if it fits."""
    rot = _rotation(opts.yaw_deg, opts.pitch, joints_world[0])
    height = body.body_height(joints_world[0])
    pts = cylinder_points(joints_world @ rot.T, radii, _LAYERS[:1]).reshape(-1, 3)
    mid = (pts.min(0) + pts.max(0)) / 2
    width, frame_h = opts.size
    half = np.array([width, frame_h]) * (0.5 - opts.margin)
    wanted = opts.body_fraction * frame_h / height
    if opts.perspective is None:
        fit = np.min(half / np.maximum(np.abs(pts[:, :2] - mid[:2]).max(0), 1e-9))
        kind, scale, origin = "orthographic", min(wanted, fit), mid
    else:
        rel = pts - mid
        dist = max(opts.perspective / wanted, np.max(rel[:, 2:] + opts.perspective * np.abs(rel[:, :2]) / half))
        kind, scale, origin = "perspective", float(opts.perspective), mid + [0.0, 0.0, dist]
    return Camera(
        kind=kind,
        yaw_deg=opts.yaw_deg,
        pitch_deg=float(opts.pitch),
        rotation=rot,
        origin=origin @ rot,
        scale=float(scale),
        cx=width / 2,
        cy=frame_h / 2,
    )


def body_pieces(joints: np.ndarray) -> np.ndarray:
    """(..., 12, 2, 3) ends of the drawn pieces of joints (..., 16, 3): the ten segments, then
    each foot's heel and toe, square to the shin and pointing the way the hips and trunk face."""
    ends, j = body.segment_endpoints(joints), body.JOINT_INDEX
    u = body.body_height(joints.reshape(-1, 16, 3)[0]) / body.BODY_HEIGHT
    trunk = _unit(joints[..., j["neck"], :] - joints[..., j["pelvis"], :], _UP)[..., None, :]
    ahead = np.cross(joints[..., j["hip_l"], :] - joints[..., j["hip_r"], :], trunk[..., 0, :])
    shin = _unit(ends[..., _SHINS, 1, :] - ends[..., _SHINS, 0, :], -_UP)  # (..., 2, 3)
    ahead = _unit(
        ahead[..., None, :] - (ahead[..., None, :] * shin).sum(-1, keepdims=True) * shin, trunk
    )  # legs raised straight ahead: the feet point up the trunk
    axis = ends[..., _SHINS, 1, :] + shin * (body.FOOT_LENGTH / 2 * u)
    feet = np.stack([axis - ahead * (_HEEL * u), axis + ahead * (_TOE * u)], axis=-2)
    return np.concatenate([ends, feet], axis=-3)


def cylinder_points(joints_cam: np.ndarray, radii: np.ndarray, layers: np.ndarray) -> np.ndarray:
    """(..., 12, L, 2R, 3) points on both end ellipses of every piece, camera frame.

    ``radii`` (12, 2): lateral and front-to-back radii (the torso's lateral axis runs right to
    left). One ring per layer: radii times ``layer[0]``, shifted ``layer[1]`` radii to the light."""
    ends = body_pieces(joints_cam)  # (..., 12, 2, 3)
    axis = _unit(ends[..., 1, :] - ends[..., 0, :], _UP)
    across = _unit(np.cross(axis, [0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]))
    lateral = np.broadcast_to(across, axis.shape).copy()
    lateral[..., _TORSO, :] = body.left_direction(joints_cam)
    lateral = _unit(lateral - (lateral * axis).sum(-1, keepdims=True) * axis, across)
    sagittal = np.cross(axis, lateral)
    light = _unit(_LIGHT - (axis @ _LIGHT)[..., None] * axis, across)
    r = radii[:, None, :] * layers[:, :1]  # (12, L, 2)
    ring = (
        _RING.real[:, None] * r[..., None, 0:1, None] * lateral[..., None, None, None, :]
        + _RING.imag[:, None] * r[..., None, 1:2, None] * sagittal[..., None, None, None, :]
    )
    shift = (radii[:, :1] * layers[:, 1])[..., None] * light[..., None, :]  # (..., 10, L, 3)
    centres = ends[..., None, :, None, :] + shift[..., None, None, :]  # (..., 10, L, 2, 1, 3)
    pts = centres + ring  # (..., 10, L, 2, R, 3)
    return pts.reshape(*pts.shape[:-3], 2 * len(_RING), 3)


def _unit(v: np.ndarray, fallback: np.ndarray) -> np.ndarray:
    """Normalise along the last axis; near-zero vectors become ``fallback``."""
    n = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(n > 1e-9, v / np.maximum(n, 1e-12), fallback)


# -- pictures -------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Scene:
    """Everything needed to draw any frame of a clip."""

    opts: RenderOptions
    camera: Camera
    joints_cam: np.ndarray  # (F, 16, 3) camera frame
    radii: np.ndarray  # (12, 2) lateral and front-to-back radii (segments, feet), m
    canvas: np.ndarray  # background, wider than the frame when it pans
    noise: np.ndarray  # (2, H+pad, W+pad, 3) positive and negative sensor noise


def shape_widths(shape: str) -> np.ndarray:
    """(10,) each segment's widths against the model's for a body ``shape`` (SHAPES)."""
    if shape not in SHAPES:
        raise MocapError(f"unknown body shape {shape!r} (choose {', '.join(SHAPES)})")
    return np.array([SHAPES[shape].get(body.segment_kind(s), 1.0) for s in body.SEGMENT_NAMES])


def plan_scene(joints_world: np.ndarray, opts: RenderOptions) -> Scene:
    """Camera, background and noise for rendering ``joints_world`` (F, 16, 3)."""
    joints_world = np.asarray(joints_world, dtype=float)
    if joints_world.ndim != 3 or joints_world.shape[1:] != (16, 3) or not len(joints_world):
        raise MocapError(f"expected joints of shape (F, 16, 3), got {joints_world.shape}")
    height = body.body_height(joints_world[0])
    radii = np.concatenate([body.semi_axes(height), np.full((2, 2), _FOOT_R * height)])
    camera = frame_camera(joints_world, radii, opts)  # the model's: shapes share it
    radii[: len(body.SEGMENT_NAMES)] *= shape_widths(opts.shape)[:, None]
    (width, height), rng = opts.size, np.random.default_rng(opts.seed)
    pan = min(_PAN_SPEED * (len(joints_world) - 1), width) if opts.moving_background else 0
    canvas = _room(width + pan, height, rng, clutter=opts.moving_background)
    noise = rng.normal(0.0, opts.noise, (height + _NOISE_PAD, width + _NOISE_PAD, 3))
    noise = np.stack([np.clip(noise, 0, 255), np.clip(-noise, 0, 255)]).round().astype(np.uint8)
    return Scene(opts, camera, camera.to_camera(joints_world), radii, canvas, noise)


def _room(width: int, height: int, rng: np.random.Generator, clutter: bool) -> np.ndarray:
    """A deterministic room (wall, floor, pictures, texture); ``clutter`` adds saturated shapes."""
    t = np.linspace(0.0, 1.0, height)[:, None, None]
    horizon = int(height * 0.62)
    wall = np.array([172, 178, 184]) - 25 * t
    floor = np.array([92, 105, 118]) + 40 * t
    img = np.where(np.arange(height)[:, None, None] < horizon, wall, floor) * np.ones((1, width, 1))
    for _ in range(max(3, width // 110)):
        w, h = rng.uniform(0.06, 0.19) * width, rng.uniform(0.14, 0.5) * horizon
        x, y = int(rng.uniform(0, width - w)), int(rng.uniform(0.1, 0.5) * horizon)
        corner = (int(x + w), int(y + h))
        colour = img[y, x] * rng.uniform(0.75, 1.05) + rng.uniform(-20, 20, 3)
        cv2.rectangle(img, (x, y), corner, colour.tolist(), -1)
        cv2.rectangle(img, (x, y), corner, (colour * 0.7).tolist(), 2)
    cv2.rectangle(img, (0, horizon - 8), (width, horizon), (70, 80, 90), -1)
    for _ in range(width // 8 if clutter else 0):
        x, y = int(rng.integers(0, width)), int(rng.integers(0, height))
        r, colour = int(rng.integers(3, 15)) * height // 240, rng.integers(20, 236, 3).tolist()
        if rng.random() < 0.5:
            cv2.circle(img, (x, y), r, colour, -1)
        else:
            cv2.rectangle(img, (x, y), (x + 2 * r, y + r), colour, -1)
    coarse = cv2.resize(
        rng.normal(0, 6, (height // 16 + 2, width // 16 + 2)), (width, height), interpolation=cv2.INTER_CUBIC
    )
    img += coarse[..., None] + rng.normal(0, 2.5, (height, width, 1))
    return np.clip(img, 0, 255).astype(np.uint8)


def background(scene: Scene, i: int) -> np.ndarray:
    """The noise-free background of frame ``i`` (a view into the canvas)."""
    width = scene.opts.size[0]
    pan = scene.canvas.shape[1] - width
    step = (i * _PAN_SPEED) % (2 * pan) if pan else 0
    offset = step if step <= pan else 2 * pan - step
    return scene.canvas[:, offset : offset + width]


def draw_frame(scene: Scene, i: int) -> np.ndarray:
    """The BGR image of frame ``i``: background, cylinders back to front, sensor noise."""
    img = background(scene, i).copy()
    pts = cylinder_points(scene.joints_cam[i], scene.radii, _LAYERS)
    px = np.round(scene.camera.project_camera(pts) * 16).astype(np.int32)  # 4 fraction bits
    depth = body_pieces(scene.joints_cam[i]).mean(axis=1)[:, 2]
    line = cv2.LINE_AA if scene.opts.antialias else cv2.LINE_8
    for k in np.argsort(depth):
        for layer in range(len(_LAYERS)):
            cv2.fillConvexPoly(img, cv2.convexHull(px[k, layer]), _SHADES[k][layer], line, 4)
        if k == _HEAD and scene.opts.hair:  # a face in front, hair behind (mocap.silhouette.facing)
            draw_hair(
                img, scene.joints_cam[i], scene.radii[k, 0], scene.camera.project_camera, cv2.convexHull(px[k, 0]), line
            )
    if scene.opts.noise > 0:
        width, height = scene.opts.size
        dy, dx = np.random.default_rng([scene.opts.seed, i]).integers(0, _NOISE_PAD, 2)
        cv2.add(img, scene.noise[0, dy : dy + height, dx : dx + width], dst=img)
        cv2.subtract(img, scene.noise[1, dy : dy + height, dx : dx + width], dst=img)
    return img


def scene_truth(scene: Scene, source: str, source_frames: np.ndarray) -> Truth:
    """The ground truth of every frame of ``scene``."""
    cam = scene.camera
    pelvis = scene.joints_cam[:, body.JOINT_INDEX["pelvis"]]
    height_m = body.body_height(scene.joints_cam[0])
    # a perspective body's size varies; quote it at the mean depth of the clip
    depth = 1.0 if cam.kind == "orthographic" else float(-np.mean(pelvis[:, 2]))
    width, height = scene.opts.size
    return Truth(
        source=source,
        fps=float(scene.opts.fps),
        width=width,
        height=height,
        camera=cam,
        body_height_m=height_m,
        body_height_px=cam.scale * height_m / depth,
        source_frames=np.asarray(source_frames, dtype=int),
        joints2d=cam.project_camera(scene.joints_cam),
        joints3d=scene.joints_cam - pelvis[:, None],
        pelvis_camera=pelvis,
    )


def render_clip(
    joints_world: np.ndarray,
    out_video: str | Path,
    options: RenderOptions | None = None,
    *,
    truth_path: str | Path | None = None,
    source: str = "joints",
    source_frames: np.ndarray | None = None,
    **overrides,
) -> Truth:
    """Render joints (F, 16, 3; metres, y up) to ``out_video`` and its truth JSON (default
    VIDEO.truth.json); ``overrides`` set RenderOptions fields, e.g. ``view="front"``."""
    opts = replace(options or RenderOptions(), **overrides)
    scene = plan_scene(joints_world, opts)
    n = len(scene.joints_cam)
    write_video(out_video, (draw_frame(scene, i) for i in range(n)), opts.fps, opts.size)
    truth = scene_truth(scene, source, np.arange(n) if source_frames is None else source_frames)
    save_truth(truth, truth_path or Path(out_video).with_suffix(".truth.json"))
    return truth


def resample_indices(
    n_source: int,
    frame_time: float,
    fps: float,
    frames: tuple[int | None, int | None] | None = None,
    seconds: float | None = None,
) -> np.ndarray:
    """Source frame nearest in time for each output frame, in ``frames`` (slice rules), ``seconds`` long."""
    start, stop, _ = slice(*(frames or (None, None))).indices(n_source)
    if stop <= start:
        raise MocapError(f"frame range {frames} is empty (the motion has {n_source} frames)")
    duration = min((stop - start) * frame_time, np.inf if seconds is None else seconds)
    count = max(1, int(np.floor(duration * fps + 1e-6)))
    picks = start + np.round(np.arange(count) / (fps * frame_time)).astype(int)
    return np.minimum(picks, stop - 1)


def render_motion(
    source: str | Path,
    out_video: str | Path,
    options: RenderOptions | None = None,
    *,
    frames: tuple[int | None, int | None] | None = None,
    seconds: float | None = None,
    in_place: bool = False,
    truth_path: str | Path | None = None,
    **overrides,
) -> Truth:
    """Render a BVH file (resampled to the output fps by nearest frame), or with
    ``source="walk-cycle"`` the procedural walk (``seconds`` long, default 4)."""
    opts = replace(options or RenderOptions(), **overrides)
    if str(source) == WALK_CYCLE:
        joints, frame_time = walk_cycle(seconds or 4.0, opts.fps, in_place=in_place), 1 / opts.fps
    else:
        motion = read_bvh(source)
        joints, frame_time = contract_joints(motion), motion.frame_time
    picks = resample_indices(len(joints), frame_time, opts.fps, frames, seconds)
    return render_clip(
        joints[picks], out_video, opts, truth_path=truth_path, source=Path(source).name, source_frames=picks
    )
