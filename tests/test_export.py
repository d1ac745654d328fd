"""Exports read back by independent readers: BVH by bvhio, GLB by pygltflib and
trimesh, CSV by the csv module (Blender's own imports: test_blender.py)."""

import csv
import importlib.util
from pathlib import Path

import bvhio
import numpy as np
import pygltflib
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.cli import main
from mocap.errors import MocapError
from mocap.io.bvh_reader import contract_joints, read_bvh
from mocap.io.export.formats import FORMATS, Clip, write_format
from mocap.io.export.glb import SIDES
from mocap.io.export.marks import FACING_MARKS, facing_marks
from mocap.lift.motion import build_motion
from mocap.lift.skeleton import BONES, JOINT_BONES
from mocap.synth import resample_indices
from mocap.synth.walk import walk_cycle

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
FPS = 30.0
_COMPONENTS = {"SCALAR": 1, "VEC3": 3, "VEC4": 4, "MAT4": 16}
_DTYPES = {pygltflib.FLOAT: np.float32, pygltflib.UNSIGNED_SHORT: np.uint16, pygltflib.UNSIGNED_INT: np.uint32}


@pytest.fixture(scope="module")
def walk_motion():
    """The procedural walk from every third frame, smoothed."""
    joints = walk_cycle(2.0, FPS)
    return build_motion({i: joints[i] for i in range(0, len(joints), 3)}, len(joints), FPS, smooth=1.0)


@pytest.fixture(scope="module")
def cmu_motion():
    """Two seconds of the CMU walk at 30 fps from every fourth frame, pelvis as root."""
    if not CMU_WALK.exists():
        pytest.skip(f"{CMU_WALK} absent")
    capture = read_bvh(CMU_WALK)
    joints = contract_joints(capture)
    joints = joints[resample_indices(len(joints), capture.frame_time, FPS, None, 2.0)]
    pelvis = joints[:, body.JOINT_INDEX["pelvis"]]
    return build_motion({i: joints[i] - pelvis[i] for i in range(0, len(joints), 4)}, len(joints), FPS, root=pelvis)


def bvhio_joints(path: Path) -> tuple[np.ndarray, float]:
    """(F, 16, 3) contract joint positions in metres as bvhio reads them, frame time."""
    root = bvhio.readAsHierarchy(str(path))
    by_name = {joint.Name: joint for joint, _, _ in root.layout()}
    frames = bvhio.readAsBvh(str(path), loadKeyFrames=False)
    head_end = next(j for j in _tree(frames.Root) if j.Name == "Head").EndSite
    out = np.empty((frames.FrameCount, len(body.JOINTS), 3))
    for f in range(frames.FrameCount):
        root.loadPose(f)
        # bvhio keeps End Sites apart: the head top is the Head's, in the Head's frame
        out[f] = [
            by_name["Head"].pointToWorld(head_end) if BONES[b] == "Head_End" else by_name[BONES[b]].PositionWorld
            for b in JOINT_BONES
        ]
    return out / 100.0, frames.FrameTime  # the file is in centimetres


def _tree(joint):
    """A bvhio BVH joint and all below it."""
    yield joint
    for child in joint.Children:
        yield from _tree(child)


@pytest.mark.parametrize("which", ["walk_motion", "cmu_motion"])
def test_bvh_round_trip_through_bvhio(which, tmp_path, request):
    motion = request.getfixturevalue(which)
    path = write_format("bvh", tmp_path / "m.bvh", Clip("m", {}, [], motion))
    joints, frame_time = bvhio_joints(path)
    assert frame_time == pytest.approx(1 / FPS) and len(joints) == motion.n_frames
    assert np.abs(joints - motion.world_joints).max() < 0.001


def test_bvh_of_one_frame(tmp_path):
    motion = build_motion({0: walk_cycle(0.1, FPS)[0]}, 1, FPS)
    joints, _ = bvhio_joints(write_format("bvh", tmp_path / "one.bvh", Clip("m", {}, [], motion)))
    assert np.abs(joints - motion.world_joints).max() < 0.001


