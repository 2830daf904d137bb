"""One browser tab: its view state, the callbacks of its controls, and what they redraw.

A ``Session`` owns its state (selection, animation and stiffness settings, the point shown),
a ``Layout`` (the viser handles, ``session.layout``) and a ``Drawing`` (the draw steps,
``session.drawing``).  Callbacks only change the state under ``self.lock`` and ``request``
redraws; the drawing coalesces the requests in a per-tab thread (latest state wins), so dragging a
slider never queues up stale work and the slider being dragged is never reset under the user.
With ``sync=True`` (tests) every request is drawn at once in the caller's thread.
"""
from __future__ import annotations

import threading

import numpy as np

from nnm_solver import cubic_scaling

from . import downloads
from . import scene as sc
from .downloads import file_stem
from .drawing import ALL_KINDS, Drawing
from .fep import Y_LABELS, axis_ranges, energy_to_s, interp_at, should_zoom
from .fep_view import branch_options, sweep_key
from .layout import SEE_COMPUTE_TAB, Layout
from .state import branch_label, scaling_law_holds
from .worker import JobRunner, one_line

#: auto amplification: the peak displacement is shown as this fraction of the model size
AUTO_PEAK_FRACTION = 0.12
#: non-cubic model: seconds the stiffness slider must rest before its factor is computed (debounce;
#: tests with sync=True start at once)
RECOMPUTE_DELAY = 0.5

#: controls that set one state field from their value: handle -> (field, type, redraws)
SIMPLE_CONTROLS = {
    "h_along": ("s", float, ("fep", "sliders:energy", "point")),
    "h_play": ("playing", bool, ("controls", "glb")),
    "h_phase": ("phase", float, ("glb",)),
    "h_auto": ("auto_amp", bool, ("controls", "glb")),
    "h_amp": ("amp_log", float, ("glb",)),
    "h_speed": ("speed", float, ("glb",)),
    "h_board": ("show_board", bool, ("branches",)),
    "h_relative": ("relative", bool, ("branches",)),
    "h_dofs": ("dofs_text", str, ("info",)),
    "h_ghost": ("show_ghost", bool, ("ghost",)),
}


