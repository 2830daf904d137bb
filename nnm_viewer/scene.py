"""3D scene: the model's mesh (GLB, animated by morph targets), the camera, and the
clickable copy of the FEP (batched spheres, one instance per branch point)."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

import nnm_solver

from .glb import build_glb
from .board import BOARD_MARGINS, BoardLayout, board_layout
from .fep import MARKER_RGB, STABLE_RGB, UNSTABLE_RGB, off_backbone_style, pale, rgb

#: vertical field of view of the initial camera, degrees
CAMERA_FOV_DEG = 50.0
#: direction from the scene centre to the initial camera (z up)
CAMERA_DIR = np.array([0.9, -1.25, 0.75])
#: largest number of DOFs drawn by the fallback mesh of a model without a mesh
FALLBACK_MAX_DOF = 400


#: auto amplification: the peak displacement is shown as this fraction of the model size
AUTO_PEAK_FRACTION = 0.12


def auto_amplification(geom, peak):
    """The display amplification that shows a physical peak displacement ``peak`` (m) as
    AUTO_PEAK_FRACTION of the model size (1 for a motion at rest)."""
    return AUTO_PEAK_FRACTION * geom.size / peak if peak > 0 else 1.0


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


def view_geometry(vertices, aspect=0.85, fill=0.92):
    """Camera and FEP-board placement for a mesh with the given vertices (V, 3) m: the camera
    looks along -CAMERA_DIR, from the nearest distance at which the model's bounding box and the
    board fit in a viewport of width/height ``aspect`` (``fill``: fraction of the half-height used)."""
    v = np.asarray(vertices, dtype=float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    center = 0.5 * (lo + hi)
    size = float(max(np.max(hi - lo), 1e-9))
    d = CAMERA_DIR / np.linalg.norm(CAMERA_DIR)
    f = -d
    board = board_layout(lo, hi, f)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    bc = np.array([board.origin + a * board.width * board.right + b * board.height * board.up
                   for a in (-_ML, 1 + _MR) for b in (-_MB, 1 + _MT)])
    pts = np.concatenate([corners, bc])
    look_at = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    t = fill * np.tan(np.radians(CAMERA_FOV_DEG) / 2)
    rel = pts - look_at
    depth = rel @ f
    dist = float(max(np.max(np.abs(rel @ r) / (t * aspect) - depth), np.max(np.abs(rel @ u) / t - depth)))
    return ViewGeometry(center=center, size=size, board=board, camera_position=look_at + d * max(dist, 1e-6),
                        camera_look_at=look_at)


#: view presets: direction from the model's centre to the camera (z up); 'Top' leans a little toward -y
#: so that the camera's up direction (z) stays defined
PRESET_DIRECTIONS = {"Iso": CAMERA_DIR, "Top": np.array([0.0, -0.02, 1.0]), "Side": np.array([0.0, -1.0, 0.0]),
                     "Front": np.array([-1.0, 0.0, 0.0])}


def preset_camera(vertices, name, fov_deg=CAMERA_FOV_DEG, fill=0.85):
    """(position, look_at) of the camera preset ``name`` ('Iso', 'Top', 'Side', 'Front') framing the
    mesh ``vertices`` (V, 3) m: its bounding sphere fills ``fill`` of the vertical field of view."""
    if name not in PRESET_DIRECTIONS:
        raise ValueError(f"unknown view {name!r}; choose one of {', '.join(PRESET_DIRECTIONS)}")
    v = np.asarray(vertices, dtype=float)
    lo, hi = v.min(axis=0), v.max(axis=0)
    center = 0.5 * (lo + hi)
    radius = max(0.5 * float(np.linalg.norm(hi - lo)), 1e-9)
    d = PRESET_DIRECTIONS[name] / np.linalg.norm(PRESET_DIRECTIONS[name])
    dist = radius / (fill * np.sin(np.radians(fov_deg) / 2))
    return center + d * dist, center


def static_glb(mesh):
    """GLB of the undeformed mesh in light grey (before any orbit is picked)."""
    return build_glb(mesh.vertices, mesh.faces)


def project_points(points, geom, box):
    """Screen pixels (N, 2) of world points (N, 3) m seen by the initial camera of ``geom``
    (z up, vertical field of view geom.fov_deg) drawing into the canvas rectangle ``box``
    (dict x, y, width, height in px, as given by a browser).  Used to click FEP points in
    browser tests and to frame screenshots."""
    cam = np.asarray(geom.camera_position, dtype=float)
    f = np.asarray(geom.camera_look_at, dtype=float) - cam
    f /= np.linalg.norm(f)
    r = np.cross(f, [0.0, 0.0, 1.0])
    r /= np.linalg.norm(r)
    u = np.cross(r, f)
    d = np.asarray(points, dtype=float) - cam
    z = d @ f
    t = np.tan(np.radians(geom.fov_deg) / 2)
    nx = (d @ r) / (z * t * box["width"] / box["height"])
    ny = (d @ u) / (z * t)
    return np.stack([box["x"] + (nx + 1) / 2 * box["width"], box["y"] + (1 - ny) / 2 * box["height"]], axis=1)


_SPHERE = None


def sphere_mesh():
    """Unit icosphere (vertices, faces) used for FEP points."""
    global _SPHERE
    if _SPHERE is None:
        import trimesh
        s = trimesh.creation.icosphere(subdivisions=2, radius=1.0)
        _SPHERE = (np.asarray(s.vertices, dtype=np.float32), np.asarray(s.faces, dtype=np.uint32))
    return _SPHERE


#: legend entries of the board picture at most
BOARD_LEGEND_MAX = 14
#: margins of the board picture around the plotting area (board.BOARD_MARGINS)
_ML, _MR, _MB, _MT = BOARD_MARGINS


def render_board(board, ranges, series=(), width_px=900, ylabel=None):
    """The board picture (RGB uint8): axes, ticks, labels and thin branch lines; the plotting
    area maps exactly onto the rectangle of ``board`` so that the spheres sit on the curves."""
    fig = board_figure(board, ranges, series, width_px, ylabel)
    return np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()


def fit_left_labels(fig, ax, smallest=10):
    """Shrink the y tick labels and the y axis label until they fit in the figure's left margin (long tick labels,
    '31.7825', pushed the axis label out of the picture)."""
    for _ in range(6):
        fig.canvas.draw()
        renderer = fig.canvas.get_renderer()
        left = min([t.get_window_extent(renderer).x0 for t in ax.get_yticklabels() if t.get_text()]
                   + [ax.yaxis.label.get_window_extent(renderer).x0])
        if left >= 2:
            return
        size = ax.get_yticklabels()[0].get_fontsize() if ax.get_yticklabels() else smallest
        if size <= smallest:
            return
        ax.tick_params(axis="y", labelsize=max(smallest, 0.85 * size))
        ax.yaxis.label.set_fontsize(max(smallest, 0.85 * ax.yaxis.label.get_fontsize()))


def board_figure(board, ranges, series=(), width_px=900, ylabel=None):
    """The drawn matplotlib Figure of ``render_board`` (its axes fill the board's rectangle; the
    legend is in the bottom margin, below the tick labels)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from .fep import Y_LABELS, plot_branches, set_fep_axes

    wq, hq = board.width * (1 + _ML + _MR), board.height * (1 + _MB + _MT)
    dpi = 100
    fig = Figure(figsize=(width_px / dpi, width_px * hq / wq / dpi), dpi=dpi, facecolor="#f7f7f4")
    FigureCanvasAgg(fig)
    ax = fig.add_axes([_ML / (1 + _ML + _MR), _MB / (1 + _MB + _MT), 1 / (1 + _ML + _MR), 1 / (1 + _MB + _MT)])
    ax.set_facecolor("#ffffff")
    # thin lines, and event markers large enough to ring the spheres drawn in front of the picture
    handles, labels = plot_branches(ax, series, points=False, lw=2.0, ms=10.0, event_ms=24.0, event_mew=3.0,
                                    ranges=ranges, legend_max=BOARD_LEGEND_MAX)
    set_fep_axes(ax, ranges, ticks_size=19, label_size=21, grid_alpha=0.3, ylabel=ylabel or Y_LABELS[False])
    fit_left_labels(fig, ax)
    if handles:
        # below the plotting area, never over the curves (nor over the spheres drawn in front of them)
        ax.legend(handles[:BOARD_LEGEND_MAX], labels[:BOARD_LEGEND_MAX], fontsize=14, loc="upper center",
                  bbox_to_anchor=(0.5, -0.15), ncol=2, frameon=False, markerscale=0.6, handlelength=1.5,
                  columnspacing=1.2)
    ax.set_title("FEP: click a point to animate it", fontsize=22)
    fig.canvas.draw()
    return fig


