"""Viewer building blocks without a server: GLB writer, orbit animation, FEP mapping/image, info."""
import io
import struct

import numpy as np
import pytest

from nnm_solver import ShootingSettings, fourier_amplitudes
from nnm_viewer.animation import format_length, fourier_fit, orbit_animation
from nnm_viewer.fep import (LEGEND_MAX, FepRenderer, FepSeries, axis_ranges, energy_at, energy_to_s, interp_at,
                             render_fep)
from nnm_viewer.fep_view import PANEL_FEP_SIZE
from nnm_viewer.glb import build_glb, read_glb_json
from nnm_viewer.info import parse_dofs
from nnm_viewer.scene import BOARD_LEGEND_MAX, board_figure, fallback_mesh, view_geometry


def _tetra():
    V = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    return V, F


def test_glb_structure_morph_targets_and_animation():
    V, F = _tetra()
    targets = np.random.default_rng(0).normal(size=(3, 4, 3))
    times = np.linspace(0, 2, 9)
    W = np.random.default_rng(1).normal(size=(9, 3))
    glb = build_glb(V, F, colors=np.full((4, 3), 100, np.uint8), targets=targets, times=times, weights=W)
    assert glb[:4] == b"glTF" and struct.unpack_from("<I", glb, 8)[0] == len(glb)
    assert len(glb) % 4 == 0
    js = read_glb_json(glb)
    prim = js["meshes"][0]["primitives"][0]
    assert set(prim["attributes"]) == {"POSITION", "COLOR_0"}      # no NORMAL: flat shading follows morphs
    assert len(prim["targets"]) == 3 and len(js["meshes"][0]["weights"]) == 3
    for t in prim["targets"]:
        acc = js["accessors"][t["POSITION"]]
        assert acc["count"] == 4 and "min" in acc and "max" in acc   # required by glTF for POSITION
    anim = js["animations"][0]
    assert anim["channels"][0]["target"]["path"] == "weights"
    sampler = anim["samplers"][0]
    assert js["accessors"][sampler["input"]]["max"] == [2.0]
    assert js["accessors"][sampler["output"]]["count"] == 9 * 3


def test_glb_loads_in_trimesh():
    trimesh = pytest.importorskip("trimesh")
    V, F = _tetra()
    glb = build_glb(V, F, targets=np.ones((1, 4, 3)) * 0.1, times=[0, 1], weights=[[0], [1]])
    scene = trimesh.load(io.BytesIO(glb), file_type="glb")
    mesh = list(scene.geometry.values())[0]
    assert mesh.vertices.shape == (4, 3) and mesh.faces.shape == (4, 3)


def test_fourier_fit_recovers_harmonics_with_or_without_endpoint():
    T = 0.7
    for endpoint in (False, True):
        t = np.linspace(0, T, 64, endpoint=endpoint)
        w = 2 * np.pi / T
        x = np.stack([0.1 + 2 * np.cos(w * t) + 0.3 * np.sin(3 * w * t), -np.cos(w * t)], axis=1)
        orders, c = fourier_fit(t, x, T, n_harm=15)
        assert orders[0] == 0 and orders[1] == orders[2] == 1
        assert c[0] == pytest.approx([0.1, 0.0], abs=1e-10)
        assert c[1] == pytest.approx([2.0, -1.0], abs=1e-10)         # a_1
        assert c[6] == pytest.approx([0.3, 0.0], abs=1e-10)          # b_3


def test_orbit_animation_peak_colors_and_harmonic_pruning():
    mesh = fallback_mesh(2)
    T = 2.0
    t = np.arange(128) * T / 128
    w = 2 * np.pi / T
    x = np.stack([0.5 * np.cos(w * t) + 0.05 * np.cos(3 * w * t), 0.2 * np.cos(w * t)], axis=1)
    anim = orbit_animation(mesh.vertices, mesh.faces, mesh.displacements, t, x, T)
    assert set(anim.orders.tolist()) == {1, 3}                        # even harmonics dropped
    assert anim.peak_max == pytest.approx(0.55, rel=1e-3)             # true peak, m
    assert anim.peak[anim.peak_vertex] == anim.peak_max
    assert anim.peak[:8] == pytest.approx(np.full(8, 0.55), rel=1e-3)
    # the morph weights reproduce the motion at any phase
    d = anim.displacement([0.25])[0]
    xs = np.array([0.5 * np.cos(np.pi / 2) + 0.05 * np.cos(3 * np.pi / 2), 0.2 * np.cos(np.pi / 2)])
    assert d[:, 2] == pytest.approx(mesh.displacements(xs)[:, 2], abs=1e-9)
    colors = anim.colors()
    assert colors.shape == (len(mesh.vertices), 3) and colors.dtype == np.uint8
    assert not np.array_equal(colors[0], colors[8])                   # box 1 moves more than box 2
    js = read_glb_json(anim.glb(10.0, display_period=2.0))
    assert len(js["meshes"][0]["primitives"][0]["targets"]) == len(anim.orders)
    assert "animations" in js
    assert "animations" not in read_glb_json(anim.glb(10.0, playing=False, phase=0.3))


