"""GLB export of a Motion: a skinned glTF 2.0 character that Blender, Unity and Unreal import as one
armature (``mocap.lift.skeleton``'s bones, T-pose rest at the first frame's root), one mesh (the 10
cylinders, ``body.semi_axes`` at 1.75 m, and ``io.export.marks``' cones, riding their segments' bones;
the torso blends Hips to Spine1) and one animation (per frame at 1/fps: bone rotations, slerped by
glTF LINEAR, and the root's translation in the exports' world, floor at y = 0)."""

from __future__ import annotations

import numpy as np
import pygltflib as gl
import trimesh

from mocap import body
from mocap.io.export.marks import FACING_MARKS, facing_marks
from mocap.lift.motion import Motion
from mocap.lift.skeleton import BONE_INDEX, BONES, END_SITE, JOINT_BONES, PARENTS, rest_positions

SIDES = 16  # facets around each cylinder
COLOUR = [0.55, 0.62, 0.75, 1.0]  # the body's base colour (linear RGBA)
_JOINT = {j: BONES[b] for j, b in zip(body.JOINTS, JOINT_BONES)}
# the bones a segment's start and end rings follow
_RIDERS = {s: (_JOINT[a], _JOINT[a]) for s, (a, _) in body.SEGMENTS.items()} | {
    "torso": ("Hips", "Spine1"),
    "head": ("Neck", "Neck"),
}
_ANIMATED = np.flatnonzero(~END_SITE)  # End Sites never turn


def glb_bytes(motion: Motion) -> bytes:
    """The whole GLB file."""
    doc = _Document()
    rest = rest_positions(motion.offsets) + motion.world_root[0]
    nodes = [_bone_node(motion, b) for b in range(len(BONES))]
    skin_node = len(nodes)
    nodes.append(gl.Node(name="body", mesh=0, skin=0))
    nodes.append(gl.Node(name="Armature", children=[0, skin_node]))
    ibm = np.tile(np.eye(4, dtype=np.float32), (len(BONES), 1, 1))
    ibm[:, 3, :3] = -rest  # glTF matrices are column-major
    doc.gltf.nodes = nodes
    doc.gltf.skins = [
        gl.Skin(
            name="Armature", joints=list(range(len(BONES))), skeleton=0, inverseBindMatrices=doc.accessor(ibm, gl.MAT4)
        )
    ]
    doc.gltf.meshes = [doc.body_mesh(rest)]
    doc.gltf.materials = [
        gl.Material(
            name="body",
            doubleSided=False,
            pbrMetallicRoughness=gl.PbrMetallicRoughness(
                baseColorFactor=COLOUR, metallicFactor=0.0, roughnessFactor=0.8
            ),
        )
    ]
    doc.gltf.animations = [doc.animation(motion)]
    doc.gltf.scenes = [gl.Scene(name="mocap", nodes=[skin_node + 1])]
    doc.gltf.scene = 0
    return doc.glb()


def _bone_node(motion: Motion, bone: int) -> gl.Node:
    """A bone's glTF node in the rest pose (rotation identity)."""
    translation = motion.world_root[0] if bone == 0 else motion.offsets[bone]
    children = np.flatnonzero(PARENTS == bone).tolist()
    return gl.Node(name=BONES[bone], translation=[float(v) for v in translation], children=children)