class Session:
    """State and GUI of one tab. ``api`` is a viser ``ClientHandle`` (one tab) or the
    ``ViserServer`` (shared by all tabs, used by tests); both have ``.gui`` and ``.scene``."""

    def __init__(self, api, shared, sync=False, start_job=None):
        self.api = api
        self.scene = api.scene
        self.shared = shared
        self.model = shared.model
        self.mesh = shared.mesh
        self.geom = sc.view_geometry(self.mesh.vertices)
        self.start_job = start_job
        self.sync = sync
        self.lock = threading.RLock()
        #: pure cubic springs: the stiffness slider applies the exact scaling law; else it recomputes
        self.scaling_law = scaling_law_holds(self.model)
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
        self.zoom = False            # FEP axes fitted to the selected branch only (when not zoom_auto)
        self.zoom_auto = True        # until the user ticks or unticks zoom: zoom when fep.should_zoom
        self.relative = False        # FEP frequency axis relative to each branch's linear frequency (%)
        self.dofs_text = "auto"
        self.show_ghost = False      # the undeformed shape, translucent
        self.view = "Iso"            # last camera preset
        self.linear_mode = None      # k (1-based): linear mode k is shown instead of the selected point
        self.message = ""            # last status line for this tab
        # ---- the point shown (written by the drawing, under self.lock)
        self.current_point = None    # PointData shown (scaled to the current k3), or None
        self.current_anim = None     # its OrbitAnimation (for the branch's own k3)
        self.current_uid = None      # uid of the branch it belongs to
        self.ratio = 1.0             # k3 factor of the view / k3 factor of that branch
        self.last_runner = None      # the JobRunner started from this tab
        self.last_download = None    # (file name, bytes) last offered to the browser
        # ---- recomputes started by the stiffness slider (models that are not pure cubic)
        self._recompute_lock = threading.RLock()
        self._pending = None         # (mode, energy_max, factor) chosen on the slider, not started yet
        self._timer = None           # the debounce timer that starts it
        self.slider_runner = None    # the last JobRunner the slider started
        self._slider_base = None     # (mode, energy_max, uid of the branch it started from)
        self._slider_uids = set()    # entries computed for the slider
        self.layout = Layout(api.gui, self.model, shared.linear_freqs, scaling_law=self.scaling_law)
        self.drawing = Drawing(self, sync=sync)
        self.layout.connect(self._callbacks())
        first = next((e for e in shared.snapshot() if len(e)), None)
        if first is not None:
            self.sel_uid = first.uid
        shared.subscribe(self._on_shared)
        self.drawing.start()
        self.request(*ALL_KINDS)

    def __getattr__(self, name):
        """The GUI handles ``h_*`` of ``self.layout`` read as ``session.h_*`` (tests, scripts)."""
        if name.startswith("h_") and "layout" in self.__dict__:
            return getattr(self.layout, name)
        raise AttributeError(f"'Session' object has no attribute {name!r}")

    # ================================================================== drawing
    def request(self, *kinds):
        """Ask for redraws (see Drawing.request)."""
        self.drawing.request(*kinds)

    def close(self):
        with self._recompute_lock:
            self._pending = None
            if self._timer is not None:
                self._timer.cancel()
        self.drawing.close()
        self.shared.unsubscribe(self._on_shared)

    @property
    def last_glb(self):
        """Bytes of the last GLB sent to the scene (tests, benchmark)."""
        return self.drawing.point.last_glb

    @property
    def _charts(self):
        return self.drawing.point.charts

    @property
    def _board_handles(self):
        return self.drawing.fep.board_handles

    # ================================================================== state queries
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

    def view_factor(self, e):
        """The k3 factor entry ``e`` is shown at: the slider's (exact scaling law) when its springs are
        all pure cubic, else its own (nothing is scaled; the slider recomputes instead)."""
        return self.factor if self.scaling_law and e.scalable else e.k3_factor

    def fep_series(self, e, factor=None):
        """FEP series of entry ``e`` at the k3 factor ``factor`` (default: the one it is shown at,
        ``view_factor``), on the frequency axis chosen (Hz, or relative to the branch's linear
        frequency, %)."""
        ser = e.series(self.view_factor(e) if factor is None else factor)
        if self.relative:
            f_lin = e.linear_frequency(self.shared.linear_freqs)
            if f_lin:
                ser = ser.relative(f_lin)
        return ser

    @property
    def ylabel(self):
        return Y_LABELS[bool(self.relative)]

    def _series(self):
        """(entries, their FEP series at the current k3, on the chosen frequency axis)."""
        entries = self.shared.snapshot()
        return entries, [self.fep_series(e) for e in entries]

    def zoomed(self, entries, series):
        """Whether the FEP is zoomed on the selected branch: the user's choice once made, else by
        default when the selected branch spans a small part of the frequency range (fep.should_zoom)."""
        if not self.zoom_auto:
            return self.zoom
        sel = next((k for k, e in enumerate(entries) if e.uid == self.sel_uid), None)
        return should_zoom(series, sel)

    def _view_ranges(self, entries, series):
        """FEP axis ranges: all branches, or the selected one when zoomed."""
        if self.zoomed(entries, series):
            sel = [s for e, s in zip(entries, series) if e.uid == self.sel_uid and len(s)]
            if sel:
                return axis_ranges(sel)
        return axis_ranges(series)

    def amplification(self):
        """Display amplification and the physical peak displacement (m) of the shown orbit."""
        anim = self.current_anim
        if anim is None:
            return 1.0, 0.0
        peak = anim.peak_max * cubic_scaling(self.ratio).amplitude
        if self.auto_amp:
            amp = AUTO_PEAK_FRACTION * self.geom.size / peak if peak > 0 else 1.0
        else:
            amp = 10.0 ** self.amp_log
        return float(amp), float(peak)

    # ================================================================== callbacks
    def _cb(self, fn):
        """Wrap a callback: ignore programmatic updates, report exceptions in the page."""
        def wrapped(event=None):
            if self.layout.programmatic:
                return
            try:
                fn(event)
            except Exception as exc:
                self.show_error(one_line(exc))
        return wrapped

    def _callbacks(self):
        """The callback of every control, by handle name (wired by Layout.connect)."""
        cbs = {name: self._set_field(name) for name in SIMPLE_CONTROLS}
        cbs.update(h_k3=self._on_k3, h_zoom=self._on_zoom, h_branch=self._on_branch, h_energy=self._on_energy,
                   h_reset=self._on_reset_camera, h_recompute=self._on_recompute, h_start=self._on_start,
                   h_stop=self._on_stop, h_save=self._on_save, h_dismiss=self._dismiss_error,
                   h_csv_fep=self._on_csv_fep, h_csv_orbit=self._on_csv_orbit, h_gif=self._on_gif,
                   h_view=self._on_view, h_show_linear=self._on_show_linear,
                   h_compute_linear=self._on_compute_linear)
        return {name: self._cb(fn) for name, fn in cbs.items()}

    def _set_field(self, name):
        """Callback of a SIMPLE_CONTROLS handle: copy its value into its state field, redraw."""
        field, kind, redraws = SIMPLE_CONTROLS[name]

        def on_update(_):
            with self.lock:
                setattr(self, field, kind(getattr(self.layout, name).value))
                if field == "s":             # a point of the branch: no more linear mode
                    self.linear_mode = None
            self.request(*redraws)
        return on_update

    def _on_zoom(self, _):
        """The user's zoom choice, kept from now on (no more automatic zoom)."""
        with self.lock:
            self.zoom, self.zoom_auto = bool(self.layout.h_zoom.value), False
        self.request("branches")

    def _on_branch(self, _):
        entries = self.shared.snapshot()
        for i, option in branch_options(entries):
            if option == self.layout.h_branch.value:
                self._select_uid(entries[i].uid, 0.0)
                return

    def select(self, index, s):
        """Select point ``s`` (fractional index) of branch ``index`` (position in the list)."""
        e = self.shared.snapshot()[index]
        self._select_uid(e.uid, float(np.clip(s, 0, max(len(e) - 1, 0))))

    def _select_uid(self, uid, s):
        with self.lock:
            changed = uid != self.sel_uid
            self.sel_uid, self.s = uid, float(s)
            self.linear_mode = None          # a pick (or a branch chosen) shows its point again
        self.request("fep", "sliders", "point", *(("branches",) if changed else ()))

    def pick(self, uid, instance_index):
        """A click on FEP point ``instance_index`` of the branch with ``uid``."""
        if instance_index is None:
            return
        idx = self.shared.index_of(uid)
        if idx is not None:
            self.select(idx, int(instance_index))

    def _on_energy(self, _):
        e = self.selected_entry()
        if e is None or not len(e):
            return
        ser = e.series(self.view_factor(e))
        with self.lock:
            self.s = energy_to_s(ser.energy, 10.0 ** float(self.layout.h_energy.value), self.s)
            self.linear_mode = None
        self.request("fep", "sliders:along", "point")

    def _on_reset_camera(self, _):
        cam = getattr(self.api, "camera", None)        # a tab (ClientHandle); tests use the server
        if cam is not None:
            cam.position = tuple(self.geom.camera_position)
            cam.look_at = tuple(self.geom.camera_look_at)

    def _on_view(self, event):
        """A view preset (Iso, Top, Side, Front): the camera of this tab frames the model from there."""
        name = getattr(getattr(event, "target", None), "value", None) or self.layout.h_view.value
        position, look_at = sc.preset_camera(self.mesh.vertices, name, self.geom.fov_deg)
        cam = getattr(self.api, "camera", None)        # a tab (ClientHandle); the server has none
        if cam is not None:
            cam.position = tuple(position)
            cam.look_at = tuple(look_at)
        with self.lock:
            self.view = name

    def view_direction(self):
        """Direction the tab's camera looks along (world): from its camera if it has one, else the
        last preset's, else the initial camera's."""
        cam = getattr(self.api, "camera", None)
        try:
            d = np.asarray(cam.look_at, dtype=float) - np.asarray(cam.position, dtype=float)
            if np.linalg.norm(d) > 0:
                return d
        except Exception:
            pass
        return -sc.PRESET_DIRECTIONS.get(getattr(self, "view", "Iso"), sc.CAMERA_DIR)

    def _on_recompute(self, _):
        target = self._recompute_target()
        if target is None:
            raise ValueError("select a branch first")
        self._start(target[0], target[1], self.factor)

    def _recompute_target(self):
        """(mode, energy_max, uid) of a recompute at the slider's factor: the selected branch's mode
        up to its largest energy (at the factor in use); for a branch the slider computed, or while
        its job is being replaced, those of the branch the slider started from.  None: no branch."""
        e = self.selected_entry()
        with self.lock:
            base = self._slider_base
        if base is not None and (e is None or e.uid in self._slider_uids):
            return base
        job = self.shared.job
        if not self.scaling_law and e is not None and job is not None and job.entry is e:
            return job.mode, job.energy_max, e.uid        # a branch being computed: its job's range
        if e is None or not len(e):
            return None
        return int(e.mode), float(np.max(e.series(self.view_factor(e)).energy)), e.uid

    # ---- the stiffness slider
    def _on_k3(self, _):
        """The stiffness slider: pure cubic springs, the FEP and the orbit follow by the exact scaling
        law; otherwise nothing is scaled and the chosen factor is computed (``_slider_recompute``)."""
        with self.lock:
            self.factor_log = float(self.layout.h_k3.value)
        if self.scaling_law:
            self.request("branches", "point", "controls")
            return
        self.request("controls", "progress", "sliders")
        self._slider_recompute()

    def _entry_at(self, mode, factor, prefer=None):
        """A complete branch of ``mode`` computed at ``factor`` on the file's model (not a sweep
        variant's), ``prefer`` (a uid) first; or None."""
        found = [e for e in self.shared.snapshot()
                 if len(e) and e.mode == mode and abs(e.k3_factor / factor - 1.0) < 1e-9
                 and e.source in ("file", "computed", "saved") and sweep_key(e) is None]
        return next((e for e in found if e.uid == prefer), found[0] if found else None)

    def _slider_recompute(self):
        """Non-cubic model: a background job (the Recompute button's path) for the selected branch's
        mode at the slider's factor, debounced: it starts once the slider has rested RECOMPUTE_DELAY s
        (at once with sync=True) and no job runs; a job the slider started for another factor is
        stopped and its branch dropped, so that one job runs, for the final value.  A complete branch
        already computed at that factor is selected instead."""
        factor = self.factor
        target = self._recompute_target()
        if target is None:
            self.show_status("select a branch: the stiffness slider recomputes the selected branch")
            return
        mode, emax, origin = target
        existing = self._entry_at(mode, factor, prefer=origin)
        with self._recompute_lock:
            self._slider_base = (mode, emax, origin)
            runner = self.slider_runner
            busy = runner is not None and runner.running and not runner.cancelled
            same = busy and abs(runner.k3_factor / factor - 1.0) < 1e-9
            self._pending = None if (existing is not None or same) else (mode, emax, factor)
            if self._timer is not None:
                self._timer.cancel()
                self._timer = None
        if busy and not same:
            self._supersede(runner, origin)
        if existing is not None:
            self._select_existing(existing)
            return
        if same:
            return
        if self.sync:
            self._start_pending()
        else:
            timer = threading.Timer(RECOMPUTE_DELAY, self._start_pending)
            timer.daemon = True
            with self._recompute_lock:
                self._timer = timer
            timer.start()
        job = self.shared.job
        if job is not None and job.running and job is not self.slider_runner:
            self.show_status(f"recompute at x {factor:.3g} queued: it starts when the running job ends")

    def _supersede(self, runner, origin):
        """Stop a slider job whose factor is no longer wanted and drop its branch; the branch the
        slider started from is selected meanwhile."""
        runner.cancel()
        self.shared.remove(runner.entry)
        with self.lock:
            if self.sel_uid == runner.entry.uid and self.shared.index_of(origin) is not None:
                self.sel_uid, self.s = origin, 0.0
        self.request("branches", "point", "progress")

    def _select_existing(self, e):
        """Select ``e`` (a branch already computed at the slider's factor) near the energy shown."""
        cur = self.selected_entry()
        s = 0.0
        if cur is not None and len(cur) and cur.uid != e.uid:
            ser = cur.series(self.view_factor(cur))
            energy = 10 ** interp_at(np.log10(ser.energy), float(np.clip(self.s, 0, len(ser) - 1)))
            s = energy_to_s(e.series(e.k3_factor).energy, energy, 0.0)
        elif cur is not None and cur.uid == e.uid:
            return
        self._select_uid(e.uid, s)

    def _start_pending(self):
        """Start the recompute the slider asked for, unless a job is running (then ``_on_shared``
        starts it when that job ends)."""
        with self._recompute_lock:
            pending = self._pending
            if pending is None:
                return
            job = self.shared.job
            if job is not None and job.running:
                return
            self._pending = None
            mode, emax, factor = pending
            try:
                runner = self._start(mode, emax, factor)
            except Exception as exc:
                self.show_error(one_line(exc))
                return
            self.slider_runner = runner
            self._slider_uids.add(runner.entry.uid)

    def _on_start(self, _):
        mode = int(str(self.layout.h_mode.value).split(":")[0])
        emin, emax = float(self.layout.h_emin.value), float(self.layout.h_emax.value)
        return self._start(mode, emax, self.factor, energy_min=emin if emin > 0 else None)

    def _start(self, mode, emax, factor, energy_min=None):
        with self.shared.lock:
            if self.shared.job is not None and self.shared.job.running:
                raise ValueError("a job is already running; stop it first")
        ui = self.layout
        spp = int(round(float(ui.h_spp.value)))
        if spp < 8:
            raise ValueError(f"steps per period must be at least 8, got {spp}")
        opts = {"max_points": int(ui.h_maxpts.value), "integrator": str(ui.h_integrator.value),
                "steps_per_period": spp}
        if energy_min is not None:
            opts["energy_min"] = float(energy_min)
        runner = JobRunner(self.shared, mode, emax, k3_factor=factor, start=self.start_job, **opts)
        runner.start()
        self.last_runner = runner
        with self.lock:            # the new branch is selected: its points replace the old animation
            self.sel_uid, self.s = runner.entry.uid, 0.0
            self.current_point = self.current_anim = self.current_uid = None
            self.linear_mode = None
        self.request("branches", "point", "progress")
        return runner

    # ---- the Modes tab
    def _linear_mode_choice(self):
        """Mode k (1-based) chosen in the Modes tab's dropdown."""
        return int(str(self.layout.h_lin_mode.value).split(":")[0])

    def show_linear_mode(self, k):
        """Animate linear mode ``k`` (1-based) instead of the selected point (``info.linear_mode_point``);
        the selection is kept: a pick, the sliders, a branch chosen or a new job show a point again."""
        k = int(k)
        freqs = self.shared.linear_freqs
        if not 1 <= k <= len(freqs):
            raise ValueError(f"linear mode {k} does not exist (valid: 1..{len(freqs)})")
        if not freqs[k - 1] > 1e-9 * max(float(np.max(np.abs(freqs))), 1e-300):
            raise ValueError(f"linear mode {k} is a rigid-body mode (0 Hz): nothing to animate")
        with self.lock:
            self.linear_mode = k
        self.request("point")

    def _on_show_linear(self, _):
        self.show_linear_mode(self._linear_mode_choice())

    def _on_compute_linear(self, _):
        """'Compute its branch': that mode in the Compute tab's Mode list, then Start (as its button)."""
        k = self._linear_mode_choice()
        self.layout.set(self.layout.h_mode, value=self.layout.mode_options[k - 1])
        runner = self._on_start(None)
        self.show_status(f"started {runner.name}: {SEE_COMPUTE_TAB}")
        return runner

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
        name = branch_label(e.branch, e.k3_factor, source="file", model=self.model)
        target, reason = self.shared.save(e)
        self.show_status(f"saved {name}, {len(e)} points, to {target}"
                         + (f" ({reason}: it is left unchanged; open the new file with nnm-view {target})"
                            if reason else ""))

    # ================================================================== downloads
    def download(self, filename, content):
        """Offer ``content`` (bytes) to the browser as file ``filename`` (kept as ``last_download``)."""
        with self.lock:
            self.last_download = (filename, content)
        send = getattr(self.api, "send_file_download", None)
        if send is not None:
            send(filename, content, save_immediately=True)
        self.show_status(f"download: {filename} ({len(content)} bytes)")

    def _download_stem(self, e):
        idx = self.shared.index_of(e.uid)
        factor = self.view_factor(e)
        k3 = f"_k3x{factor:.3g}" if abs(factor - 1.0) > 1e-9 else ""
        return file_stem(f"{self.model.name or 'model'}_branch{(idx or 0) + 1}_{e.label}{k3}")

    def fep_csv(self):
        """(file name, CSV bytes) of the selected branch's FEP, at the current k3 factor."""
        e = self.selected_entry()
        if e is None or not len(e):
            raise ValueError("select a branch with points first")
        ratio = self.view_factor(e) / e.k3_factor
        branch = e.branch if abs(ratio - 1.0) < 1e-12 else e.branch.scaled(ratio)
        return f"{self._download_stem(e)}_fep.csv", downloads.fep_csv(branch)

    def _linear_stem(self, k):
        return file_stem(f"{self.model.name or 'model'}_linear_mode{k}")

    def orbit_csv(self):
        """(file name, CSV bytes) of the picked orbit (as shown: at the current k3 factor), or of the
        linear mode shown."""
        e = self.selected_entry()
        with self.lock:
            pd, uid, along, lin = self.current_point, self.current_uid, self.s, self.linear_mode
        if lin is not None and pd is not None:
            return f"{self._linear_stem(lin)}_orbit.csv", downloads.orbit_csv(pd, self.model)
        if e is None or pd is None or uid != e.uid:
            raise ValueError("no orbit shown: pick a point of the FEP first")
        return f"{self._download_stem(e)}_point{along:.2f}_orbit.csv", downloads.orbit_csv(pd, self.model)

    def animation_gif(self):
        """(file name, GIF bytes) of the picked orbit over one period, as shown (amplification, k3
        factor), seen along the tab's camera direction."""
        from .gif import gif_title, orbit_gif

        from .info import linear_mode_title

        e = self.selected_entry()
        with self.lock:
            pd, anim, uid, along, lin = (self.current_point, self.current_anim, self.current_uid, self.s,
                                         self.linear_mode)
        if lin is not None and pd is not None and anim is not None:
            amp, peak = self.amplification()
            title = gif_title("L" + linear_mode_title(self.model, self.shared.linear_freqs, lin, freq=False)[1:], pd, peak)
            return f"{self._linear_stem(lin)}.gif", orbit_gif(anim, amp, self.view_direction(), title=title)
        if e is None or pd is None or anim is None or uid != e.uid:
            raise ValueError("no orbit shown: pick a point of the FEP first")
        amp, peak = self.amplification()
        idx = self.shared.index_of(e.uid)
        title = gif_title(f"Branch {(idx or 0) + 1}: {e.label}, point {along:.2f}", pd, peak)
        data = orbit_gif(anim, amp * cubic_scaling(self.ratio).amplitude, self.view_direction(), title=title)
        return f"{self._download_stem(e)}_point{along:.2f}.gif", data

    def _on_gif(self, _):
        self.show_status("drawing the animation (GIF) …")
        self.download(*self.animation_gif())

    def _on_csv_fep(self, _):
        self.download(*self.fep_csv())

    def _on_csv_orbit(self, _):
        self.download(*self.orbit_csv())

    def _dismiss_error(self, _):
        with self.shared.lock:
            self.shared.error = ""
        self.request("error")

    def _on_shared(self, kind):
        if kind == "branches":
            self.request("branches", "progress")
        elif kind == "progress":
            self.request("progress")
            if self._pending is not None:       # a recompute of the stiffness slider waits for a job
                self._start_pending()
        elif kind == "solver":
            self.request("solver", "point", "progress")
        elif kind == "error":
            self.request("error")
            msg = self.shared.error
            if msg and hasattr(self.api, "add_notification"):
                try:
                    self.api.add_notification("nnm solver", msg, color="red", auto_close_seconds=10.0)
                except Exception:
                    pass

    # ================================================================== messages
    def show_error(self, msg):
        """Show an error of this tab in the page (the server keeps running)."""
        with self.lock:
            self.message = msg
        ui = self.layout
        ui.set(ui.h_error, content=f"**Error:** {msg}", visible=True)
        ui.set(ui.h_dismiss, visible=True)

    def show_status(self, msg):
        with self.lock:
            self.message = msg
        self.layout.set(self.layout.h_status, content=msg)