def test_energy_to_s_monotonic_fold_and_out_of_range():
    E = np.array([1e-3, 1e-2, 1e-1, 1.0])
    assert energy_to_s(E, 1e-2) == pytest.approx(1.0)
    # linear in energy between points, as Branch.interpolate: the orbit at the index has the target energy
    assert energy_to_s(E, 10 ** -1.5) == pytest.approx(1 + (10 ** -1.5 - 1e-2) / (1e-1 - 1e-2))
    assert energy_at(E, energy_to_s(E, 0.37)) == pytest.approx(0.37)
    assert energy_to_s(E, 1e3) == 3.0 and energy_to_s(E, 1e-9) == 0.0
    # a fold (tongue): energy up, down, up -- the crossing nearest to the current point wins
    F = np.array([1.0, 10.0, 100.0, 10.0, 1.0, 10.0, 100.0, 1000.0])
    assert energy_to_s(F, 10.0, s_current=0.5) == pytest.approx(1.0)
    assert energy_to_s(F, 10.0, s_current=3.2) == pytest.approx(3.0)
    assert energy_to_s(F, 10.0, s_current=5.5) == pytest.approx(5.0)
    assert energy_to_s([5.0], 1.0) == 0.0
    assert interp_at([0.0, 2.0, 4.0], 1.25) == pytest.approx(2.5)


def test_fep_image_and_ranges():
    a = FepSeries(np.logspace(-3, 1, 10), np.linspace(1.0, 1.2, 10), np.array([True] * 7 + [False] * 3), "NNM 1")
    empty = FepSeries(np.zeros(0), np.zeros(0), np.zeros(0, bool), "empty")
    (elo, ehi), (flo, fhi) = axis_ranges([a, empty])
    assert elo < -3 < 1 < ehi and flo < 1.0 < 1.2 < fhi
    img = render_fep([a, empty], selected=(0.1, 1.1), selected_branch=0, size=(300, 200))
    assert img.shape == (200, 300, 3) and img.dtype == np.uint8
    assert img.std() > 10
    assert render_fep([], size=(300, 200)).shape == (200, 300, 3)    # no branch: a hint, no crash


def _inside(inner, outer, tol=0.5):
    return (inner.x0 >= outer.x0 - tol and inner.y0 >= outer.y0 - tol and inner.x1 <= outer.x1 + tol
            and inner.y1 <= outer.y1 + tol)


def _many_series(n=11):
    return [FepSeries(np.logspace(-2, 1, 12), 31.7 - 0.01 * k - np.linspace(0, 0.3, 12), np.ones(12, bool),
                      f"NNM {10 + k} · tongue {k} (3:1)", events=[("fold", 5.0, 31.6)]) for k in range(n)]


def test_panel_fep_title_and_legend_fit_in_the_image():
    """Issue 32, finding (f): the panel image's title (the long zoomed, scaled one) and its legend (as many
    entries as it holds) are inside the image, and the legend is below the axes, not on the curves."""
    r = FepRenderer(size=PANEL_FEP_SIZE)
    r.set_series(_many_series(16), 0, title="Frequency-energy plot (k3 x 3.16), zoomed on the selected branch")
    fig = r.fig
    renderer = r.canvas.get_renderer()
    box = fig.bbox
    title = r.ax.title.get_window_extent(renderer)
    legend = fig.legends[0].get_window_extent(renderer)
    axes = r.ax.get_tightbbox(renderer)
    assert "\n" in r.ax.get_title()                        # wrapped
    assert _inside(title, box) and _inside(legend, box) and _inside(axes, box)
    assert legend.y1 <= r.ax.get_window_extent(renderer).y0  # below the plotting area
    assert len(fig.legends[0].get_texts()) == LEGEND_MAX