class Gltf:
    """A GLB as pygltflib reads it, with numpy views of its accessors."""

    def __init__(self, path: Path):
        self.doc = pygltflib.GLTF2().load(str(path))
        self.blob = self.doc.binary_blob()
        self.parent = {c: i for i, node in enumerate(self.doc.nodes) for c in node.children or []}

    def accessor(self, index: int) -> np.ndarray:
        acc = self.doc.accessors[index]
        view = self.doc.bufferViews[acc.bufferView]
        width = _COMPONENTS[acc.type]
        flat = np.frombuffer(
            self.blob, _DTYPES[acc.componentType], acc.count * width, view.byteOffset + (acc.byteOffset or 0)
        )
        return flat.reshape(acc.count, width).astype(float)

    def world_matrices(self, sample: int | None) -> dict[int, np.ndarray]:
        """4x4 world transform of every node at one animation sample (None: at rest)."""
        local = {}
        for i, node in enumerate(self.doc.nodes):
            local[i] = {"translation": node.translation or [0, 0, 0], "rotation": node.rotation or [0, 0, 0, 1]}
        animation = self.doc.animations[0]
        for channel in animation.channels if sample is not None else ():
            sampler = animation.samplers[channel.sampler]
            local[channel.target.node][channel.target.path] = self.accessor(sampler.output)[sample]
        world: dict[int, np.ndarray] = {}

        def place(i: int) -> np.ndarray:
            if i not in world:
                m = np.eye(4)
                m[:3, :3] = Rotation.from_quat(local[i]["rotation"]).as_matrix()
                m[:3, 3] = local[i]["translation"]
                world[i] = place(self.parent[i]) @ m if i in self.parent else m
            return world[i]

        for i in range(len(self.doc.nodes)):
            place(i)
        return world


def test_glb_is_one_skinned_character(walk_motion, tmp_path):
    """One mesh, one skin over every bone, one animation; on sampled frames the joints
    are the motion's, the skinned cylinders' ends sit on their joints and the nose and
    chest marks stand out of the body's front."""
    gltf = Gltf(write_format("glb", tmp_path / "m.glb", Clip("m", {}, [], walk_motion)))
    doc = gltf.doc
    assert len(doc.animations) == len(doc.meshes) == len(doc.skins) == len(doc.materials) == 1
    skin, primitive = doc.skins[0], doc.meshes[0].primitives[0]
    names = [doc.nodes[j].name for j in skin.joints]
    assert names == list(BONES)
    times = gltf.accessor(doc.animations[0].samplers[0].input)[:, 0]
    assert len(times) == walk_motion.n_frames
    assert times[-1] == pytest.approx((walk_motion.n_frames - 1) / FPS)
    inverse_bind = gltf.accessor(skin.inverseBindMatrices).reshape(-1, 4, 4).transpose(0, 2, 1)
    rest = gltf.world_matrices(None)
    assert np.abs(inverse_bind @ np.array([rest[j] for j in skin.joints]) - np.eye(4)).max() < 1e-5
    vertices = gltf.accessor(primitive.attributes.POSITION)
    joints = gltf.accessor(primitive.attributes.JOINTS_0).astype(int)
    weights = gltf.accessor(primitive.attributes.WEIGHTS_0)
    assert np.allclose(weights.sum(1), 1.0)
    per_segment = len(trimesh.creation.cylinder(radius=1.0, height=1.0, sections=SIDES).vertices)
    per_mark = (len(vertices) - per_segment * len(body.SEGMENTS)) // len(FACING_MARKS)
    world = walk_motion.world_joints
    for sample in (0, 17, walk_motion.n_frames - 1):
        matrices = gltf.world_matrices(sample)
        at = {doc.nodes[j].name: matrices[j][:3, 3] for j in skin.joints}
        assert np.abs([at[BONES[b]] - world[sample, k] for k, b in enumerate(JOINT_BONES)]).max() < 1e-5
        skinning = np.array([matrices[j] for j in skin.joints]) @ inverse_bind
        moved = np.einsum("vk,vkij,vj->vi", weights, skinning[joints], np.c_[vertices, np.ones(len(vertices))])[:, :3]
        for k, (start, end) in enumerate(body.SEGMENTS.values()):
            part = slice(k * per_segment, (k + 1) * per_segment)
            ends = world[sample, [body.JOINT_INDEX[start], body.JOINT_INDEX[end]]]
            along = _along(vertices[part], rest, skin, start, end)
            for end_at, joint in ((0.0, ends[0]), (1.0, ends[1])):
                ring = moved[part][np.abs(along - end_at) < 1e-4]
                assert np.abs(ring.mean(0) - joint).max() < 1e-5, (start, end)
        marks = moved[per_segment * len(body.SEGMENTS) :].reshape(len(FACING_MARKS), per_mark, 3)
        for (segment, *_), (_, out, _), mark in zip(FACING_MARKS.values(), facing_marks(world[sample]), marks):
            start, end = world[sample, [body.JOINT_INDEX[j] for j in body.SEGMENTS[segment]]]
            axis = (end - start) / np.linalg.norm(end - start)
            offset = mark - start - np.outer((mark - start) @ axis, axis)  # off the axis
            tip = offset[np.argmax(np.linalg.norm(offset, axis=1))]
            assert tip @ out > 0.9 * np.linalg.norm(tip), (segment, sample)  # in front


