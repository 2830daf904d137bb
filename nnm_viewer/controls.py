"""One browser tab: its controls, its selection and the drawing of its scene.

Callbacks only change the session state under ``self.lock`` and ``request`` redraws; a
per-session draw thread coalesces the requests (latest state wins), so dragging a slider
never queues up stale work and the slider being dragged is never reset under the user.
With ``sync=True`` (tests) every request is drawn at once in the caller's thread.
"""
from __future__ import annotations

import logging
import threading
import time

import numpy as np
import viser

from . import scene as sc
from .animation import format_length, orbit_animation
from .fep import FepRenderer, axis_ranges, energy_to_s, interp_at
from .info import auto_dofs, info_markdown, parse_dofs, peak_text, point_data, uplot_harmonics, uplot_time_series
from .worker import JobRunner, one_line

log = logging.getLogger("nnm_viewer")

#: auto amplification: the peak displacement is shown as this fraction of the model size
AUTO_PEAK_FRACTION = 0.12
MAX_MODES_LISTED = 60
#: widths (px) of the docked control panel (left) and information panel (right)
CONTROL_WIDTH = 340
PANEL_WIDTH = 500
_ALL = ("branches", "fep", "sliders", "point", "glb", "info", "progress", "error")


class Session:
    """State and GUI of one tab. ``api`` is a viser ``ClientHandle`` (one tab) or the
    ``ViserServer`` (shared by all tabs, used by tests); both have ``.gui`` and ``.scene``."""

    def __init__(self, api, shared, sync=False, start_job=None):
        self.api = api
        self.gui = api.gui
        self.scene = api.scene
        self.shared = shared
        self.model = shared.model
        self.mesh = shared.mesh
        self.geom = sc.view_geometry(self.mesh.vertices)
        self.sync = sync
        self.start_job = start_job
        self.lock = threading.RLock()
        # ---- view state (under self.lock)
        self.sel_uid = None          # uid of the selected BranchEntry
        self.s = 0.0                 # fractional index along the selected branch
        self.factor_log = 0.0        # log10 of the k3 factor on the file's springs
        self.playing = True
        self.phase = 0.0             # orbit phase (fraction of a period) when paused
        self.auto_amp = True
        self.amp_log = 0.0           # log10 of the manual amplification
        self.speed = 0.5             # displayed cycles per second
        self.show_board = True
        self.zoom = False            # FEP axes fitted to the selected branch only
        self.dofs_text = "auto"
        self.message = ""            # last status line for this tab
        # ---- drawing machinery
        self._dirty: set[str] = set()
        self._wake = threading.Event()
        self._draw_lock = threading.RLock()
        self._closed = False
        self._tl = threading.local()
        self._anim_cache: dict = {}
        self._point_cache: dict = {}
        self._ranges = None
        self._board_handles = {}
        self._fep = FepRenderer(size=(480, 350))
        self._charts = {}            # uPlot handles of the Point tab: name -> (handle, n_series)
        self._ratio = 1.0
        self.last_runner = None      # the JobRunner started from this tab
        self.last_glb = None         # bytes of the last GLB sent (tests, benchmark)
        self.last_pick_time = None
        self.anim_ready_time = None
        self.current_point = None    # PointData shown (scaled), or None
        self.current_anim = None
        self._build_gui()
        entries = shared.snapshot()
        first = next((e for e in entries if len(e)), None)
        if first is not None:
            self.sel_uid = first.uid
        shared.subscribe(self._on_shared)
        if not sync:
            self._thread = threading.Thread(target=self._loop, name="nnm-view-draw", daemon=True)
            self._thread.start()
        self.request(*_ALL)

    # ================================================================== GUI
    def _build_gui(self):
        gui = self.gui
        m = self.model
        name = m.name or "model"
        gui.configure_theme(control_width="large", dark_mode=False, show_logo=False)
        self.h_title = gui.add_markdown(f"**nnm-view** · {name} · {m.n} DOFs · {len(m.springs)} cubic springs")
        self.h_error = gui.add_markdown("", visible=False)
        self.h_dismiss = gui.add_button("Dismiss error", visible=False, color="red")
        self.h_dismiss.on_click(self._cb(self._dismiss_error))
        with gui.add_folder("Selection"):
            self.h_branch = gui.add_dropdown("Branch", options=("(none)",), initial_value="(none)")
            self.h_energy = gui.add_slider("Energy log10(J)", min=-3.0, max=3.0, step=0.01, initial_value=0.0,
                                           hint="Moves the selection along the branch (nearest crossing)")
            self.h_along = gui.add_slider("Along branch", min=0.0, max=1.0, step=0.01, initial_value=0.0,
                                          hint="Fractional point index: follows folds and tongues")
            self.h_sel = gui.add_markdown("no point selected")
        with gui.add_folder("Animation"):
            self.h_play = gui.add_checkbox("Play", initial_value=True)
            self.h_phase = gui.add_slider("Phase (t/T)", min=0.0, max=1.0, step=0.01, initial_value=0.0,
                                          visible=False)
            self.h_auto = gui.add_checkbox("Auto amplification", initial_value=True)
            self.h_amp = gui.add_slider("Amplification log10", min=-1.0, max=6.0, step=0.05, initial_value=0.0,
                                        disabled=True)
            self.h_speed = gui.add_slider("Speed (cycles/s)", min=0.05, max=3.0, step=0.05, initial_value=0.5)
            self.h_peak = gui.add_markdown("")
            self.h_board = gui.add_checkbox("Show FEP in scene", initial_value=True)
            self.h_zoom = gui.add_checkbox("FEP: zoom on selected branch", initial_value=False)
            self.h_reset = gui.add_button("Reset camera")
        with gui.add_folder("Nonlinear stiffness"):
            self.h_k3 = gui.add_slider("k3 factor log10", min=-2.0, max=2.0, step=0.05, initial_value=0.0,
                                       marks=((-2, "0.01x"), (-1, "0.1x"), (0, "1x"), (1, "10x"), (2, "100x")))
            self.h_k3_text = gui.add_markdown("k3 x 1 (as in the file)")
            self.h_recompute = gui.add_button("Recompute at this stiffness", disabled=True,
                                              hint="Background job on the scaled model, to confirm the scaling law")
        self.h_status = gui.add_markdown("")

        panel = gui.add_panel()
        self.panel = panel
        with panel.add_tab("FEP", viser.Icon.CHART_DOTS):
            self.h_fep = gui.add_image(np.full((350, 480, 3), 255, np.uint8), label=None, format="png")
            gui.add_markdown("Pick a point: click a sphere of the FEP in the 3D view "
                             "(blue: stable, red: unstable; the yellow sphere is the picked orbit).")
        self.tab_point = panel.add_tab("Point", viser.Icon.INFO_CIRCLE)
        with self.tab_point:
            self.h_info = gui.add_markdown("no point selected")
            self.h_dofs = gui.add_text("DOFs (0-based)", initial_value="auto",
                                       hint="comma-separated DOF indices, or 'auto'")
        with panel.add_tab("Compute", viser.Icon.PLAYER_PLAY):
            nmodes = min(m.n, MAX_MODES_LISTED)
            self._mode_options = tuple(self._mode_label(k) for k in range(1, nmodes + 1))
            self.h_mode = gui.add_dropdown("Mode", options=self._mode_options, initial_value=self._mode_options[0])
            self.h_emin = gui.add_number("Min energy (J), 0 = auto", initial_value=0.0, min=0.0, step=1e-6)
            self.h_emax = gui.add_number("Max energy (J)", initial_value=100.0, min=1e-12, step=1e-6)
            self.h_maxpts = gui.add_number("Max points", initial_value=80, min=2, max=5000, step=1)
            self.h_start = gui.add_button("Start", color="green")
            self.h_stop = gui.add_button("Stop (keep points)", disabled=True)
            self.h_save = gui.add_button("Save selected branch to file", disabled=True)
            self.h_progress = gui.add_progress_bar(0.0, animated=False)
            self.h_job = gui.add_markdown("no job running")
        with panel.add_tab("Modes", viser.Icon.LIST):
            gui.add_markdown(self._modes_markdown())
        panel.dock_right()
        panel.set_width(PANEL_WIDTH)
        main = gui.main_panel
        main.dock_left()
        main.set_width(CONTROL_WIDTH)

        self.h_branch.on_update(self._cb(self._on_branch))
        self.h_energy.on_update(self._cb(self._on_energy))
        self.h_along.on_update(self._cb(self._on_along))
        self.h_play.on_update(self._cb(self._on_play))
        self.h_phase.on_update(self._cb(self._on_phase))
        self.h_auto.on_update(self._cb(self._on_auto))
        self.h_amp.on_update(self._cb(self._on_amp))
        self.h_speed.on_update(self._cb(self._on_speed))
        self.h_board.on_update(self._cb(self._on_board))
        self.h_zoom.on_update(self._cb(self._on_zoom))
        self.h_reset.on_click(self._cb(self._on_reset_camera))
        self.h_k3.on_update(self._cb(self._on_k3))
        self.h_recompute.on_click(self._cb(self._on_recompute))
        self.h_dofs.on_update(self._cb(self._on_dofs))
        self.h_start.on_click(self._cb(self._on_start))
        self.h_stop.on_click(self._cb(self._on_stop))
        self.h_save.on_click(self._cb(self._on_save))

    def _mode_label(self, k):
        labels = self.model.mode_labels or []
        lab = f" {labels[k - 1]}" if k - 1 < len(labels) else ""
        return f"{k}: {self.shared.linear_freqs[k - 1]:.4g} Hz{lab}"

    def _modes_markdown(self):
        labels = self.model.mode_labels or []
        rows = ["| mode | f (Hz) | label |", "|---|---|---|"]
        for k in range(min(self.model.n, 200)):
            rows.append(f"| {k + 1} | {self.shared.linear_freqs[k]:.5g} | {labels[k] if k < len(labels) else ''} |")
        more = f"\n\n({self.model.n - 200} more modes not listed)" if self.model.n > 200 else ""
        return "**Linear modes**\n\n" + "\n".join(rows) + more

    # ================================================================== callbacks
    def _cb(self, fn):
        """Wrap a callback: ignore programmatic updates, report exceptions in the page."""
        def wrapped(event=None):
            if getattr(self._tl, "programmatic", False):
                return
            try:
                fn(event)
            except Exception as exc:
                self.show_error(one_line(exc))
        return wrapped

    def _set(self, handle, **props):
        """Set handle properties from Python without triggering our callbacks."""
        self._tl.programmatic = True
        try:
            for k, v in props.items():
                if k == "value":
                    if handle.value != v:
                        handle.value = v
                elif getattr(handle, k) != v:
                    setattr(handle, k, v)
        finally:
            self._tl.programmatic = False

    @property
    def factor(self):
        return float(10.0 ** self.factor_log)

    def selected_entry(self):
        if self.sel_uid is None:
            return None
        for e in self.shared.snapshot():
            if e.uid == self.sel_uid:
                return e
        return None

    def _on_branch(self, _):
        label = self.h_branch.value
        entries = self.shared.snapshot()
        for i, e in enumerate(entries):
            if self._entry_option(i, e) == label:
                with self.lock:
                    changed = e.uid != self.sel_uid
                    self.sel_uid, self.s = e.uid, 0.0
                self.mark_pick()
                self.request("fep", "sliders", "point", *(("branches",) if changed else ()))
                return

    def select(self, index, s):
        """Select point ``s`` (fractional index) of branch ``index`` (position in the list)."""
        entries = self.shared.snapshot()
        e = entries[index]
        with self.lock:
            changed = e.uid != self.sel_uid
            self.sel_uid = e.uid
            self.s = float(np.clip(s, 0, max(len(e) - 1, 0)))
        self.mark_pick()
        self.request("fep", "sliders", "point", *(("branches",) if changed else ()))

    def pick(self, uid, instance_index):
        """A click on FEP point ``instance_index`` of the branch with ``uid``."""
        if instance_index is None:
            return
        idx = self.shared.index_of(uid)
        if idx is not None:
            self.select(idx, int(instance_index))

    def mark_pick(self):
        self.last_pick_time = time.perf_counter()

    def _on_energy(self, _):
        e = self.selected_entry()
        if e is None or not len(e):
            return
        ser = e.series(self.factor)
        with self.lock:
            self.s = energy_to_s(ser.energy, 10.0 ** float(self.h_energy.value), self.s)
        self.request("fep", "sliders:along", "point")

    def _on_along(self, _):
        with self.lock:
            self.s = float(self.h_along.value)
        self.request("fep", "sliders:energy", "point")

    def _on_play(self, _):
        with self.lock:
            self.playing = bool(self.h_play.value)
        self._set(self.h_phase, visible=not self.playing)
        self.request("glb")

    def _on_phase(self, _):
        with self.lock:
            self.phase = float(self.h_phase.value)
        self.request("glb")

    def _on_auto(self, _):
        with self.lock:
            self.auto_amp = bool(self.h_auto.value)
        self._set(self.h_amp, disabled=self.auto_amp)
        self.request("glb")

    def _on_amp(self, _):
        with self.lock:
            self.amp_log = float(self.h_amp.value)
        self.request("glb")

    def _on_speed(self, _):
        with self.lock:
            self.speed = float(self.h_speed.value)
        self.request("glb")

    def _on_board(self, _):
        with self.lock:
            self.show_board = bool(self.h_board.value)
        self.request("branches")

    def _on_reset_camera(self, _):
        cam = getattr(self.api, "camera", None)        # a tab (ClientHandle); tests use the server
        if cam is not None:
            cam.position = tuple(self.geom.camera_position)
            cam.look_at = tuple(self.geom.camera_look_at)

    def _on_zoom(self, _):
        with self.lock:
            self.zoom = bool(self.h_zoom.value)
        self.request("branches")

    def _on_k3(self, _):
        with self.lock:
            self.factor_log = float(self.h_k3.value)
        self.request("branches", "point")

    def _on_dofs(self, _):
        with self.lock:
            self.dofs_text = str(self.h_dofs.value)
        self.request("info")

    def _on_recompute(self, _):
        e = self.selected_entry()
        if e is None or not len(e):
            raise ValueError("select a branch first")
        mode = e.mode
        emax = float(np.max(e.series(self.factor).energy))
        self._start(mode, emax, self.factor)

    def _on_start(self, _):
        mode = int(str(self.h_mode.value).split(":")[0])
        emin = float(self.h_emin.value)
        self._start(mode, float(self.h_emax.value), self.factor, energy_min=emin if emin > 0 else None)

    def _start(self, mode, emax, factor, energy_min=None):
        with self.shared.lock:
            if self.shared.job is not None and self.shared.job.running:
                raise ValueError("a job is already running; stop it first")
        opts = {"max_points": int(self.h_maxpts.value)}
        if energy_min is not None:
            opts["energy_min"] = float(energy_min)
        runner = JobRunner(self.shared, mode, emax, k3_factor=factor, start=self.start_job, **opts)
        runner.start()
        self.last_runner = runner
        with self.lock:
            self.sel_uid, self.s = runner.entry.uid, 0.0
        self.request("branches", "progress")

    def _on_stop(self, _):
        job = self.shared.job
        if job is not None:
            job.cancel()

    def _on_save(self, _):
        e = self.selected_entry()
        if e is None:
            raise ValueError("select a branch to save")
        if e.source == "running":
            raise ValueError("the branch is still being computed: stop it or wait, then save")
        if e.saved:
            raise ValueError("this branch is already in the file")
        self.shared.save(e)
        self.show_status(f"saved {e.label} ({len(e)} points) to {self.shared.path}")

    def _dismiss_error(self, _):
        with self.shared.lock:
            self.shared.error = ""
        self.request("error")

    def _on_shared(self, kind):
        if kind == "branches":
            self.request("branches", "progress")
        elif kind == "progress":
            self.request("progress")
        elif kind == "error":
            self.request("error")
            msg = self.shared.error
            if msg and hasattr(self.api, "add_notification"):
                try:
                    self.api.add_notification("nnm solver", msg, color="red", auto_close_seconds=10.0)
                except Exception:
                    pass

    def show_error(self, msg):
        """Show an error of this tab in the page (the server keeps running)."""
        with self.lock:
            self.message = msg
        self._set(self.h_error, content=f"**Error:** {msg}", visible=True)
        self._set(self.h_dismiss, visible=True)

    def show_status(self, msg):
        with self.lock:
            self.message = msg
        self._set(self.h_status, content=msg)

    # ================================================================== drawing
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
