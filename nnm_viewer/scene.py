"""3D scene: the model's mesh (GLB, animated by morph targets), the camera, and the
clickable copy of the FEP (batched spheres, one instance per branch point)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import nnm_solver

from .glb import build_glb
from .fep import MARKER_RGB, STABLE_RGB, UNSTABLE_RGB, BoardLayout, board_layout

#: vertical field of view of the initial camera, degrees
CAMERA_FOV_DEG = 50.0
#: direction from the scene centre to the initial camera (z up)
CAMERA_DIR = np.array([0.9, -1.25, 0.75])
#: largest number of DOFs drawn by the fallback mesh of a model without a mesh
FALLBACK_MAX_DOF = 400


def fallback_mesh(n):
    """A mesh for models that have none: one small box per DOF along x, each moving
    vertically (z) with its DOF (1 m of x_j = 1 m of motion)."""
    m = min(n, FALLBACK_MAX_DOF)
    corners = np.array([[x, y, z] for x in (-0.3, 0.3) for y in (-0.3, 0.3) for z in (-0.3, 0.3)])
    box_faces = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                          [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    verts, faces = [], []
    D = np.zeros((3 * 8 * m, n))
    for j in range(m):
        verts.append(corners + [j * 1.0, 0.0, 0.0])
        faces.append(box_faces + 8 * j)
        for c in range(8):
            D[3 * (8 * j + c) + 2, j] = 1.0
    return nnm_solver.DisplayMesh(vertices=np.concatenate(verts), faces=np.concatenate(faces),
                                  displacement_map=D)


@dataclass
class ViewGeometry:
    """Where things go: model centre and size (m), FEP board layout, initial camera."""

    center: np.ndarray
    size: float
    board: BoardLayout
    camera_position: np.ndarray
    camera_look_at: np.ndarray
    fov_deg: float = CAMERA_FOV_DEG


def view_geometry(vertices):
    """Camera and FEP-board placement for a mesh with the given vertices (V, 3) m."""
    v = np.asarray(vertices, dtype=float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    center = 0.5 * (lo + hi)
    size = float(max(np.max(hi - lo), 1e-9))
    d = CAMERA_DIR / np.linalg.norm(CAMERA_DIR)
    board = board_layout(lo, hi, -d)
    board_center = board.origin + 0.5 * board.width * board.right + 0.5 * board.height * board.up
    look_at = 0.5 * (center + board_center)
    span = np.linalg.norm(board_center - center) + 0.75 * size
    dist = 1.05 * span / np.tan(np.radians(CAMERA_FOV_DEG) / 2)
    return ViewGeometry(center=center, size=size, board=board, camera_position=look_at + d * dist,
                        camera_look_at=look_at)


def static_glb(mesh):
    """GLB of the undeformed mesh in light grey (before any orbit is picked)."""
    return build_glb(mesh.vertices, mesh.faces)


_SPHERE = None


def sphere_mesh():
    """Unit icosphere (vertices, faces) used for FEP points."""
    global _SPHERE
    if _SPHERE is None:
        import trimesh
        s = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        _SPHERE = (np.asarray(s.vertices, dtype=np.float32), np.asarray(s.faces, dtype=np.uint32))
    return _SPHERE


def draw_board_frame(scene, board, ranges, name="/fep"):
    """The FEP board: a light backdrop, axes and a few tick labels (not clickable)."""
    o, r, u, n = board.origin, board.right, board.up, board.normal
    W, H = board.width, board.height
    quad = np.array([o - 0.05 * W * r - 0.08 * H * u, o + 1.03 * W * r - 0.08 * H * u,
                     o + 1.03 * W * r + 1.05 * H * u, o - 0.05 * W * r + 1.05 * H * u]) - 0.01 * H * n
    scene.add_mesh_simple(f"{name}/backdrop", vertices=quad, faces=np.array([[0, 1, 2], [0, 2, 3]]),
                          color=(245, 245, 240), side="double", opacity=0.85, cast_shadow=False,
                          receive_shadow=False)
    axes = np.array([[o, o + W * r], [o, o + H * u]])
    scene.add_line_segments(f"{name}/axes", points=axes, colors=(60, 60, 60), thickness=2.0,
                            thickness_units="screen")
    (elo, ehi), (flo, fhi) = ranges
    labels = []
    for e in range(int(np.ceil(elo)), int(np.floor(ehi)) + 1):
        p = o + (e - elo) / (ehi - elo) * W * r - 0.05 * H * u
        labels.append((f"1e{e}", p))
    for k in range(3):
        f = flo + (k + 0.5) / 3 * (fhi - flo)
        p = o + (f - flo) / (fhi - flo) * H * u - 0.02 * W * r
        labels.append((f"{f:.4g}", p))
    labels.append(("energy (J)", o + 0.5 * W * r - 0.1 * H * u))
    labels.append(("frequency (Hz)", o + 1.03 * H * u))
    # Remove stale labels first: the number of ticks changes with the range.
    for k in range(len(labels), 40):
        scene.remove_by_name(f"{name}/label{k}")
    for k, (text, p) in enumerate(labels[:40]):
        scene.add_label(f"{name}/label{k}", text=text, position=tuple(p), font_screen_scale=0.7)


def draw_board_points(scene, board, ranges, series, uid, on_click, emphasized=False, name="/fep"):
    """One batched-sphere object for a branch: instance i = point i; returns its handle."""
    if not len(series):
        scene.remove_by_name(f"{name}/b{uid}")
        return None
    V, F = sphere_mesh()
    pos = board.to_world(series.energy, series.frequency, ranges)
    colors = np.where(np.asarray(series.stable, dtype=bool)[:, None], STABLE_RGB, UNSTABLE_RGB).astype(np.uint8)
    rad = board.point_radius() * (1.0 if emphasized else 0.7)
    h = scene.add_batched_meshes_simple(
        f"{name}/b{uid}", vertices=V * rad, faces=F,
        batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (len(pos), 1)), batched_positions=pos,
        batched_colors=colors, lod="off", cast_shadow=False, receive_shadow=False)
    h.on_click(on_click)
    return h


def draw_marker(scene, position, radius, name="/fep/marker"):
    """The picked point on the board (a larger yellow sphere, not clickable)."""
    V, F = sphere_mesh()
    return scene.add_mesh_simple(name, vertices=V * radius, faces=F, color=MARKER_RGB,
                                 position=tuple(np.asarray(position, dtype=float)), cast_shadow=False,
                                 receive_shadow=False)
