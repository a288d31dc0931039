"""A small binary glTF 2.0 (GLB) writer and reader: numpy and struct, nothing else.

A scene is a list of :class:`GlbMesh` (triangles or line segments, optional
per-vertex colours, one material each).  Positions are given in the model's
frame (z up, mm) and written in glTF's (y up, metres) unless told otherwise.

GLB layout: 12-byte header ``magic 'glTF', version 2, total length``, then a
JSON chunk (padded with spaces to 4 bytes) and a BIN chunk (padded with zeros).
"""
from __future__ import annotations

import json
import struct
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from optimize import jsontext
from optimize.atomic import atomic_path
from optimize.errors import writing

GLB_MAGIC = 0x46546C67  # b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942
FLOAT, UINT32 = 5126, 5125
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963
MODES = {"lines": 1, "triangles": 4}
# model frame (x, y, z) z-up -> glTF (x, z, -y) y-up
Z_UP_TO_Y_UP = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


@dataclass(frozen=True)
class GlbMesh:
    """One primitive of the scene.

    positions : (k, 3) float, model frame.
    indices : (t, 3) int triangles, or (e, 2) int segments for ``mode="lines"``.
    colors : (k, 3) or (k, 4) float in [0, 1], or None (then ``color`` alone).
    color : RGBA base colour of the material (multiplies the vertex colours).
    """

    name: str
    positions: np.ndarray
    indices: np.ndarray
    colors: np.ndarray | None = None
    color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    metallic: float = 0.0
    roughness: float = 0.8
    mode: str = "triangles"
    visible: bool = True  # False: the viewer starts with it hidden (node extras {"hidden": true})


def glb_bytes(meshes: list[GlbMesh], *, mm_to_m: bool = True, z_up: bool = True,
              generator: str = "conical-fab") -> bytes:
    """Encode ``meshes`` as one GLB file (one node per mesh)."""
    if not meshes:
        raise ValueError("a GLB scene needs at least one mesh")
    gltf = {"asset": {"version": "2.0", "generator": generator}, "scene": 0,
            "scenes": [{"nodes": list(range(len(meshes)))}], "nodes": [], "meshes": [],
            "materials": [], "accessors": [], "bufferViews": [], "buffers": []}
    blob = bytearray()

    def add(array: np.ndarray, kind: str, comp: int, target: int, bounds: bool = False) -> int:
        while len(blob) % 4:
            blob.append(0)
        data = np.ascontiguousarray(array).tobytes()
        gltf["bufferViews"].append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data),
                                    "target": target})
        blob.extend(data)
        acc = {"bufferView": len(gltf["bufferViews"]) - 1, "componentType": comp,
               "count": int(array.shape[0]), "type": kind}
        if bounds:
            acc["min"] = array.min(axis=0).astype(float).tolist()
            acc["max"] = array.max(axis=0).astype(float).tolist()
        gltf["accessors"].append(acc)
        return len(gltf["accessors"]) - 1

    M = Z_UP_TO_Y_UP if z_up else np.eye(3)
    scale = 1e-3 if mm_to_m else 1.0
    for i, m in enumerate(meshes):
        P = np.asarray(m.positions, dtype=np.float64)
        idx = np.asarray(m.indices, dtype=np.int64)
        per = 2 if m.mode == "lines" else 3
        if P.ndim != 2 or P.shape[1] != 3 or len(P) == 0:
            raise ValueError(f"{m.name}: positions have shape {P.shape}, expected (k, 3) with k > 0")
        if idx.ndim != 2 or idx.shape[1] != per or len(idx) == 0:
            raise ValueError(f"{m.name}: indices have shape {idx.shape}, expected (t, {per}) with t > 0")
        if idx.min() < 0 or idx.max() >= len(P):
            raise ValueError(f"{m.name}: indices range {idx.min()}..{idx.max()}, expected 0..{len(P) - 1}")
        attributes = {"POSITION": add((P @ M.T * scale).astype(np.float32), "VEC3", FLOAT,
                                      ARRAY_BUFFER, bounds=True)}
        if m.colors is not None:
            C = np.clip(np.asarray(m.colors, dtype=np.float32), 0.0, 1.0)
            if C.shape not in ((len(P), 3), (len(P), 4)):
                raise ValueError(f"{m.name}: colors have shape {C.shape}, expected ({len(P)}, 3|4)")
            attributes["COLOR_0"] = add(C, "VEC3" if C.shape[1] == 3 else "VEC4", FLOAT, ARRAY_BUFFER)
        indices = add(idx.astype(np.uint32).ravel(), "SCALAR", UINT32, ELEMENT_ARRAY_BUFFER)
        material = {"name": m.name, "doubleSided": True,
                    "pbrMetallicRoughness": {"baseColorFactor": [float(c) for c in m.color],
                                             "metallicFactor": float(m.metallic),
                                             "roughnessFactor": float(m.roughness)}}
        if m.color[3] < 1.0:
            material["alphaMode"] = "BLEND"
        gltf["materials"].append(material)
        gltf["meshes"].append({"name": m.name, "primitives": [
            {"attributes": attributes, "indices": indices, "material": i, "mode": MODES[m.mode]}]})
        node = {"name": m.name, "mesh": i}
        if not m.visible:
            node["extras"] = {"hidden": True}
        gltf["nodes"].append(node)
    while len(blob) % 4:
        blob.append(0)
    gltf["buffers"].append({"byteLength": len(blob)})
    text = json.dumps(gltf, separators=(",", ":")).encode("utf-8")
    text += b" " * (-len(text) % 4)
    total = 12 + 8 + len(text) + 8 + len(blob)
    return b"".join([struct.pack("<III", GLB_MAGIC, 2, total),
                     struct.pack("<II", len(text), CHUNK_JSON), text,
                     struct.pack("<II", len(blob), CHUNK_BIN), bytes(blob)])


