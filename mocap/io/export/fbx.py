"""FBX export of a Motion: the GLB export's skinned character imported into an empty Blender scene
(``bpy``: ``pip install 'mocap[fbx]'``, Python 3.11) and written with the settings Unity and Unreal
expect (y up, -z forward, baked on every frame, no extra leaf bones). Blender runs in a child process
(``python -m mocap.io.export.fbx GLB FBX FPS``) to keep its log and state out of ours."""

from __future__ import annotations

import importlib.util
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING

from mocap.errors import MocapError

if TYPE_CHECKING:
    from mocap.lift.motion import Motion

BLENDER_TIMEOUT_S = 600


def has_blender() -> bool:
    """Whether ``bpy`` can be imported here (without importing it: that takes seconds)."""
    return importlib.util.find_spec("bpy") is not None


def fbx_bytes(motion: "Motion") -> bytes:
    """The motion as an FBX file (mocap.io.export.formats checks that bpy is here)."""
    # imported here: every command reads has_blender, and trimesh is slow to import
    from mocap.io.export.glb import glb_bytes

    with tempfile.TemporaryDirectory(prefix="mocap-fbx-") as folder:
        glb, fbx = Path(folder) / "motion.glb", Path(folder) / "motion.fbx"
        glb.write_bytes(glb_bytes(motion))
        try:
            done = subprocess.run(
                [sys.executable, "-m", __name__, str(glb), str(fbx), repr(motion.fps)],
                capture_output=True,
                text=True,
                timeout=BLENDER_TIMEOUT_S,
            )
        except subprocess.TimeoutExpired:
            raise MocapError(f"Blender did not write the FBX within {BLENDER_TIMEOUT_S} s") from None
        if done.returncode != 0 or not fbx.exists():
            last = (done.stderr.strip().splitlines() or ["no message"])[-1]
            raise MocapError(f"Blender could not write the FBX: {last}")
        return fbx.read_bytes()


def convert(glb: str, fbx: str, fps: float) -> None:
    """In Blender: import the GLB into an empty scene at ``fps`` and export it as FBX."""
    import bpy

    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    # Blender's frame rate is an integer over a base (29.97 = 30 / 1.001)
    scene.render.fps = max(1, round(fps))
    scene.render.fps_base = scene.render.fps / fps
    bpy.ops.import_scene.gltf(filepath=glb)
    for obj in list(scene.objects):  # the importer's bone display shapes
        if obj.type not in ("ARMATURE", "MESH") or (obj.type == "MESH" and not obj.parent):
            bpy.data.objects.remove(obj)
    action = next(o for o in scene.objects if o.type == "ARMATURE").animation_data.action
    scene.frame_start, scene.frame_end = (int(round(f)) for f in action.frame_range)
    bpy.ops.export_scene.fbx(
        filepath=fbx,
        object_types={"ARMATURE", "MESH"},
        axis_forward="-Z",
        axis_up="Y",
        add_leaf_bones=False,
        bake_anim=True,
        bake_anim_use_all_actions=False,
        bake_anim_use_nla_strips=False,
        bake_anim_simplify_factor=0.0,
        bake_anim_force_startend_keying=True,
    )


if __name__ == "__main__":
    convert(sys.argv[1], sys.argv[2], float(sys.argv[3]))