def test_board_legend_is_outside_the_plotting_area():
    """Issue 32, finding (g): the in-scene board's legend is in its bottom margin, inside the picture and
    never over the plotting area (where the curves and the clickable spheres are), even full and zoomed."""
    geom = view_geometry(np.array([[0, 0, 0], [10, 4, 2]], float))
    fig = board_figure(geom.board, ((-2.2, 1.2), (31.3, 31.75)), _many_series(14))
    renderer = fig.canvas.get_renderer()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent(renderer)
    area = ax.get_window_extent(renderer)
    ticks = ax.xaxis.get_tightbbox(renderer)
    assert _inside(legend, fig.bbox) and legend.y1 <= ticks.y0 < area.y0
    assert len(ax.get_legend().get_texts()) == BOARD_LEGEND_MAX


def test_board_layout_maps_corners_and_faces_camera():
    geom = view_geometry(np.array([[0, 0, 0], [10, 4, 2]], float))
    b = geom.board
    ranges = ((-2.0, 2.0), (1.0, 3.0))
    p = b.to_world([1e-2, 1e2], [1.0, 3.0], ranges)
    lift = 0.02 * b.height * b.normal
    assert p[0] == pytest.approx(b.origin + lift)
    assert p[1] == pytest.approx(b.origin + b.width * b.right + b.height * b.up + lift)
    to_cam = geom.camera_position - (b.origin + 0.5 * b.width * b.right)
    assert np.dot(to_cam, b.normal) > 0                                # the board faces the camera


def test_info_helpers():
    assert parse_dofs("auto", 5, [3, 1]) == [3, 1]
    assert parse_dofs("0, 4", 5, []) == [0, 4]
    with pytest.raises(ValueError, match="does not exist"):
        parse_dofs("7", 5, [])
    with pytest.raises(ValueError, match="not an integer"):
        parse_dofs("a", 5, [])
    t = np.arange(64) / 64
    x = np.stack([np.cos(2 * np.pi * t) + 0.1 * np.cos(6 * np.pi * t)], axis=1)
    h = fourier_amplitudes(x, 15)
    assert h.shape == (16, 1) and h[1, 0] == pytest.approx(1.0) and h[3, 0] == pytest.approx(0.1)
    assert format_length(0.0123) == "12.3 mm" and format_length(2.0) == "2 m"


def test_point_data_falls_back_to_a_computed_point():
    from nnm_viewer.info import point_data

    class Stub:
        """Branch-like: integrating interpolated states fails, computed points work."""
        energy, frequency_hz, period = np.array([1.0, 2.0]), np.array([1.0, 1.1]), np.array([1.0, 0.9])
        stable, floquet = np.array([True, False]), np.ones((2, 4), complex)
        settings = ShootingSettings(steps_per_period=64)

        def __init__(self, interpolated=False):
            self.interpolated = interpolated

        def __len__(self):
            return 1 if self.interpolated else 2

        def interpolate(self, s):
            return Stub(True)

        def motion(self, i, samples):
            if self.interpolated:
                raise RuntimeError("time integration of point 0 failed")
            t = np.arange(samples) * self.period[i] / samples
            return t, np.stack([np.cos(2 * np.pi * t / self.period[i]), 0 * t], axis=1)

        def mac_to_linear(self, i):
            return np.array([1.0, 0.0])

    pd = point_data(Stub(), 0.7)
    assert pd.energy == 2.0 and not pd.stable and "showing computed point 2" in pd.note     # row 1, numbered from 1
    assert len(pd.t) == 64 and pd.harmonics[1, 0] == pytest.approx(1.0)


def test_info_panel_names_the_orbit_from_its_harmonics(two_dof_nnm1):
    from nnm_viewer.info import info_markdown, point_data
    b = two_dof_nnm1
    tip = [e for e in b.events if e["kind"] == "fold"][1]["index"]
    pd = point_data(b, float(tip))
    assert pd.description.startswith("3:1 internal resonance")
    text = info_markdown(pd, b.model, b.model.linear_modes()[0])
    assert "3:1 internal resonance" in text
    assert "fundamental NNM motion" in point_data(b, 0.0).description


def test_fep_series_of_a_branch_without_multipliers_says_so():
    """A branch computed with floquet=False has NaN multipliers: its points are drawn filled but its legend
    label says that the stability was not computed (not that they are stable)."""
    import nnm_solver as nnm
    from nnm_viewer.state import BranchEntry
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=1.0)])
    off = nnm.continue_nnm(m, 1, 1.0, floquet=False, max_points=8)
    on = nnm.continue_nnm(m, 1, 1.0, max_points=8)
    assert BranchEntry(off, "NNM 1").series().label.endswith("(stability not computed)")
    assert "stability" not in BranchEntry(on, "NNM 1").series().label


