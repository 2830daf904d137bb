"""One browser tab: its view state, the callbacks of its controls, and what they redraw.

A ``Session`` owns its state (selection, animation and stiffness settings, the point shown: one
immutable ``ViewState``, ``session.view``, swapped under ``session.lock``; view_state.py), a ``Layout``
(the viser handles, ``session.layout``) and a ``Drawing`` (the draw steps, ``session.drawing``).
Callbacks only change the state (``set_view`` / ``change_view``) and ``request`` redraws; the drawing coalesces the requests in a per-tab thread (latest state wins), so dragging a
slider never queues up stale work and the slider being dragged is never reset under the user.
With ``sync=True`` (tests) every request is drawn at once in the caller's thread.
"""
from __future__ import annotations

import threading

import numpy as np

from nnm_solver import cubic_scaling

from . import scene as sc
from .compute_actions import ComputeActions
from .downloads import DownloadActions
from .fep_queries import FepQueries
from .drawing import ALL_KINDS, Drawing
from .fep import energy_to_s
from .fep_text import branch_options
from .layout import Layout, default_steps
from .numbering import along_from_slider
from .state import scaling_law_holds
from .view_state import ViewHolder, ViewState
from .worker import one_line

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


class Session(ViewHolder, ComputeActions, DownloadActions, FepQueries):
    """State and GUI of one tab. ``api`` is a viser ``ClientHandle`` (one tab) or the
    ``ViserServer`` (shared by all tabs, used by tests); both have ``.gui`` and ``.scene``.

    One lock, ``self.lock``, guards everything of the tab that changes: the view (a ViewState swapped
    whole) and the stiffness slider's recompute state (``_pending``, ``_timer``, ``slider_runner``,
    ``_slider_base``, ``_slider_uids``).  Lock order: the drawing's lock, then this one, then the shared
    state's (state.SharedState)."""

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
        # ---- view state: one immutable record, swapped under self.lock (view_state.py)
        self.__dict__["_view"] = ViewState()
        self.last_runner = None      # the JobRunner started from this tab
        self.last_download = None    # (file name, bytes) last offered to the browser
        # ---- recomputes started by the stiffness slider (models that are not pure cubic), under self.lock
        self._pending = None         # (mode, energy_max, factor) chosen on the slider, not started yet
        self._timer = None           # the debounce timer that starts it
        self.slider_runner = None    # the last JobRunner the slider started
        self._slider_base = None     # (mode, energy_max, uid of the branch it started from)
        self._slider_uids = set()    # entries computed for the slider
        self.layout = Layout(api.gui, self.model, shared.linear_freqs, scaling_law=self.scaling_law,
                             reference=shared.reference_names)
        self.drawing = Drawing(self, sync=sync)
        self.layout.connect(self._callbacks())
        first = next((e for e in shared.snapshot() if len(e)), None)
        if first is not None:
            self.set_view(sel_uid=first.uid)
            self._mode_lists_on(first)
        shared.subscribe(self._on_shared)
        camera = getattr(api, "camera", None)          # a tab (ClientHandle); tests use the server
        if camera is not None:
            camera.on_update(self._on_camera)
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
        with self.lock:
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
        return self.view.factor

    def selected_entry(self, v=None):
        """The selected BranchEntry of view ``v`` (default: the current view), or None."""
        uid = (v or self.view).sel_uid
        if uid is None:
            return None
        for e in self.shared.snapshot():
            if e.uid == uid:
                return e
        return None

    def amplification(self, v=None):
        """Display amplification and the physical peak displacement (m) of the orbit shown in view ``v``
        (default: the current view)."""
        v = v or self.view
        anim = v.current_anim
        if anim is None:
            return 1.0, 0.0
        peak = anim.peak_max * cubic_scaling(v.ratio).amplitude
        if v.auto_amp:
            amp = sc.auto_amplification(self.geom, peak)
        else:
            amp = 10.0 ** v.amp_log
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
                   h_view=self._on_view, h_show_linear=self._on_show_linear, h_method=self._on_method,
                   h_integrator=self._on_integrator, h_compute_linear=self._on_compute_linear)
        return {name: self._cb(fn) for name, fn in cbs.items()}

    def _set_field(self, name):
        """Callback of a SIMPLE_CONTROLS handle: copy its value into its state field, redraw."""
        field, kind, redraws = SIMPLE_CONTROLS[name]

        def on_update(_):
            value = kind(getattr(self.layout, name).value)
            if field == "s":                 # the slider shows the point's number, 1-based; a point: no linear mode
                self.set_view(s=along_from_slider(value), linear_mode=None)
            else:
                self.set_view(**{field: value})
            self.request(*redraws)
        return on_update

    def _on_method(self, _):
        """The Compute tab's method: its own options shown (time steps for shooting, harmonics for HB)."""
        self.request("controls")

    def _on_integrator(self, _):
        """The Compute tab's integrator: the steps per period become its default (the solver's)."""
        self.layout.set(self.layout.h_spp, value=default_steps(self.layout.h_integrator.value))

    def _on_zoom(self, _):
        """The user's zoom choice, kept from now on (no more automatic zoom)."""
        self.set_view(zoom=bool(self.layout.h_zoom.value), zoom_auto=False)
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
        # a pick (or a branch chosen) shows its point again
        new, old = self.change_view(lambda v: dict(sel_uid=uid, s=float(s), linear_mode=None))
        changed = uid != old.sel_uid
        if changed:
            idx = self.shared.index_of(uid)
            if idx is not None:
                self._mode_lists_on(self.shared.snapshot()[idx])
        self.request("fep", "sliders", "point", *(("branches",) if changed else ()))

    def _mode_lists_on(self, e):
        """The mode lists of the Modes tab and the Compute tab on the linear mode of the selected branch ``e``
        (its NNM's mode): Start computes the selected NNM's mode unless another is chosen."""
        k = int(getattr(e.branch, "mode", 0) or 0)
        options = self.layout.mode_options
        if 1 <= k <= len(options):
            self.layout.set(self.layout.h_lin_mode, value=options[k - 1])
            self.layout.set(self.layout.h_mode, value=options[k - 1])

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
        energy = 10.0 ** float(self.layout.h_energy.value)
        self.change_view(lambda v: dict(s=energy_to_s(ser.energy, energy, v.s), linear_mode=None))
        self.request("fep", "sliders:along", "point")

    def _on_camera(self, camera):
        """A camera message of this tab: when its canvas changed size, the FEP board's spheres are drawn again.

        viser 1.1 outlines the hovered instance of a clickable batched mesh in screen space
        (BatchedMeshHoverOutlines) with the canvas size read once, when the mesh was added: after the canvas was
        resized (a window or a panel resized) that outline was offset by different amounts across and along the
        screen, a stretched translucent halo around the sphere under the pointer (the picked one, right after a
        click).  The spheres are added again under a new name (scene.sphere_group: a mesh re-sent under its
        old name keeps its outline and the old size), so the outline reads the canvas's size of now."""
        size = (int(camera.image_width), int(camera.image_height))
        if min(size) <= 0:
            return
        _, old = self.change_view(lambda v: dict(canvas=size))
        if old.canvas != size and not self.drawing.closed:
            self.request("board")

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
        self.set_view(camera_preset=name)

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
        return -sc.PRESET_DIRECTIONS.get(self.view.camera_preset, sc.CAMERA_DIR)


    def _dismiss_error(self, _):
        with self.shared.lock:
            self.shared.error = ""
        self.request("error")

    def _on_shared(self, kind):
        if kind == "branches":
            self.request("branches", "progress")
        elif kind == "progress":
            self.request("progress")
            with self.lock:
                pending = self._pending is not None
            if pending:                         # a recompute of the stiffness slider waits for a job
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
        self.set_view(message=msg)
        ui = self.layout
        ui.set(ui.h_error, content=f"**Error:** {msg}", visible=True)
        ui.set(ui.h_dismiss, visible=True)

    def show_status(self, msg):
        self.set_view(message=msg)
        self.layout.set(self.layout.h_status, content=msg)
