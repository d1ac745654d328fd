"""Exports read back by independent readers: BVH by bvhio, GLB by pygltflib and
trimesh, CSV by the csv module."""

import csv
from pathlib import Path

import bvhio
import numpy as np
import pygltflib
import pytest
import trimesh
from scipy.spatial.transform import Rotation

from mocap import body
from mocap.io.bvh import contract_joints, read_bvh
from mocap.errors import MocapError
from mocap.io.export.formats import FORMATS, Clip, write_format
from mocap.lift.motion import build_motion
from mocap.synth import resample_indices
from mocap.walk import walk_cycle

CMU_WALK = Path(__file__).resolve().parents[2] / "shared" / "data" / "bvh" / "cmu_walk.bvh"
FPS = 30.0
_COMPONENTS = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}
_DTYPES = {pygltflib.FLOAT: np.float32, pygltflib.UNSIGNED_SHORT: np.uint16}


@pytest.fixture(scope="module")
def walk_motion():
    """The procedural walk from every third frame, smoothed."""
    joints = walk_cycle(2.0, FPS)
    return build_motion({i: joints[i] for i in range(0, len(joints), 3)}, len(joints), FPS,
                        smooth=1.0)


@pytest.fixture(scope="module")
def cmu_motion():
    """Two seconds of the CMU walk at 30 fps from every fourth frame, pelvis as root."""
    if not CMU_WALK.exists():
        pytest.skip(f"{CMU_WALK} absent")
    capture = read_bvh(CMU_WALK)
    joints = contract_joints(capture)
    joints = joints[resample_indices(len(joints), capture.frame_time, FPS, None, 2.0)]
    pelvis = joints[:, body.JOINT_INDEX["pelvis"]]
    return build_motion({i: joints[i] - pelvis[i] for i in range(0, len(joints), 4)},
                        len(joints), FPS, root=pelvis)


def bvhio_joints(path: Path) -> tuple[np.ndarray, float]:
    """(F, 16, 3) contract joint positions in metres as bvhio reads them, frame time."""
    root = bvhio.readAsHierarchy(str(path))
    by_name = {joint.Name: joint for joint, _, _ in root.layout()}
    frames = bvhio.readAsBvh(str(path), loadKeyFrames=False)
    out = np.empty((frames.FrameCount, len(body.JOINTS), 3))
    for f in range(frames.FrameCount):
        root.loadPose(f)
        out[f] = [by_name[name].PositionWorld for name in body.JOINTS]
    return out / 100.0, frames.FrameTime          # the file is in centimetres


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
        flat = np.frombuffer(self.blob, _DTYPES[acc.componentType], acc.count * width,
                             view.byteOffset + (acc.byteOffset or 0))
        return flat.reshape(acc.count, width).astype(float)

    def world_matrices(self, sample: int) -> list[np.ndarray]:
        """4x4 world transform of every node at one animation sample."""
        local = {}
        for i, node in enumerate(self.doc.nodes):
            local[i] = {"translation": node.translation or [0, 0, 0],
                        "rotation": node.rotation or [0, 0, 0, 1]}
        animation = self.doc.animations[0]
        for channel in animation.channels:
            sampler = animation.samplers[channel.sampler]
            local[channel.target.node][channel.target.path] = self.accessor(sampler.output)[sample]
        world: list[np.ndarray] = []
        for i in range(len(self.doc.nodes)):      # parents come first in our files
            m = np.eye(4)
            m[:3, :3] = Rotation.from_quat(local[i]["rotation"]).as_matrix()
            m[:3, 3] = local[i]["translation"]
            world.append(world[self.parent[i]] @ m if i in self.parent else m)
        return world


def test_glb_animation_puts_cylinders_on_the_joints(walk_motion, tmp_path):
    gltf = Gltf(write_format("glb", tmp_path / "m.glb", Clip("m", {}, [], walk_motion)))
    doc = gltf.doc
    assert len(doc.animations) == 1 and len(doc.meshes) == 10
    times = gltf.accessor(doc.animations[0].samplers[0].input)[:, 0]
    assert len(times) == walk_motion.n_frames
    assert times[-1] == pytest.approx((walk_motion.n_frames - 1) / FPS)
    names = [node.name for node in doc.nodes]
    world = walk_motion.world_joints
    for sample in (0, 17, walk_motion.n_frames - 1):
        matrices = gltf.world_matrices(sample)
        at = {name: matrices[i][:3, 3] for i, name in enumerate(names)}
        assert np.abs([at[j] - world[sample, k] for k, j in enumerate(body.JOINTS)]).max() < 1e-5
        for i, node in enumerate(doc.nodes):
            if node.mesh is None:
                continue
            mesh = doc.meshes[node.mesh]
            start, end = body.SEGMENTS[mesh.name]
            vertices = gltf.accessor(mesh.primitives[0].attributes.POSITION)
            centre = matrices[i][:3, :3] @ vertices.mean(0) + matrices[i][:3, 3]
            middle = world[sample, [body.JOINT_INDEX[start], body.JOINT_INDEX[end]]].mean(0)
            assert np.abs(centre - middle).max() < 1e-5, mesh.name


def test_glb_loads_in_trimesh(walk_motion, tmp_path):
    scene = trimesh.load(write_format("glb", tmp_path / "m.glb", Clip("m", {}, [], walk_motion)))
    assert len(scene.geometry) == 10
    assert all(m.is_watertight and m.volume > 0 for m in scene.geometry.values())
    torso = scene.geometry["torso"]
    radii = body.semi_axes(body.BODY_HEIGHT_M)[body.SEGMENT_INDEX["torso"]]
    assert np.ptp(torso.vertices, axis=0)[[0, 2]] == pytest.approx(2 * radii, rel=0.01)
    # trimesh places the nodes by their static transforms, the first frame
    neck, _ = scene.graph.get("neck")
    assert np.abs(neck[:3, 3] - walk_motion.world_joints[0, body.JOINT_INDEX["neck"]]).max() < 1e-5


def test_csv_round_trip(walk_motion, tmp_path):
    with open(write_format("csv", tmp_path / "m.csv", Clip("m", {}, [], walk_motion)), newline="") as f:
        rows = list(csv.reader(f))
    assert rows[0][:5] == ["frame", "time", "head_top_x", "head_top_y", "head_top_z"]
    assert len(rows[0]) == 2 + 3 * 16 and len(rows) == 1 + walk_motion.n_frames
    values = np.array(rows[1:], dtype=float)
    assert values[:, 0].tolist() == list(range(walk_motion.n_frames))
    assert np.allclose(values[:, 1], walk_motion.times, atol=1e-6)
    assert np.abs(values[:, 2:].reshape(-1, 16, 3) - walk_motion.world_joints).max() < 1e-6


@pytest.mark.parametrize("key", list(FORMATS))
def test_unwritable_path_is_refused(key, walk_motion, tmp_path):
    clip = Clip("m", {}, [], walk_motion)
    with pytest.raises(MocapError, match="cannot write"):
        write_format(key, tmp_path / "missing" / "out", clip)
    with pytest.raises(MocapError, match="cannot write"):
        write_format(key, tmp_path, clip)                   # a directory
    assert list(tmp_path.iterdir()) == []


def test_unknown_format_is_refused(walk_motion, tmp_path):
    with pytest.raises(MocapError, match="no export format 'fbx'"):
        write_format("fbx", tmp_path / "m.fbx", Clip("m", {}, [], walk_motion))
