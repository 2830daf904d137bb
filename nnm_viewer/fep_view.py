"""Draw steps of a tab's selection: the branch list, the clickable FEP in the scene, the FEP image
of the panel and the selection sliders (state read from the ``Session``)."""
from __future__ import annotations

import numpy as np

from . import scene as sc
from .fep import Y_LABELS, FepRenderer, branch_color, energy_at, interp_at
from .info import linear_mode_title
from .numbering import point_words, slider_value
from .fep_text import branch_markdown, branch_options, point_facts, readout_markdown, sweep_markdown
from .worker import one_line

#: size (px) of the FEP image of the panel (the plot, and its legend below)
PANEL_FEP_SIZE = (480, 470)


class FepView:
    """The FEP of one tab: dropdown, board of clickable spheres, panel image, sliders."""

    def __init__(self, session):
        self.session = session
        self.ui = session.layout
        self.board_handles = {}      # uid -> batched-sphere handle (None: hidden)
        self.board_points = {}       # uid -> world positions (N, 3) of its spheres on the board
        self.board_group = None      # scene name of the spheres' group (scene.sphere_group)
        self.ranges = None           # axis ranges of the board
        self.renderer = FepRenderer(size=PANEL_FEP_SIZE)

    def check_selection(self):
        """Select the first branch if the selection vanished.  Returns True if the point shown
        must be (re)computed: it is missing or of another branch (a new branch selected, a
        streaming branch that got its first points)."""
        s = self.session
        entries = s.shared.snapshot()
        if not entries:
            return False
        first = next((e for e in entries if len(e)), entries[0])
        live = {e.uid for e in entries}
        v, old = s.change_view(lambda w: {} if w.sel_uid in live else dict(sel_uid=first.uid, s=0.0))
        vanished = old.sel_uid not in live
        e = s.selected_entry(v)
        if e is None:                     # removed meanwhile: the next 'branches' request selects again
            return False
        return vanished or (bool(len(e)) and v.linear_mode is None
                            and (v.current_point is None or v.current_uid != e.uid))

    def draw_branch_list(self):
        """The branch dropdown, showing the selected branch."""
        s, ui = self.session, self.ui
        entries = s.shared.snapshot()
        if not entries:
            ui.set(ui.h_branch, options=("(none)",), value="(none)")
            ui.set(ui.h_branch_info, content="")
            return
        listed = branch_options(entries)
        options = tuple(opt for _, opt in listed)
        sel_uid = s.view.sel_uid
        sel = next((i for i, e in enumerate(entries) if e.uid == sel_uid), 0)
        ui.set(ui.h_branch, options=options)
        ui.set(ui.h_branch, value=dict(listed)[sel])
        ui.set(ui.h_branch_info, content=sweep_markdown(entries[sel]) + branch_markdown(entries[sel]))

    def draw_board(self):
        s = self.session
        v = s.view
        entries, series = s._series(v)
        ranges = s._view_ranges(entries, series, v)
        self.ranges = ranges
        board = s.geom.board
        if not v.show_board:
            self.ui.set(self.ui.h_zoom, value=bool(s.zoomed(entries, series, v)))
            s.scene.remove_by_name("/fep")
            self.board_handles, self.board_points, self.board_group = {}, {}, None
            return
        group, old_group = sc.sphere_group(v.canvas), self.board_group
        if group != old_group:                        # a new canvas size: every sphere is added anew
            self.board_handles, self.board_group = {}, group
        zoomed = s.zoomed(entries, series, v)
        self.ui.set(self.ui.h_zoom, value=bool(zoomed))
        sc.draw_board_frame(s.scene, board, ranges, series, ylabel=Y_LABELS[bool(v.relative)])
        live = set()
        for k, (e, ser) in enumerate(zip(entries, series)):
            uid = e.uid
            if zoomed and uid != v.sel_uid:            # zoomed: only the selected branch
                ser = ser.__class__(ser.energy[:0], ser.frequency[:0], ser.stable[:0], ser.label)
            live.add(uid)
            self.board_points[uid] = board.to_world(ser.energy, ser.frequency, ranges) if len(ser) else None
            self.board_handles[uid] = sc.draw_board_points(s.scene, board, ranges, ser, uid,
                                                           on_click=self._click_handler(uid), name=group,
                                                           emphasized=(uid == v.sel_uid), color=branch_color(k))
        for uid in list(self.board_handles):
            if uid not in live:
                s.scene.remove_by_name(f"{group}/b{uid}")
                del self.board_handles[uid]
                self.board_points.pop(uid, None)
        if old_group is not None and old_group != group:
            s.scene.remove_by_name(old_group)

    def nearest_point(self, origin, direction):
        """(uid, index) of the board point seen nearest to the ray (origin, direction) of a click,
        i.e. nearest on the screen (smallest angle from the ray), or None."""
        o = np.asarray(origin, dtype=float)
        d = np.asarray(direction, dtype=float)
        d = d / max(np.linalg.norm(d), 1e-300)
        best, best_angle = None, np.inf
        for uid, pos in list(self.board_points.items()):
            if pos is None or not len(pos):
                continue
            v = pos - o
            along = v @ d
            perp = np.linalg.norm(v - along[:, None] * d, axis=1)
            angle = np.where(along > 0, np.arctan2(perp, along), np.inf)
            i = int(np.argmin(angle))
            if angle[i] < best_angle:
                best, best_angle = (uid, i), float(angle[i])
        return best

    def _click_handler(self, uid):
        """A click on a sphere of branch ``uid``: the point whose centre is nearest to the click on
        the screen is picked (overlapping spheres: not necessarily the one the ray hit first)."""
        def on_click(event):
            try:
                hit = None
                if getattr(event, "ray_origin", None) is not None and getattr(event, "ray_direction", None) is not None:
                    hit = self.nearest_point(event.ray_origin, event.ray_direction)
                self.session.pick(*(hit or (uid, event.instance_index)))
            except Exception as exc:
                self.session.show_error(one_line(exc))
        return on_click

    def draw_series(self):
        """The branches of the panel image (redrawn when branches or the k3 factor change)."""
        s = self.session
        v = s.view
        entries, series = s._series(v)
        # the branches as computed, in grey, behind their scaled FEP (scaling law only)
        ghost = ([s.fep_series(e, e.k3_factor, v) for e in entries if e.scalable]
                 if s.scaling_law and abs(v.factor_log) > 1e-9 else [])
        zoomed = s.zoomed(entries, series, v)
        title = ("Frequency-energy plot" + (f" (k3 x {v.factor:.3g})" if s.scaling_law else "")
                 + (", zoomed on the selected branch" if zoomed else ""))
        sel = next((i for i, e in enumerate(entries) if e.uid == v.sel_uid), None)
        self.renderer.set_series(series, sel, ghosts=ghost, title=title,
                                 ranges=s._view_ranges(entries, series, v) if zoomed else None,
                                 ylabel=Y_LABELS[bool(v.relative)],
                                 measured=self.measured_points(entries[sel], v) if sel is not None else None)

    def measured_points(self, e, v):
        """(energy J, frequency on the view's axis, label) of the measured backbone placed on entry ``e``'s
        branch at the view's k3 factor (nnm_viewer/measured.py), or None."""
        from .measured import on_fep

        s = self.session
        m = s.shared.measured
        if m is None or not len(e):
            return None
        pts = on_fep(m, e.branch, e.series(s.view_factor(e, v)).energy, e.branch.energy)
        if pts is None:
            return None
        f = pts[1]
        if v.relative:
            f_lin = e.linear_frequency(s.shared.linear_freqs)
            f = 100.0 * (f / f_lin - 1.0) if f_lin else f
        return pts[0], f, m.label

    def selected_point(self, v=None):
        """(energy J, frequency on the FEP's axis: Hz or %) of the selection of view ``v`` at its k3 factor,
        or None (the energy of the orbit shown, fep.energy_at: linear in energy, as Branch.interpolate)."""
        s = self.session
        v = v or s.view
        e = s.selected_entry(v)
        if e is None or not len(e):
            return None
        ser = s.fep_series(e, v=v)
        return energy_at(ser.energy, v.s), interp_at(ser.frequency, v.s)

    def draw_image(self):
        """The panel image with the selection marker, and the marker on the board."""
        s, ui = self.session, self.ui
        v = s.view
        sel = self.selected_point(v)
        ui.h_fep.image = self.renderer.image(sel)
        self.draw_readout(v)
        board = s.geom.board
        if v.show_board and self.ranges is not None and sel is not None:
            pos = board.to_world([sel[0]], [sel[1]], self.ranges)[0]
            sc.draw_marker(s.scene, pos + 0.5 * board.point_radius() * board.normal, 1.6 * board.point_radius())
        elif sel is None:
            s.scene.remove_by_name("/fep/marker")

    def draw_readout(self, v=None):
        """The picked point's readout under the panel image; while a linear mode is animated instead
        (Modes tab) it says so first, so that it never names as shown a point that is not."""
        s, ui = self.session, self.ui
        v = v or s.view
        e = s.selected_entry(v)
        text = readout_markdown(s, e, v) if e is not None and len(e) else "no point picked"
        k = v.linear_mode
        if k is not None:
            text = (f"**Shown:** {linear_mode_title(s.model, s.shared.linear_freqs, k)} (Modes tab); pick a "
                    "point or move a slider to animate the picked point again  \n" + text)
        ui.set(ui.h_readout, content=text)

    def draw_sliders(self, skip=None):
        """Energy and along-branch sliders (``skip``: the one being dragged), selection text.  The
        Along-branch slider gives the point's number, 1 .. n, as the texts do."""
        s, ui = self.session, self.ui
        v = s.view
        e = s.selected_entry(v)
        if e is None or not len(e):
            ui.set(ui.h_energy, disabled=True)
            ui.set(ui.h_along, disabled=True)
            ui.set(ui.h_sel, content="no point selected: compute a branch in the Compute tab")
            return
        ser = e.series(s.view_factor(e, v))
        n = len(ser)
        uid = e.uid
        v, _ = s.change_view(lambda w: dict(s=float(np.clip(w.s, 0, n - 1))) if w.sel_uid == uid else {})
        along = float(np.clip(v.s, 0, n - 1))
        le = np.log10(ser.energy)
        lo, hi = float(np.floor(le.min() * 100) / 100), float(np.ceil(le.max() * 100) / 100)
        if hi - lo < 0.02:
            lo, hi = lo - 0.01, hi + 0.01
        energy = energy_at(ser.energy, along)
        cur_le = float(np.log10(energy))
        if skip != "energy":
            ui.set(ui.h_energy, min=lo, max=hi, disabled=False)
            ui.set(ui.h_energy, value=float(np.clip(round(cur_le, 2), lo, hi)))
        if skip != "along":
            ui.set(ui.h_along, min=1.0, max=float(max(n, 1.01)), disabled=n < 2)
            ui.set(ui.h_along, value=float(round(slider_value(along), 2)))
        f = interp_at(ser.frequency, along)
        st = ", ".join(point_facts(e, along)[:2])
        entries = s.shared.snapshot()
        idx = next((i for i, x in enumerate(entries) if x.uid == uid), None)
        if idx is None:                   # removed meanwhile: the next draw shows the new selection
            return
        option = dict(branch_options(entries)).get(idx)
        if option is not None and option in ui.h_branch.options:
            ui.set(ui.h_branch, value=option)
        ui.set(ui.h_sel, content=f"**Selected:** branch {idx + 1}, {point_words(along, n)}  \n"
                                 f"E = {energy:.4g} J, f = {f:.5g} Hz, {st}")
        ui.set(ui.h_recompute, disabled=abs(v.factor / e.k3_factor - 1.0) < 1e-9)
        ui.set(ui.h_save, disabled=e.saved or e.source == "running")