def board_rotation(board):
    """Quaternion wxyz turning viser's image frame (x right, y down, seen from -z) onto the board."""
    import viser.transforms as vtf

    R = np.stack([board.right, -board.up, -board.normal], axis=1)
    return vtf.SO3.from_matrix(R).wxyz


_BOARD_CACHE: dict = {}


def cached_board(board, ranges, series, ylabel=None):
    """render_board with a small cache (the same picture is drawn for every tab)."""
    import hashlib
    h = hashlib.sha1(repr((ranges, board.width, board.height, ylabel)).encode())
    for ser in series:
        h.update(np.asarray(ser.energy, dtype=float).tobytes())
        h.update(np.asarray(ser.frequency, dtype=float).tobytes())
        h.update(np.asarray(ser.stable, dtype=bool).tobytes())
        h.update(repr((ser.label, ser.status, ser.events, tuple(lab for lab, _ in ser.off_backbone()))).encode())
    key = h.hexdigest()
    img = _BOARD_CACHE.get(key)
    if img is None:
        img = render_board(board, ranges, series, ylabel=ylabel)
        if len(_BOARD_CACHE) > 8:
            _BOARD_CACHE.clear()
        _BOARD_CACHE[key] = img
    return img


def draw_board_frame(scene, board, ranges, series=(), name="/fep", ylabel=None):
    """The FEP board picture (axes, ticks, labels, curves) as one textured quad, not clickable."""
    img = cached_board(board, ranges, series, ylabel)
    wq, hq = board.width * (1 + _ML + _MR), board.height * (1 + _MB + _MT)
    center = (board.origin + board.right * board.width * (1 + _MR - _ML) / 2
              + board.up * board.height * (1 + _MT - _MB) / 2 - 0.01 * board.height * board.normal)
    return scene.add_image(f"{name}/backdrop", img, render_width=wq, render_height=hq, format="png",
                           cast_shadow=False, receive_shadow=False, wxyz=board_rotation(board),
                           position=tuple(center))


