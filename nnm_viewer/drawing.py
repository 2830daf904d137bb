"""Drawing of a tab: requests are coalesced and drawn by one thread per tab (latest state
wins), in the order the user waits for them: the animation first, then the FEP, the sliders
and the information panel.  Each step is isolated: a failure (e.g. the solver cannot integrate
an orbit) is shown in the page and the other steps still run.
"""
from __future__ import annotations

import logging
import time

import numpy as np

from . import scene as sc
from .animation import orbit_animation
from .fep import axis_ranges, interp_at
from .info import auto_dofs, info_markdown, parse_dofs, peak_text, point_data, uplot_harmonics, uplot_time_series
from .worker import one_line

log = logging.getLogger("nnm_viewer")

#: auto amplification: the peak displacement is shown as this fraction of the model size
AUTO_PEAK_FRACTION = 0.12
#: everything a new tab draws
ALL_KINDS = ("branches", "fep", "sliders", "point", "glb", "info", "progress", "error")


class SessionDrawing:
    """Mixin of Session: redraw requests and the draw steps (state is read under self.lock)."""

    def request(self, *kinds):
        """Ask for redraws: 'branches', 'fep', 'sliders' (or 'sliders:energy'/'sliders:along'),
        'point', 'glb', 'info', 'progress', 'error'."""
        with self.lock:
            self._dirty.update(kinds)
        if self.sync:
            self.flush()
        else:
            self._wake.set()

    def flush(self):
        """Draw everything requested so far (in the caller's thread, one drawer at a time)."""
        with self._draw_lock:
            while True:
                with self.lock:
                    kinds, self._dirty = self._dirty, set()
                if not kinds or self._closed:
                    return
                try:
                    self._draw(kinds)
                except Exception as exc:
                    self.show_error(one_line(exc))

    def _loop(self):
        while not self._closed:
            self._wake.wait(0.5)
            self._wake.clear()
            if self._closed:
                break
            self.flush()

    def close(self):
        self._closed = True
        self._wake.set()
        self.shared.unsubscribe(self._on_shared)

    def _entry_option(self, i, e):
        return f"{i + 1}: {e.label} ({len(e)} pts)"

    def _draw(self, kinds):
        t0 = time.perf_counter()
        self._draw_all(kinds)
        log.info("drew %s in %.3f s", ",".join(sorted(kinds)), time.perf_counter() - t0)

    def _draw_all(self, kinds):
        """Run the draw steps for ``kinds``; a failing step (e.g. the solver cannot integrate
        an orbit) is reported in the page and does not stop the others."""
        def step(fn, *args):
            try:
                fn(*args)
                return True
            except Exception as exc:
                self.show_error(one_line(exc))
                return False

        if "branches" in kinds:
            step(self._draw_branch_list)
            step(self._draw_board)
            kinds |= {"fep", "sliders", "fep_series"}
        if "point" in kinds and step(self._compute_point):
            kinds |= {"glb", "info"}
        if "glb" in kinds:            # first: the animation is what the user waits for
            step(self._draw_glb)
        if "fep_series" in kinds:
            step(self._draw_fep_series)
        if "fep" in kinds:
            step(self._draw_fep)
        slider_kinds = {k for k in kinds if k.startswith("sliders")}
        if slider_kinds:
            skip = None
            if slider_kinds == {"sliders:along"}:
                skip = "energy"
            elif slider_kinds == {"sliders:energy"}:
                skip = "along"
            step(self._draw_sliders, skip)
        if "info" in kinds:
            step(self._draw_info)
        if "progress" in kinds:
            step(self._draw_progress)
        if "error" in kinds:
            step(self._draw_error)

    # ---- branch list, board, FEP image
    def _draw_branch_list(self):
        entries = self.shared.snapshot()
        if not entries:
            self._set(self.h_branch, options=("(none)",), value="(none)")
            return
        options = tuple(self._entry_option(i, e) for i, e in enumerate(entries))
        if self.selected_entry() is None:
            first = next((e for e in entries if len(e)), entries[0])
            with self.lock:
                self.sel_uid, self.s = first.uid, 0.0
            self._dirty.add("point")
        sel = self.shared.index_of(self.sel_uid)
        self._set(self.h_branch, options=options)
        self._set(self.h_branch, value=options[sel])
        # a streaming branch grows: keep s inside the branch, recompute the point if it was empty
        e = entries[sel]
        if self.current_point is None and len(e):
            self._dirty.add("point")

    def _series(self):
        entries = self.shared.snapshot()
        return entries, [e.series(self.factor) for e in entries]

    def _view_ranges(self, entries, series):
        """FEP axis ranges: all branches, or the selected one when zoomed."""
        if self.zoom:
            sel = [s for e, s in zip(entries, series) if e.uid == self.sel_uid and len(s)]
            if sel:
                return axis_ranges(sel)
        return axis_ranges(series)

    def _draw_board(self):
        entries, series = self._series()
        ranges = self._view_ranges(entries, series)
        self._ranges = ranges
        board = self.geom.board
        if not self.show_board:
            self.scene.remove_by_name("/fep")
            self._board_handles = {}
            return
        sc.draw_board_frame(self.scene, board, ranges, series)
        live = set()
        for e, ser in zip(entries, series):
            uid = e.uid
            if self.zoom and uid != self.sel_uid:            # zoomed: only the selected branch
                ser = ser.__class__(ser.energy[:0], ser.frequency[:0], ser.stable[:0], ser.label)
            live.add(uid)
            h = sc.draw_board_points(self.scene, board, ranges, ser, uid,
                                     on_click=self._click_handler(uid), emphasized=(uid == self.sel_uid))
            self._board_handles[uid] = h
        for uid in list(self._board_handles):
            if uid not in live:
                self.scene.remove_by_name(f"/fep/b{uid}")
                del self._board_handles[uid]

    def _click_handler(self, uid):
        def on_click(event):
            try:
                self.pick(uid, event.instance_index)
            except Exception as exc:
                self.show_error(one_line(exc))
        return on_click

    def selected_point_fep(self):
        """(energy J, frequency Hz) of the selection at the current k3 factor, or None
        (interpolated linearly in log energy, like the energy slider)."""
        e = self.selected_entry()
        if e is None or not len(e):
            return None
        ser = e.series(self.factor)
        return 10 ** interp_at(np.log10(ser.energy), self.s), interp_at(ser.frequency, self.s)

    def _draw_fep_series(self):
        entries, series = self._series()
        ghost = []
        if abs(self.factor_log) > 1e-9:
            ghost = [e.series(e.k3_factor) for e in entries]
        self._fep.set_series(series, self.shared.index_of(self.sel_uid), ghosts=ghost,
                             title=f"Frequency-energy plot (k3 x {self.factor:.3g})",
                             ranges=self._view_ranges(entries, series) if self.zoom else None)

    def _draw_fep(self):
        sel = self.selected_point_fep()
        self.h_fep.image = self._fep.image(sel)
        if self.show_board and self._ranges is not None and sel is not None:
            pos = self.geom.board.to_world([sel[0]], [sel[1]], self._ranges)[0]
            sc.draw_marker(self.scene, pos + 0.5 * self.geom.board.point_radius() * self.geom.board.normal,
                           1.6 * self.geom.board.point_radius())
        elif sel is None:
            self.scene.remove_by_name("/fep/marker")

    def _draw_sliders(self, skip=None):
        e = self.selected_entry()
        if e is None or not len(e):
            self._set(self.h_energy, disabled=True)
            self._set(self.h_along, disabled=True)
            self._set(self.h_sel, content="no point selected: compute a branch in the Compute tab")
            return
        ser = e.series(self.factor)
        n = len(ser)
        with self.lock:
            self.s = float(np.clip(self.s, 0, n - 1))
            s = self.s
        le = np.log10(ser.energy)
        lo, hi = float(np.floor(le.min() * 100) / 100), float(np.ceil(le.max() * 100) / 100)
        if hi - lo < 0.02:
            lo, hi = lo - 0.01, hi + 0.01
        cur_le = interp_at(le, s)
        if skip != "energy":
            self._set(self.h_energy, min=lo, max=hi, disabled=False)
            self._set(self.h_energy, value=float(np.clip(round(cur_le, 2), lo, hi)))
        if skip != "along":
            self._set(self.h_along, min=0.0, max=float(max(n - 1, 0.01)), disabled=n < 2)
            self._set(self.h_along, value=float(round(s, 2)))
        f = interp_at(ser.frequency, s)
        st = "stable" if ser.stable[int(round(s))] else "unstable"
        idx = self.shared.index_of(self.sel_uid)
        options = self.h_branch.options
        if idx is not None and idx < len(options):
            self._set(self.h_branch, value=options[idx])
        self._set(self.h_sel, content=f"**Selected:** branch {idx + 1}, point {s:.2f} of {n - 1}  \n"
                                      f"E = {10 ** cur_le:.4g} J, f = {f:.5g} Hz, {st}")
        self._set(self.h_recompute, disabled=abs(self.factor / e.k3_factor - 1.0) < 1e-9)
        self._set(self.h_save, disabled=e.saved or e.source == "running")

    # ---- point, animation, info
    def _compute_point(self):
        e = self.selected_entry()
        if e is None or not len(e):
            self.current_point = None
            self.current_anim = None
            return
        s = float(np.clip(self.s, 0, len(e) - 1))
        key = (e.uid, len(e), round(s, 4))
        pd = self._point_cache.get(key)
        if pd is None:
            pd = point_data(e.branch, s)
            if len(self._point_cache) > 64:
                self._point_cache.clear()
            self._point_cache[key] = pd
        anim = self._anim_cache.get(key)
        if anim is None:
            anim = orbit_animation(self.mesh.vertices, self.mesh.faces, self.shared.mapper,
                                   pd.t, pd.x, pd.period)
            if len(self._anim_cache) > 32:
                self._anim_cache.clear()
            self._anim_cache[key] = anim
        ratio = self.factor / e.k3_factor
        self.current_point = pd.scaled(ratio)
        self.current_anim = anim
        self._ratio = ratio

    def amplification(self):
        """Display amplification and the physical peak displacement (m) of the shown orbit."""
        anim = self.current_anim
        if anim is None:
            return 1.0, 0.0
        peak = anim.peak_max / np.sqrt(self._ratio)
        if self.auto_amp:
            amp = AUTO_PEAK_FRACTION * self.geom.size / peak if peak > 0 else 1.0
        else:
            amp = 10.0 ** self.amp_log
        return float(amp), float(peak)

    def _draw_glb(self):
        anim = self.current_anim
        if anim is None:
            glb = sc.static_glb(self.mesh)
            self._set(self.h_peak, content="")
        else:
            amp, peak = self.amplification()
            r = 1.0 / np.sqrt(self._ratio)      # exact scaling law on the displacement shapes
            glb = anim.glb(amp * r, display_period=1.0 / max(self.speed, 1e-3), playing=self.playing,
                           phase=self.phase)
            if self.auto_amp:
                self._set(self.h_amp, value=float(np.clip(round(np.log10(amp), 2), -1.0, 6.0)))
            self._set(self.h_peak, content=peak_text(peak, amp, self.auto_amp)
                      + f"  \nreal period {anim.period:.4g} s, shown in {1.0 / max(self.speed, 1e-3):.3g} s")
        self.scene.add_glb("/model", glb, cast_shadow=False, receive_shadow=False)
        self.last_glb = glb
        self.anim_ready_time = time.perf_counter()

    def _draw_info(self):
        pd = self.current_point
        if pd is None:
            self._set(self.h_info, content="no point selected")
            return
        idx = self.shared.index_of(self.sel_uid)
        e = self.selected_entry()
        where = f"Branch {idx + 1} ({e.label}), point {self.s:.2f}"
        self._set(self.h_info, content=info_markdown(pd, self.model, self.shared.linear_freqs, self.factor,
                                                     where=where))
        try:
            dofs = parse_dofs(self.dofs_text, self.model.n, auto_dofs(self.model, pd.x))
        except ValueError as exc:
            self.show_error(str(exc))
            dofs = auto_dofs(self.model, pd.x)
        self._chart("time", "Time series over one period (vs t/T)", *uplot_time_series(pd, self.model, dofs),
                    order=1000.0)
        self._chart("harm", "Fourier coefficients: log10 amplitude (m) vs harmonic k",
                    *uplot_harmonics(pd, self.model, dofs), order=1001.0)

    def _chart(self, key, title, data, series, order):
        """Create or update a uPlot chart of the Point tab (re-created if the series change)."""
        from viser import uplot

        h, n = self._charts.get(key, (None, 0))
        if h is not None and n == len(series):
            h.series = series
            h.data = data
            return
        if h is not None:
            h.remove()
        scales = {"x": uplot.Scale(time=False, auto=True), "y": uplot.Scale(auto=True)}
        axes = (uplot.Axis(), uplot.Axis(size=64))
        with self.tab_point:
            h = self.gui.add_uplot(data, series, title=title, scales=scales, axes=axes, aspect=1.6,
                                   legend=uplot.Legend(show=True), order=order)
        self._charts[key] = (h, len(series))

    def _draw_progress(self):
        job = self.shared.job
        running = job is not None and job.running
        self._set(self.h_progress, value=float(np.clip(100.0 * self.shared.progress, 0, 100)))
        self._set(self.h_job, content=self.shared.status or "no job running")
        self._set(self.h_start, disabled=running)
        self._set(self.h_stop, disabled=not running)
        self._set(self.h_recompute, disabled=running or self.selected_entry() is None
                  or abs(self.factor / self.selected_entry().k3_factor - 1.0) < 1e-9)
        e = self.selected_entry()
        self._set(self.h_save, disabled=e is None or e.saved or e.source == "running")

    def _draw_error(self):
        msg = self.shared.error
        if msg:
            self._set(self.h_error, content=f"**Error:** {msg}", visible=True)
            self._set(self.h_dismiss, visible=True)
        else:
            self._set(self.h_error, content="", visible=False)
            self._set(self.h_dismiss, visible=False)
