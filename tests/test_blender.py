"""Blender as the judge: the BVH, the GLB and the FBX that `mocap fit` writes, imported
by Blender's own importers, pose their armature's joints where the motion file says
(joints3d + root - origin) within 1 mm on sampled frames; the BVH rests in a T-pose;
the GLB and the FBX come in as one armature, one action and one skinned mesh.

Needs Blender as a Python module (``pip install 'mocap[fbx]'``, Python 3.11; CI runs
this file in a second environment that has it, .ci/run)."""

from __future__ import annotations

import numpy as np
import pytest
from app_helpers import TINY_FRAMES, tiny_video  # noqa: F401

from mocap.cli import main
from mocap.io.export.motion_json import read_motion
from mocap.lift.skeleton import BONES, JOINT_BONES

bpy = pytest.importorskip("bpy", reason="Blender as a Python module (the fbx extra) is absent")

MM = 0.001
SAMPLES = (0, TINY_FRAMES // 2, TINY_FRAMES - 1)
_BONE_OF = [BONES[b] for b in JOINT_BONES]

pytestmark = pytest.mark.blender


@pytest.fixture(scope="module")
def written(tiny_video, tmp_path_factory):
    """{format: path} of one `mocap fit` run: the motion file, BVH, GLB and FBX."""
    folder = tmp_path_factory.mktemp("blender")
    paths = {key: folder / f"walk.{key}" for key in ("json", "bvh", "glb", "fbx")}
    assert (
        main(
            [
                "fit",
                str(tiny_video),
                "--quiet",
                "--out",
                str(paths["json"]),
                *(a for key in ("bvh", "glb", "fbx") for a in (f"--{key}", str(paths[key]))),
            ]
        )
        == 0
    )
    return paths


@pytest.fixture(scope="module")
def expected(written):
    """(F, 16, 3) the motion file's joints in the exports' world."""
    data = read_motion(written["json"])
    return np.array([f["joints3d"] + np.asarray(f["root"]) - data["origin"] for f in data["frames"]])


def empty_scene(fps: float) -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.context.scene.render.fps, bpy.context.scene.render.fps_base = round(fps), 1.0


def load(key: str, path, fps: float = 15.0) -> None:
    """Import a file with Blender's importer for its format into an empty scene at the
    clip's frame rate (the tiny clip's: 15 fps; glTF keys are seconds)."""
    empty_scene(fps)
    if key == "bvh":
        bpy.ops.import_anim.bvh(
            filepath=str(path),
            global_scale=0.01,
            use_fps_scale=False,
            update_scene_fps=False,
            update_scene_duration=True,
        )
    elif key == "glb":
        bpy.ops.import_scene.gltf(filepath=str(path))
    else:
        bpy.ops.import_scene.fbx(filepath=str(path))


def armature():
    (arm,) = [o for o in bpy.context.scene.objects if o.type == "ARMATURE"]
    return arm


def posed_joints(frames) -> np.ndarray:
    """(len(frames), 16, 3) the contract joints on the armature at motion frames,
    turned from Blender's z-up world back to y up. The head top is the Head's tail
    where no Head_End bone came in (a BVH End Site)."""
    arm = armature()
    start = int(round(arm.animation_data.action.frame_range[0]))
    out = []
    for f in frames:
        bpy.context.scene.frame_set(start + f)
        row = []
        for name in _BONE_OF:
            bone = arm.pose.bones.get(name)
            point = bone.head if bone is not None else arm.pose.bones["Head"].tail
            p = arm.matrix_world @ point
            row.append((p.x, p.z, -p.y))
        out.append(row)
    return np.array(out)


@pytest.mark.parametrize("key", ["bvh", "glb", "fbx"])
def test_blender_poses_the_joints_of_the_motion_file(key, written, expected):
    load(key, written[key])
    error = np.abs(posed_joints(SAMPLES) - expected[list(SAMPLES)]).max()
    assert error < MM, f"{key}: {error * 1000:.2f} mm"


@pytest.mark.parametrize("key", ["glb", "fbx"])
def test_one_armature_one_action_one_skinned_mesh(key, written):
    load(key, written[key])
    arm = armature()
    meshes = [o for o in bpy.context.scene.objects if o.type == "MESH" and o.parent == arm]
    assert len(bpy.data.actions) == 1 and len(meshes) == 1
    (mesh,) = meshes
    assert [m.type for m in mesh.modifiers] == ["ARMATURE"] and mesh.modifiers[0].object == arm
    assert {g.name for g in mesh.vertex_groups} >= {"Hips", "Spine1", "LeftArm", "RightUpLeg"}
    assert len(mesh.data.materials) == 1
    assert set(_BONE_OF) - {"Head_End"} <= set(arm.data.bones.keys())


def test_the_bvh_rests_in_a_t_pose(written):
    load("bvh", written["bvh"])
    bones = armature().data.bones
    up = np.array([0.0, 0.0, 1.0])  # Blender's z is up
    for side, sign in (("Left", 1.0), ("Right", -1.0)):
        for name in ("Arm", "ForeArm", "Hand"):  # arms straight out sideways
            axis = np.array(bones[side + name].tail_local - bones[side + name].head_local)
            assert np.dot(axis / np.linalg.norm(axis), [sign, 0.0, 0.0]) > 0.999, side + name
        for name in ("UpLeg", "Leg"):  # legs straight down
            axis = np.array(bones[side + name].tail_local - bones[side + name].head_local)
            assert np.dot(axis / np.linalg.norm(axis), -up) > 0.999, side + name
    spine = np.array(bones["Head"].tail_local - bones["Hips"].head_local)
    assert np.dot(spine / np.linalg.norm(spine), up) > 0.99