def write_glb(path: str | Path, meshes: list[GlbMesh], **kwargs) -> dict:
    """Write ``meshes`` to ``path`` atomically; return facts for the report."""
    data = glb_bytes(meshes, **kwargs)
    with writing(path, "glTF model", needed=len(data)), atomic_path(path) as tmp:
        Path(tmp).write_bytes(data)
    return {"file": Path(path).name, "bytes": len(data), "meshes": len(meshes)}


def read_glb(data: bytes) -> tuple[dict, bytes]:
    """Split a GLB into its JSON document and binary chunk; ValueError naming what is wrong."""
    if len(data) < 20:
        raise ValueError(f"GLB too short: {len(data)} bytes")
    magic, version, total = struct.unpack_from("<III", data, 0)
    if magic != GLB_MAGIC or version != 2:
        raise ValueError(f"not a GLB 2.0 file (magic {magic:#x}, version {version})")
    if total != len(data):
        raise ValueError(f"GLB header says {total} bytes, file has {len(data)}")
    n_json, kind = struct.unpack_from("<II", data, 12)
    if kind != CHUNK_JSON:
        raise ValueError(f"first GLB chunk has type {kind:#x}, expected JSON")
    doc = jsontext.loads(data[20:20 + n_json])
    off = 20 + n_json
    binary = b""
    if off < len(data):
        n_bin, kind = struct.unpack_from("<II", data, off)
        if kind != CHUNK_BIN:
            raise ValueError(f"second GLB chunk has type {kind:#x}, expected BIN")
        binary = data[off + 8: off + 8 + n_bin]
    return doc, binary


def read_accessor(doc: dict, binary: bytes, index: int) -> np.ndarray:
    """The array of accessor ``index``: (count,) or (count, components)."""
    acc = doc["accessors"][index]
    view = doc["bufferViews"][acc["bufferView"]]
    dtype = {FLOAT: np.float32, UINT32: np.uint32}[acc["componentType"]]
    width = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}[acc["type"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    arr = np.frombuffer(binary, dtype=dtype, count=acc["count"] * width, offset=start)
    return arr if width == 1 else arr.reshape(-1, width)
