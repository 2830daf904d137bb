"""One browser tab: its controls, its selection and the drawing of its scene.

Callbacks only change the session state under ``self.lock`` and ``request`` redraws; a
per-session draw thread coalesces the requests (latest state wins), so dragging a slider
never queues up stale work and the slider being dragged is never reset under the user.
With ``sync=True`` (tests) every request is drawn at once in the caller's thread.
"""
from __future__ import annotations

import threading
import time

import numpy as np

from . import scene as sc
from .drawing import ALL_KINDS, SessionDrawing
from .fep import FepRenderer, energy_to_s
from .layout import SessionLayout
from .worker import JobRunner, one_line


class Session(SessionLayout, SessionDrawing):
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
        self.request(*ALL_KINDS)

    # ================================================================== GUI

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