def _along(vertices, rest, skin, start: str, end: str) -> np.ndarray:
    """Where rest-pose vertices lie along the segment from one joint to the other (0..1)."""
    a, b = (rest[skin.joints[JOINT_BONES[body.JOINT_INDEX[j]]]][:3, 3] for j in (start, end))
    return (vertices - a) @ (b - a) / np.sum((b - a) ** 2)


def test_glb_loads_in_trimesh(walk_motion, tmp_path):
    scene = trimesh.load(write_format("glb", tmp_path / "m.glb", Clip("m", {}, [], walk_motion)))
    assert list(scene.geometry) == ["body"]
    mesh = scene.geometry["body"]
    assert mesh.body_count == len(body.SEGMENTS) + len(FACING_MARKS) and mesh.volume > 0
    assert all(part.is_watertight for part in mesh.split(only_watertight=False))


def test_csv_round_trip(walk_motion, tmp_path):
    joints2d = np.random.default_rng(0).uniform(0, 640, (walk_motion.n_frames, 16, 2))
    frames = [{"index": i, "joints2d": joints2d[i], "score": 0.5} for i in range(walk_motion.n_frames)]
    del frames[3]["joints2d"], frames[3]["score"]  # nobody on frame 3
    path = write_format("csv", tmp_path / "m.csv", Clip("m", {}, frames, walk_motion))
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    head = rows[0]
    assert head[:6] == ["frame", "time_s", "keyframe", "score", "head_top_u_right_px", "head_top_v_down_px"]
    assert head[36:39] == ["head_top_x_right_m", "head_top_y_up_m", "head_top_z_toward_camera_m"]
    assert head[-2:] == ["ankle_l_contact", "ankle_r_contact"]
    assert len(head) == 4 + 5 * 16 + 2 and len(rows) == 1 + walk_motion.n_frames
    assert rows[4][3:36] == [""] * 33
    values = np.array([[float(v) if v else np.nan for v in row] for row in rows[1:]])
    assert values[:, 0].tolist() == list(range(walk_motion.n_frames))
    assert np.allclose(values[:, 1], walk_motion.times, atol=1e-6)
    assert np.allclose(values[:, 2], walk_motion.keyframes)
    keep = np.arange(walk_motion.n_frames) != 3
    assert np.abs(values[keep, 4:36].reshape(-1, 16, 2) - joints2d[keep]).max() < 1e-3
    assert np.abs(values[:, 36:84].reshape(-1, 16, 3) - walk_motion.world_joints).max() < 1e-6
    assert (values[:, -2:] == walk_motion.contacts).all()


@pytest.mark.parametrize("key", list(FORMATS))
def test_unwritable_path_is_refused(key, walk_motion, tmp_path):
    if not FORMATS[key].available():
        pytest.skip(f"{key}: not available here")
    clip = Clip("m", {}, [], walk_motion)
    with pytest.raises(MocapError, match="cannot write"):
        write_format(key, tmp_path / "missing" / "out", clip)
    with pytest.raises(MocapError, match="cannot write"):
        write_format(key, tmp_path, clip)  # a directory
    assert list(tmp_path.iterdir()) == []


def test_fit_without_blender_refuses_fbx_in_one_line(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None)
    assert main(["fit", str(tmp_path / "walk.mp4"), "--fbx", str(tmp_path / "m.fbx")]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "mocap: error: FBX export needs Blender as a Python module: pip install 'mocap[fbx]' (Python 3.11)"


def test_unknown_format_is_refused(walk_motion, tmp_path):
    with pytest.raises(MocapError, match="no export format 'obj'"):
        write_format("obj", tmp_path / "m.obj", Clip("m", {}, [], walk_motion))


def test_fbx_without_blender_says_how_to_get_it(walk_motion, tmp_path, monkeypatch):
    monkeypatch.setattr(importlib.util, "find_spec", lambda name, *a: None)
    assert not FORMATS["fbx"].available()
    with pytest.raises(MocapError, match=r"pip install 'mocap\[fbx\]'"):
        write_format("fbx", tmp_path / "m.fbx", Clip("m", {}, [], walk_motion))
    assert list(tmp_path.iterdir()) == []
