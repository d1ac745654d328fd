"""GLB export of a Motion: the animated 10-cylinder body (glTF 2.0, binary).

One node per bone of ``mocap.lift.motion`` (same names, same hierarchy, translation =
the bone's offset, metres, y up). Each of the 10 cylinders is a mesh on the node
of its proximal joint (the torso on ``waist``, whose x axis follows the hips), its
cross-section the model's (``body.semi_axes`` at 1.75 m). One animation, one
sample per motion frame at 1/fps: a rotation channel per node and the root's
world translation; glTF's LINEAR interpolation of rotations is slerp.
"""

from __future__ import annotations

import json
import struct

import numpy as np

from mocap import body
from mocap.lift.motion import BONES, PARENTS, Motion, forward_kinematics

SIDES = 16                                      # facets around each cylinder
_OWNERS = {s: "waist" if s == "torso" else a for s, (a, _) in body.SEGMENTS.items()}
_FLOAT, _UINT16 = 5126, 5123
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963


def glb_bytes(motion: Motion) -> bytes:
    """The whole GLB file: header, JSON chunk, binary chunk."""
    doc = _Document()
    rest = rest_pose(motion.offsets)
    radii = body.semi_axes(body.BODY_HEIGHT_M)
    mesh_of = {}
    for i, (segment, (a, b)) in enumerate(body.SEGMENTS.items()):
        owner = BONES.index(_OWNERS[segment])
        mesh_of[owner] = doc.cylinder(segment, rest[BONES.index(a)] - rest[owner],
                                      rest[BONES.index(b)] - rest[owner], radii[i])
    doc.gltf.update(scene=0, scenes=[{"name": "mocap", "nodes": [0]}],
                    nodes=[_node(motion, b, mesh_of.get(b)) for b in range(len(BONES))],
                    animations=[doc.animation(motion)])
    return doc.glb()


def _node(motion: Motion, bone: int, mesh: int | None) -> dict:
    """A bone's glTF node, posed as in the first frame (for viewers that do not play)."""
    translation = motion.root[0] if bone == 0 else motion.offsets[bone]
    node = {"name": BONES[bone], "translation": translation.tolist(),
            "rotation": motion.rotations[0, bone].tolist()}
    children = np.flatnonzero(PARENTS == bone).tolist()
    if children:
        node["children"] = children
    if mesh is not None:
        node["mesh"] = mesh
    return node


def rest_pose(offsets: np.ndarray) -> np.ndarray:
    """(len(BONES), 3) bone positions with every rotation identity: a mesh drawn
    there in its node's frame follows the node's rotation."""
    identity = np.tile([0.0, 0.0, 0.0, 1.0], (1, len(BONES), 1))
    return forward_kinematics(offsets, identity)[0]


class _Document:
    """A glTF document being built: its JSON and one binary buffer."""

    def __init__(self) -> None:
        self.gltf: dict = {"asset": {"version": "2.0", "generator": "mocap"},
                           "bufferViews": [], "accessors": [], "meshes": []}
        self.blob = bytearray()

    def accessor(self, array: np.ndarray, kind: str, target: int | None = None,
                 bounds: bool = False) -> int:
        """Store an array (float32 or uint16) in its own buffer view; its accessor index."""
        self.blob += b"\0" * (-len(self.blob) % 4)
        view = {"buffer": 0, "byteOffset": len(self.blob), "byteLength": array.nbytes}
        view.update({"target": target} if target else {})
        self.blob += array.tobytes()
        self.gltf["bufferViews"].append(view)
        acc = {"bufferView": len(self.gltf["bufferViews"]) - 1, "count": len(array), "type": kind,
               "componentType": _UINT16 if array.dtype == np.uint16 else _FLOAT}
        if bounds:
            flat = array.reshape(len(array), -1)
            acc.update(min=flat.min(0).tolist(), max=flat.max(0).tolist())
        self.gltf["accessors"].append(acc)
        return len(self.gltf["accessors"]) - 1

    def cylinder(self, name: str, start: np.ndarray, end: np.ndarray, radii: np.ndarray) -> int:
        """Add a closed elliptic cylinder from start to end; its mesh index."""
        vertices, triangles = cylinder_mesh(start, end, radii)
        position = self.accessor(vertices.astype(np.float32), "VEC3", _ARRAY_BUFFER, bounds=True)
        indices = self.accessor(triangles.astype(np.uint16).ravel(), "SCALAR",
                                _ELEMENT_ARRAY_BUFFER)
        self.gltf["meshes"].append({"name": name, "primitives": [
            {"attributes": {"POSITION": position}, "indices": indices}]})
        return len(self.gltf["meshes"]) - 1

    def animation(self, motion: Motion) -> dict:
        """The one animation: root translation and every node's rotation per frame."""
        times = self.accessor(motion.times.astype(np.float32), "SCALAR", bounds=True)
        tracks = [(0, "translation", motion.root, "VEC3")] + [
            (b, "rotation", motion.rotations[:, b], "VEC4") for b in range(len(BONES))]
        samplers, channels = [], []
        for node, path, values, kind in tracks:
            samplers.append({"input": times, "interpolation": "LINEAR",
                             "output": self.accessor(values.astype(np.float32), kind)})
            channels.append({"sampler": len(samplers) - 1, "target": {"node": node, "path": path}})
        return {"name": "motion", "samplers": samplers, "channels": channels}

    def glb(self) -> bytes:
        """Pack the JSON and the buffer into GLB chunks (each 4-byte aligned)."""
        self.blob += b"\0" * (-len(self.blob) % 4)
        self.gltf["buffers"] = [{"byteLength": len(self.blob)}]
        text = json.dumps(self.gltf, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        length = 12 + 8 + len(text) + 8 + len(self.blob)
        return (struct.pack("<4sII", b"glTF", 2, length) + struct.pack("<I4s", len(text), b"JSON")
                + text + struct.pack("<I4s", len(self.blob), b"BIN\0") + bytes(self.blob))


def cylinder_mesh(start: np.ndarray, end: np.ndarray, radii: np.ndarray,
                  sides: int = SIDES) -> tuple[np.ndarray, np.ndarray]:
    """Vertices (2 * sides + 2, 3) and outward-facing triangles (4 * sides, 3) of a
    capped cylinder whose ellipse has radii[0] along x (made perpendicular to the
    axis) and radii[1] across; the two cap centres are the last two vertices."""
    axis = end - start
    unit = axis / max(np.linalg.norm(axis), 1e-12)
    lateral = np.array([1.0, 0.0, 0.0]) - unit[0] * unit
    if np.linalg.norm(lateral) < 1e-6:                # a segment along x: any normal
        lateral = np.array([0.0, 0.0, 1.0])
    lateral /= np.linalg.norm(lateral)
    across = np.cross(unit, lateral)
    angle = 2 * np.pi * np.arange(sides) / sides
    ring = np.outer(np.cos(angle) * radii[0], lateral) + np.outer(np.sin(angle) * radii[1], across)
    vertices = np.concatenate([start + ring, end + ring, [start, end]])
    i, j = np.arange(sides), (np.arange(sides) + 1) % sides
    bottom, top = np.full(sides, 2 * sides), np.full(sides, 2 * sides + 1)
    triangles = np.concatenate([
        np.stack([i, j, sides + j], 1), np.stack([i, sides + j, sides + i], 1),     # wall
        np.stack([bottom, j, i], 1), np.stack([top, sides + i, sides + j], 1)])     # caps
    return vertices, triangles