def sphere_group(canvas):
    """Scene name of the board spheres' group for a canvas of ``canvas`` = (width, height) px (None: not known
    yet).  viser 1.1 sizes the hover outline of a clickable sphere with the canvas size read when the spheres
    are first added under a name (controls.Session._on_camera): a new size, a new name, a fresh outline."""
    return "/fep/spheres" if canvas is None else f"/fep/spheres_{int(canvas[0])}x{int(canvas[1])}"


def draw_board_points(scene, board, ranges, series, uid, on_click, emphasized=False, name="/fep", color=None):
    """One batched-sphere object for a branch: instance i = point i, in the branch's ``color``
    ('#rrggbb'; stable: that colour, unstable: paler), or blue/red by stability when None; the points off the
    backbone (a tongue's) in the solver's colour for them (fep.off_backbone_style), paler when unstable; returns
    its handle."""
    if not len(series):
        scene.remove_by_name(f"{name}/b{uid}")
        return None
    V, F = sphere_mesh()
    pos = board.to_world(series.energy, series.frequency, ranges)
    stable_rgb, unstable_rgb = (STABLE_RGB, UNSTABLE_RGB) if color is None else (rgb(color), rgb(pale(color)))
    stable = np.asarray(series.stable, dtype=bool)
    colors = np.where(stable[:, None], stable_rgb, unstable_rgb).astype(np.uint8)
    off_color = off_backbone_style()[1]                # points off the backbone (a tongue's): the solver's colour
    for _, mask in series.off_backbone():
        colors[mask & stable] = rgb(off_color)
        colors[mask & ~stable] = rgb(pale(off_color))
    rad = board.point_radius() * (1.0 if emphasized else 0.7)
    if len(pos) > 2:   # dense branches: spheres no bigger than ~half the typical spacing
        gap = float(np.median(np.linalg.norm(np.diff(pos, axis=0), axis=1)))
        rad = float(np.clip(0.5 * gap, 0.35 * board.point_radius(), rad))
    h = scene.add_batched_meshes_simple(
        f"{name}/b{uid}", vertices=V * rad, faces=F,
        batched_wxyzs=np.tile([1.0, 0.0, 0.0, 0.0], (len(pos), 1)), batched_positions=pos,
        batched_colors=colors, lod="off", cast_shadow=False, receive_shadow=False)
    h.on_click(on_click)
    return h


def draw_ghost(scene, mesh, visible, name="/ghost"):
    """The undeformed structure, translucent grey (not clickable); removed when not ``visible``."""
    if not visible:
        scene.remove_by_name(name)
        return None
    return scene.add_mesh_simple(name, vertices=np.asarray(mesh.vertices, dtype=np.float32),
                                 faces=np.asarray(mesh.faces, dtype=np.uint32), color=(150, 150, 150), opacity=0.3,
                                 flat_shading=True, side="double", cast_shadow=False, receive_shadow=False)


def draw_marker(scene, position, radius, name="/fep/marker"):
    """The picked point on the board (a larger yellow sphere, not clickable)."""
    V, F = sphere_mesh()
    return scene.add_mesh_simple(name, vertices=V * radius, faces=F, color=MARKER_RGB,
                                 position=tuple(np.asarray(position, dtype=float)), cast_shadow=False,
                                 receive_shadow=False)
