"""Minimal binary glTF (GLB) writer for one triangle mesh with morph targets.

The orbit of an NNM is shown as a GLB whose morph targets are vertex-displacement shapes
(the orbit's harmonics) and whose single animation samples the morph weights over one
period.  The browser (three.js AnimationMixer, used by viser for GLBs) then plays the
periodic motion in a loop with no per-frame traffic.

No NORMAL attribute is written on purpose: three.js' GLTFLoader then uses flat shading
computed from screen-space derivatives, so the shading follows the deformed surface.
"""
from __future__ import annotations

import json
import struct

import numpy as np

_FLOAT = 5126
_UBYTE = 5121
_UINT = 5125
_ARRAY_BUFFER = 34962
_ELEMENT_ARRAY_BUFFER = 34963


class _Buffer:
    """Accumulates 4-byte aligned binary chunks and their glTF bufferViews/accessors."""

    def __init__(self):
        self.chunks: list[bytes] = []
        self.size = 0
        self.views: list[dict] = []
        self.accessors: list[dict] = []

    def add(self, array, component, type_, target=None, normalized=False, minmax=False):
        data = np.ascontiguousarray(array).tobytes()
        view = {"buffer": 0, "byteOffset": self.size, "byteLength": len(data)}
        if target is not None:
            view["target"] = target
        self.views.append(view)
        pad = (-len(data)) % 4
        self.chunks.append(data + b"\x00" * pad)
        self.size += len(data) + pad
        arr = np.asarray(array)
        count = arr.shape[0]
        acc = {"bufferView": len(self.views) - 1, "componentType": component, "count": int(count),
               "type": type_}
        if normalized:
            acc["normalized"] = True
        if minmax:
            flat = arr.reshape(count, -1) if arr.ndim > 1 else arr.reshape(count, 1)
            acc["min"] = [float(v) for v in flat.min(axis=0)]
            acc["max"] = [float(v) for v in flat.max(axis=0)]
        self.accessors.append(acc)
        return len(self.accessors) - 1

    def blob(self):
        return b"".join(self.chunks)


def build_glb(vertices, faces, colors=None, targets=None, times=None, weights=None,
              default_weights=None, name="nnm"):
    """Return GLB bytes of one mesh, optionally with morph targets and a weight animation.

    vertices : (V, 3) float, m.  faces : (F, 3) int.  colors : (V, 3) or (V, 4) uint8 RGB(A),
    or None for light grey.  targets : (T, V, 3) float vertex displacements, m (already
    multiplied by any display amplification).  times : (K,) s, strictly increasing keyframe
    times; weights : (K, T) morph weights at those times (linear interpolation, looped by
    the viewer).  default_weights : (T,) weights of the static pose (default zeros).
    """
    V = np.asarray(vertices, dtype=np.float32).reshape(-1, 3)
    F = np.asarray(faces, dtype=np.uint32).reshape(-1, 3)
    nv = len(V)
    if colors is None:
        colors = np.full((nv, 3), 200, dtype=np.uint8)
    C = np.asarray(colors, dtype=np.uint8)
    if C.shape[1] == 3:
        C = np.concatenate([C, np.full((nv, 1), 255, dtype=np.uint8)], axis=1)
    buf = _Buffer()
    pos = buf.add(V, _FLOAT, "VEC3", _ARRAY_BUFFER, minmax=True)
    col = buf.add(C, _UBYTE, "VEC4", _ARRAY_BUFFER, normalized=True)
    idx = buf.add(F.reshape(-1), _UINT, "SCALAR", _ELEMENT_ARRAY_BUFFER)
    primitive = {"attributes": {"POSITION": pos, "COLOR_0": col}, "indices": idx, "material": 0,
                 "mode": 4}
    mesh = {"name": name, "primitives": [primitive]}
    gltf = {
        "asset": {"version": "2.0", "generator": "nnm_viewer"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": name}],
        "meshes": [mesh],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0,
                                                "roughnessFactor": 0.75},
                       "doubleSided": True}],
    }
    if targets is not None and len(targets):
        T = np.asarray(targets, dtype=np.float32).reshape(len(targets), nv, 3)
        primitive["targets"] = [{"POSITION": buf.add(T[k], _FLOAT, "VEC3", _ARRAY_BUFFER, minmax=True)}
                                for k in range(len(T))]
        dw = np.zeros(len(T)) if default_weights is None else np.asarray(default_weights, dtype=float)
        mesh["weights"] = [float(w) for w in dw]
        if times is not None:
            t = np.asarray(times, dtype=np.float32).reshape(-1)
            W = np.asarray(weights, dtype=np.float32).reshape(len(t), len(T))
            tin = buf.add(t, _FLOAT, "SCALAR", minmax=True)
            wout = buf.add(W.reshape(-1), _FLOAT, "SCALAR")
            gltf["animations"] = [{
                "name": "orbit",
                "samplers": [{"input": tin, "output": wout, "interpolation": "LINEAR"}],
                "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            }]
    blob = buf.blob()
    gltf["buffers"] = [{"byteLength": len(blob)}]
    gltf["bufferViews"] = buf.views
    gltf["accessors"] = buf.accessors
    js = json.dumps(gltf, separators=(",", ":")).encode()
    js += b" " * ((-len(js)) % 4)
    total = 12 + 8 + len(js) + 8 + len(blob)
    return b"".join([
        struct.pack("<4sII", b"glTF", 2, total),
        struct.pack("<I4s", len(js), b"JSON"), js,
        struct.pack("<I4s", len(blob), b"BIN\x00"), blob,
    ])


def read_glb_json(glb):
    """The JSON chunk of GLB bytes as a dict (for tests and debugging)."""
    magic, version, total = struct.unpack_from("<4sII", glb, 0)
    if magic != b"glTF" or version != 2 or total != len(glb):
        raise ValueError("not a GLB 2.0 blob")
    n, kind = struct.unpack_from("<I4s", glb, 12)
    return json.loads(glb[20:20 + n])
