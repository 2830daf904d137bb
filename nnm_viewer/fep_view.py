"""Draw steps of a tab's selection: the branch list, the clickable FEP in the scene, the FEP image
of the panel and the selection sliders (state read from the ``Session``)."""
from __future__ import annotations

import numpy as np

from . import scene as sc
from .fep import FepRenderer, interp_at
from .worker import one_line


def entry_option(i, e):
    """Label of branch entry ``e`` (position ``i``) in the branch dropdown."""
    return f"{i + 1}: {e.label} ({len(e)} pts)"


class FepView:
    """The FEP of one tab: dropdown, board of clickable spheres, panel image, sliders."""

    def __init__(self, session):
        self.session = session
        self.ui = session.layout
        self.board_handles = {}      # uid -> batched-sphere handle (None: hidden)
        self.ranges = None           # axis ranges of the board
        self.renderer = FepRenderer(size=(480, 350))

    def check_selection(self):
        """Select the first branch if the selection vanished.  Returns True if the point shown
        must be (re)computed: it is missing or of another branch (a new branch selected, a
        streaming branch that got its first points)."""
        s = self.session
        entries = s.shared.snapshot()
        if not entries:
            return False
        vanished = s.selected_entry() is None
        if vanished:
            first = next((e for e in entries if len(e)), entries[0])
            with s.lock:
                s.sel_uid, s.s = first.uid, 0.0
        e = s.selected_entry()
        with s.lock:
            return vanished or (bool(len(e)) and (s.current_point is None or s.current_uid != e.uid))

    def draw_branch_list(self):
        """The branch dropdown, showing the selected branch."""
        s, ui = self.session, self.ui
        entries = s.shared.snapshot()
        if not entries:
            ui.set(ui.h_branch, options=("(none)",), value="(none)")
            return
        options = tuple(entry_option(i, e) for i, e in enumerate(entries))
        sel = s.shared.index_of(s.sel_uid)
        ui.set(ui.h_branch, options=options)
        ui.set(ui.h_branch, value=options[sel if sel is not None else 0])

    def draw_board(self):
        s = self.session
        entries, series = s._series()
        ranges = s._view_ranges(entries, series)
        self.ranges = ranges
        board = s.geom.board
        if not s.show_board:
            s.scene.remove_by_name("/fep")
            self.board_handles = {}
            return
        sc.draw_board_frame(s.scene, board, ranges, series)
        live = set()
        for e, ser in zip(entries, series):
            uid = e.uid
            if s.zoom and uid != s.sel_uid:            # zoomed: only the selected branch
                ser = ser.__class__(ser.energy[:0], ser.frequency[:0], ser.stable[:0], ser.label)
            live.add(uid)
            self.board_handles[uid] = sc.draw_board_points(s.scene, board, ranges, ser, uid,
                                                           on_click=self._click_handler(uid),
                                                           emphasized=(uid == s.sel_uid))
        for uid in list(self.board_handles):
            if uid not in live:
                s.scene.remove_by_name(f"/fep/b{uid}")
                del self.board_handles[uid]

    def _click_handler(self, uid):
        def on_click(event):
            try:
                self.session.pick(uid, event.instance_index)
            except Exception as exc:
                self.session.show_error(one_line(exc))
        return on_click

    def draw_series(self):
        """The branches of the panel image (redrawn when branches or the k3 factor change)."""
        s = self.session
        entries, series = s._series()
        ghost = [e.series(e.k3_factor) for e in entries] if abs(s.factor_log) > 1e-9 else []
        self.renderer.set_series(series, s.shared.index_of(s.sel_uid), ghosts=ghost,
                                 title=f"Frequency-energy plot (k3 x {s.factor:.3g})",
                                 ranges=s._view_ranges(entries, series) if s.zoom else None)

    def selected_point(self):
        """(energy J, frequency Hz) of the selection at the current k3 factor, or None
        (interpolated linearly in log energy, like the energy slider)."""
        s = self.session
        e = s.selected_entry()
        if e is None or not len(e):
            return None
        ser = e.series(s.factor)
        return 10 ** interp_at(np.log10(ser.energy), s.s), interp_at(ser.frequency, s.s)

    def draw_image(self):
        """The panel image with the selection marker, and the marker on the board."""
        s, ui = self.session, self.ui
        sel = self.selected_point()
        ui.h_fep.image = self.renderer.image(sel)
        board = s.geom.board
        if s.show_board and self.ranges is not None and sel is not None:
            pos = board.to_world([sel[0]], [sel[1]], self.ranges)[0]
            sc.draw_marker(s.scene, pos + 0.5 * board.point_radius() * board.normal, 1.6 * board.point_radius())
        elif sel is None:
            s.scene.remove_by_name("/fep/marker")

    def draw_sliders(self, skip=None):
        """Energy and along-branch sliders (``skip``: the one being dragged), selection text."""
        s, ui = self.session, self.ui
        e = s.selected_entry()
        if e is None or not len(e):
            ui.set(ui.h_energy, disabled=True)
            ui.set(ui.h_along, disabled=True)
            ui.set(ui.h_sel, content="no point selected: compute a branch in the Compute tab")
            return
        ser = e.series(s.factor)
        n = len(ser)
        with s.lock:
            s.s = float(np.clip(s.s, 0, n - 1))
            along = s.s
        le = np.log10(ser.energy)
        lo, hi = float(np.floor(le.min() * 100) / 100), float(np.ceil(le.max() * 100) / 100)
        if hi - lo < 0.02:
            lo, hi = lo - 0.01, hi + 0.01
        cur_le = interp_at(le, along)
        if skip != "energy":
            ui.set(ui.h_energy, min=lo, max=hi, disabled=False)
            ui.set(ui.h_energy, value=float(np.clip(round(cur_le, 2), lo, hi)))
        if skip != "along":
            ui.set(ui.h_along, min=0.0, max=float(max(n - 1, 0.01)), disabled=n < 2)
            ui.set(ui.h_along, value=float(round(along, 2)))
        f = interp_at(ser.frequency, along)
        st = "stable" if ser.stable[int(round(along))] else "unstable"
        idx = s.shared.index_of(s.sel_uid)
        options = ui.h_branch.options
        if idx is not None and idx < len(options):
            ui.set(ui.h_branch, value=options[idx])
        ui.set(ui.h_sel, content=f"**Selected:** branch {idx + 1}, point {along:.2f} of {n - 1}  \n"
                                 f"E = {10 ** cur_le:.4g} J, f = {f:.5g} Hz, {st}")
        ui.set(ui.h_recompute, disabled=abs(s.factor / e.k3_factor - 1.0) < 1e-9)
        ui.set(ui.h_save, disabled=e.saved or e.source == "running")
