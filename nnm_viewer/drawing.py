"""Drawing of a tab: requests are coalesced and drawn by one thread per tab (latest state
wins), in the order the user waits for them: the animation first, then the FEP, the sliders
and the information panel.  Each step is isolated: a failure (e.g. the solver cannot integrate
an orbit) is shown in the page and the other steps still run.

``Drawing`` owns the machinery and the small steps of the control panel (animation and stiffness
controls, job progress, errors); the FEP steps are in fep_view.py, the point steps in point_view.py.
"""
from __future__ import annotations

import logging
import threading
import time

import numpy as np

from .fep_view import FepView
from .layout import METHODS, k3_text
from .point_view import PointView
from .worker import one_line

log = logging.getLogger("nnm_viewer")

#: everything a new tab draws
ALL_KINDS = ("branches", "controls", "fep", "sliders", "point", "glb", "info", "progress", "error", "solver", "ghost")


class Drawing:
    """Redraw requests and draw steps of one ``Session``.  Each step reads the tab's state once, as one
    immutable record (``session.view``, view_state.py); ``_draw_lock`` lets one thread draw at a time and
    is taken before the session's lock, never after."""

    def __init__(self, session, sync=False):
        self.session = session
        self.ui = session.layout
        self.sync = sync
        self.fep = FepView(session)
        self.point = PointView(session)
        self._dirty: set[str] = set()
        self._wake = threading.Event()
        self._draw_lock = threading.RLock()
        self._closed = False
        self.ghost_handle = None

    def start(self):
        """Start the per-tab draw thread (not with sync=True: requests are drawn by the caller)."""
        if not self.sync:
            threading.Thread(target=self._loop, name="nnm-view-draw", daemon=True).start()

    @property
    def closed(self):
        """True once the tab has closed (no more drawing)."""
        return self._closed

    def request(self, *kinds):
        """Ask for redraws: 'branches', 'board' (the FEP board's spheres only), 'controls', 'fep', 'sliders'
        (or 'sliders:energy' / 'sliders:along'), 'point', 'glb', 'info', 'readout', 'progress', 'error'."""
        with self.session.lock:
            self._dirty.update(kinds)
        if self.sync:
            self.flush()
        else:
            self._wake.set()

    def flush(self):
        """Draw everything requested so far (in the caller's thread, one drawer at a time)."""
        with self._draw_lock:
            while True:
                with self.session.lock:
                    kinds, self._dirty = self._dirty, set()
                if not kinds or self._closed:
                    return
                t0 = time.perf_counter()
                try:
                    self.draw(kinds)
                except Exception as exc:
                    self.session.show_error(one_line(exc))
                log.info("drew %s in %.3f s", ",".join(sorted(kinds)), time.perf_counter() - t0)

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

    def draw(self, kinds):
        """Run the draw steps for ``kinds``; a failing step (e.g. the solver cannot integrate
        an orbit) is reported in the page and does not stop the others."""
        def step(fn, *args):
            try:
                return fn(*args)
            except Exception as exc:
                self.session.show_error(one_line(exc))
                return False

        kinds = set(kinds)
        if "branches" in kinds:
            if step(self.fep.check_selection):
                kinds.add("point")
            kinds |= {"fep", "sliders", "fep_series"}
        if "solver" in kinds:
            step(self.draw_solver)
        if "controls" in kinds:
            step(self.draw_controls)
        # before the branch's integrator is compiled the orbit is scipy's (point_view.py), which takes a
        # while: the rest of the page is drawn first
        deferred = "point" in kinds and not self.session.shared.orbits_ready.is_set()
        if "point" in kinds and not deferred and step(self.point.compute):
            kinds |= {"glb", "info"}
        if "glb" in kinds:            # first: the animation is what the user waits for
            step(self.point.draw_glb)
        if "ghost" in kinds:
            step(self.draw_ghost)
        if "branches" in kinds:
            step(self.fep.draw_branch_list)
        if "branches" in kinds or "board" in kinds:     # 'board': the spheres again (a resized canvas)
            step(self.fep.draw_board)
        if "fep_series" in kinds:
            step(self.fep.draw_series)
        if "fep" in kinds:
            step(self.fep.draw_image)            # with the readout
        elif "readout" in kinds or "point" in kinds:
            step(self.fep.draw_readout)
        slider_kinds = {k for k in kinds if k.startswith("sliders")}
        if slider_kinds:
            skip = {frozenset({"sliders:along"}): "energy", frozenset({"sliders:energy"}): "along"}
            step(self.fep.draw_sliders, skip.get(frozenset(slider_kinds)))
        if deferred and step(self.point.compute):
            step(self.point.draw_glb)
            kinds.add("info")
        if "info" in kinds:
            step(self.point.draw_info)
        if "progress" in kinds:
            step(self.draw_progress)
        if "error" in kinds:
            step(self.draw_error)

    # ---- control panel
    def draw_controls(self):
        """Controls that depend on others: phase slider (paused only), manual amplification,
        the k3 label."""
        s, ui = self.session, self.ui
        v = s.view
        ui.set(ui.h_phase, visible=not v.playing)
        ui.set(ui.h_amp, disabled=v.auto_amp)
        ui.set(ui.h_k3_text, content=k3_text(v.factor, s.scaling_law))
        shooting = METHODS.get(str(ui.h_method.value), ("shooting", False))[0] == "shooting"
        ui.set(ui.h_integrator, visible=shooting)
        ui.set(ui.h_spp, visible=shooting)
        ui.set(ui.h_harmonics, visible=not shooting)

    def draw_ghost(self):
        """The undeformed shape, translucent, when asked for."""
        from .scene import draw_ghost

        self.ghost_handle = draw_ghost(self.session.scene, self.session.mesh, self.session.view.show_ghost)

    def draw_solver(self):
        """'Preparing the solver' while its kernels are being compiled (warmup.py)."""
        self.ui.set(self.ui.h_solver, visible=not self.session.shared.solver_ready.is_set())

    def draw_progress(self):
        s, ui = self.session, self.ui
        with s.shared.lock:
            job, progress, status = s.shared.job, s.shared.progress, s.shared.status
        running = job is not None and job.running
        e = s.selected_entry()
        ui.set(ui.h_progress, value=float(np.clip(100.0 * progress, 0, 100)))
        shared_status = status
        status = status or "no job running"
        if not s.shared.solver_ready.is_set():
            status = ("preparing the solver (compiling its kernels): a job started now begins when it is ready"
                      + (f"  \n{shared_status}" if shared_status else ""))
        ui.set(ui.h_job, content=status)
        ui.set(ui.h_start, disabled=running)
        ui.set(ui.h_compute_linear, disabled=running)
        ui.set(ui.h_modes_job, content=f"**Job:** {status}" if job is not None or shared_status else "")
        ui.set(ui.h_stop, disabled=not running)
        ui.set(ui.h_recompute, disabled=running or e is None or abs(s.view.factor / e.k3_factor - 1.0) < 1e-9)
        ui.set(ui.h_save, disabled=e is None or e.saved or e.source == "running")

    def draw_error(self):
        s, ui = self.session, self.ui
        with s.shared.lock:
            msg = s.shared.error
        ui.set(ui.h_error, content=f"**Error:** {msg}" if msg else "", visible=bool(msg))
        ui.set(ui.h_dismiss, visible=bool(msg))
        s.set_view(message=msg)
        ui.set(ui.h_status, content=msg)