def test_point_facts_and_info_say_when_the_harmonics_do_not_resolve_a_point(two_dof_nnm1):
    """A harmonic-balance point whose truncation estimate is inf (orbits/hb_error.py: no orbit with two harmonics
    more near it) is shown as not resolved, not as an error of 'inf'; a finite estimate is shown as a number."""
    from nnm_viewer.fep_text import point_facts
    from nnm_viewer.info import info_markdown, point_data
    from nnm_viewer.state import BranchEntry
    b = two_dof_nnm1
    err = np.full(len(b), 2e-5)
    err[3] = np.inf
    b2 = type(b).__new__(type(b))
    b2.__dict__.update(b.__dict__)
    b2.freq_error = err
    e = BranchEntry(b2, "NNM 1")
    assert any("not resolved by the harmonics" in f for f in point_facts(e, 3.0))
    assert any("estimated frequency error 2.0e-05" in f for f in point_facts(e, 2.0))
    pd = point_data(b2, 3.0)
    assert "not resolved by the harmonics" in info_markdown(pd, b.model, b.model.linear_modes()[0], freq_error=np.inf)
    assert "estimated relative error 2.0e-05" in info_markdown(pd, b.model, b.model.linear_modes()[0], freq_error=2e-5)


def test_one_nearest_point_rule_the_branchs_interpolate():
    """Halfway between two computed points the texts and the orbit name the same neighbour: the upper one from
    weight 0.5 on, as Branch.interpolate (numbering.nearest_row), not Python's round (round(70.5) == 70)."""
    from pathlib import Path

    import nnm_solver as nnm
    from nnm_viewer.fep_text import point_facts
    from nnm_viewer.info import point_data
    from nnm_viewer.numbering import nearest_row
    from nnm_viewer.point_view import point_label_and_error
    from nnm_viewer.state import BranchEntry

    assert [nearest_row(s, 5) for s in (0.0, 0.49, 0.5, 2.5, 3.5, 3.99, 4.0, 7.0, -1.0)] == [0, 0, 1, 3, 4, 4, 4, 4, 0]
    assert nearest_row(0.0, 1) == 0 and nearest_row(0.7, 1) == 0
    b = nnm.load_branches(Path(__file__).resolve().parents[1] / "assets" / "two_dof.h5")[0]
    assert bool(b.stable[70]) and not bool(b.stable[71])
    for s in (70.5, 70.49, 70.51, 71.0):
        ref = b.interpolate(s)
        assert bool(ref.stable[0]) == bool(b.stable[nearest_row(s, len(b))])
    e = BranchEntry(b, "NNM 1")
    assert point_facts(e, 70.5)[0] == "unstable" and point_facts(e, 70.49)[0] == "stable"
    assert point_data(b, 70.5, samples=64).stable is False
    # labels follow the same rule
    labels = np.array(["a"] * len(b), dtype=object)
    labels[71] = "b"
    b2 = type(b).__new__(type(b))
    b2.__dict__.update(b.__dict__)
    b2.labels = labels
    assert point_label_and_error(b2, 70.5)[0] == "b" and point_label_and_error(b2, 70.49)[0] == "a"


def test_point_texts_of_a_branch_without_multipliers_say_stability_not_computed():
    """floquet=False: ``stable`` is True for want of a test (Branch.stability_known False): the selection text
    and the Point tab say the stability was not computed, and list no (NaN) multipliers."""
    import nnm_solver as nnm
    from nnm_viewer.fep_text import point_facts
    from nnm_viewer.info import info_markdown, point_data
    from nnm_viewer.state import BranchEntry
    m = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs=[nnm.CubicSpring(dof=0, k3=0.5)])
    off = nnm.continue_nnm(m, 1, 1.0, floquet=False, max_points=8)
    assert not off.stability_known.any()
    facts = point_facts(BranchEntry(off, "NNM 1"), 2.0)
    assert facts[0] == "stability not computed" and "stable" not in facts
    for s in (2.0, 2.5):
        pd = point_data(off, s)
        assert pd.stability_known is False and pd.scaled(10.0).stability_known is False
        text = info_markdown(pd, m, m.linear_modes()[0])
        assert "stability: **not computed**" in text and "**stable**" not in text
        assert "Floquet multipliers:" not in text and "nan" not in text
    on = nnm.continue_nnm(m, 1, 1.0, max_points=8)
    pd = point_data(on, 2.0)
    assert pd.stability_known
    text = info_markdown(pd, m, m.linear_modes()[0])
    assert "stability: **stable**" in text and "Floquet multipliers: max |mu| = 1.0" in text
    assert point_facts(BranchEntry(on, "NNM 1"), 2.0)[0] == "stable"