def body_parts(rest: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The rest-pose mesh: vertices (V, 3), normals (V, 3), triangles (T, 3) and per vertex (V, 3)
    its start bone, end bone and the end bone's weight."""
    radii = body.semi_axes(body.BODY_HEIGHT_M)
    meshes, riders = [], []
    for i, (segment, (a, b)) in enumerate(body.SEGMENTS.items()):
        start, end = rest[BONE_INDEX[_JOINT[a]]], rest[BONE_INDEX[_JOINT[b]]]
        mesh = _cylinder(start, end, radii[i])
        along = (mesh.vertices - start) @ (end - start) / max(np.sum((end - start) ** 2), 1e-12)
        first, last = (BONE_INDEX[r] for r in _RIDERS[segment])
        riders.append(np.stack([np.full(len(along), first), np.full(len(along), last), np.clip(along, 0, 1)], axis=1))
        meshes.append(mesh)
    joints = np.array([rest[BONE_INDEX[_JOINT[j]]] for j in body.JOINTS])
    for (segment, along, *_), (base, out, size) in zip(FACING_MARKS.values(), facing_marks(joints)):
        meshes.append(_cone(base, out, size[0], size[1]))
        first, last = (BONE_INDEX[r] for r in _RIDERS[segment])
        riders.append(np.tile([first, last, along], (len(meshes[-1].vertices), 1)))
    whole = trimesh.util.concatenate(meshes)
    return (
        np.asarray(whole.vertices),
        np.asarray(whole.vertex_normals),
        np.asarray(whole.faces),
        np.concatenate(riders),
    )


def _cylinder(start: np.ndarray, end: np.ndarray, radii: np.ndarray) -> trimesh.Trimesh:
    """A closed elliptic cylinder from start to end, radii[0] across the body (x made
    perpendicular to the axis) and radii[1] front to back."""
    axis = end - start
    length = max(np.linalg.norm(axis), 1e-9)
    unit = axis / length
    lateral = np.array([1.0, 0.0, 0.0]) - unit[0] * unit
    if np.linalg.norm(lateral) < 1e-6:  # a segment along x: any normal
        lateral = np.array([0.0, 0.0, 1.0]) - unit[2] * unit
    lateral /= np.linalg.norm(lateral)
    transform = np.eye(4)
    transform[:3, :3] = np.stack([lateral * radii[0], np.cross(unit, lateral) * radii[1], unit * length], axis=1)
    transform[:3, 3] = (start + end) / 2
    return trimesh.creation.cylinder(radius=1.0, height=1.0, sections=SIDES, transform=transform)


def _cone(base: np.ndarray, out: np.ndarray, length: float, radius: float) -> trimesh.Trimesh:
    """A closed cone standing on ``base``, its tip ``length`` along the unit ``out``."""
    across = np.cross(out, [0.0, 1.0, 0.0] if abs(out[1]) < 0.9 else [1.0, 0.0, 0.0])
    across /= np.linalg.norm(across)
    transform = np.eye(4)
    transform[:3, :3] = np.stack([across * radius, np.cross(out, across) * radius, out * length], axis=1)
    transform[:3, 3] = base
    return trimesh.creation.cone(radius=1.0, height=1.0, sections=SIDES, transform=transform)


class _Document:
    """A glTF document being built and its one binary buffer."""

    def __init__(self) -> None:
        self.gltf = gl.GLTF2(asset=gl.Asset(version="2.0", generator="mocap"))
        self.blob = bytearray()

    def accessor(self, array: np.ndarray, kind: str, target: int | None = None, bounds: bool = False) -> int:
        """Store an array in its own buffer view (4-byte aligned); its accessor index."""
        self.blob += b"\0" * (-len(self.blob) % 4)
        self.gltf.bufferViews.append(
            gl.BufferView(buffer=0, byteOffset=len(self.blob), byteLength=array.nbytes, target=target)
        )
        self.blob += np.ascontiguousarray(array).tobytes()
        component = {
            np.dtype(np.float32): gl.FLOAT,
            np.dtype(np.uint16): gl.UNSIGNED_SHORT,
            np.dtype(np.uint32): gl.UNSIGNED_INT,
        }[array.dtype]
        acc = gl.Accessor(
            bufferView=len(self.gltf.bufferViews) - 1, componentType=component, count=len(array), type=kind
        )
        if bounds:
            flat = array.reshape(len(array), -1)
            acc.min, acc.max = flat.min(0).tolist(), flat.max(0).tolist()
        self.gltf.accessors.append(acc)
        return len(self.gltf.accessors) - 1

    def body_mesh(self, rest: np.ndarray) -> gl.Mesh:
        """The skinned body: positions, normals, two joint influences per vertex."""
        vertices, normals, faces, riders = body_parts(rest)
        joints = np.zeros((len(vertices), 4), np.uint16)
        weights = np.zeros((len(vertices), 4), np.float32)
        joints[:, :2] = riders[:, :2]
        weights[:, 0], weights[:, 1] = 1 - riders[:, 2], riders[:, 2]
        same = riders[:, 0] == riders[:, 1]  # one bone: all its weight
        weights[same] = [1.0, 0.0, 0.0, 0.0]
        buf = gl.ARRAY_BUFFER
        attributes = gl.Attributes(
            POSITION=self.accessor(vertices.astype(np.float32), gl.VEC3, buf, bounds=True),
            NORMAL=self.accessor(normals.astype(np.float32), gl.VEC3, buf),
            JOINTS_0=self.accessor(joints, gl.VEC4, buf),
            WEIGHTS_0=self.accessor(weights, gl.VEC4, buf),
        )
        indices = self.accessor(faces.astype(np.uint32).ravel(), gl.SCALAR, gl.ELEMENT_ARRAY_BUFFER)
        return gl.Mesh(name="body", primitives=[gl.Primitive(attributes=attributes, indices=indices, material=0)])

    def animation(self, motion: Motion) -> gl.Animation:
        """The one animation: the root's translation and every bone's rotation per frame."""
        times = self.accessor(motion.times.astype(np.float32), gl.SCALAR, bounds=True)
        tracks = [(0, "translation", motion.world_root, gl.VEC3)] + [
            (int(b), "rotation", motion.rotations[:, b], gl.VEC4) for b in _ANIMATED
        ]
        samplers, channels = [], []
        for node, path, values, kind in tracks:
            samplers.append(
                gl.AnimationSampler(
                    input=times, interpolation="LINEAR", output=self.accessor(values.astype(np.float32), kind)
                )
            )
            channels.append(
                gl.AnimationChannel(sampler=len(samplers) - 1, target=gl.AnimationChannelTarget(node=node, path=path))
            )
        return gl.Animation(name="motion", samplers=samplers, channels=channels)

    def glb(self) -> bytes:
        """The document and its buffer as GLB bytes (pygltflib lays out the chunks)."""
        self.gltf.buffers = [gl.Buffer(byteLength=len(self.blob))]
        self.gltf.set_binary_blob(bytes(self.blob))
        return b"".join(self.gltf.save_to_bytes())
