"""Draw steps of the picked point: its orbit (solver), the animated mesh (GLB) and the Point tab
(numbers and charts).  Orbits and animations are computed for the branch's own springs and
cached; the current k3 factor is applied with the exact scaling law."""
from __future__ import annotations

import numpy as np

from nnm_solver import cubic_scaling

from . import scene as sc
from .animation import orbit_animation
from .colorbar import colorbar_image
from .numbering import nearest_row, point_words
from .info import (auto_dofs, info_markdown, linear_mode_point, linear_mode_title, method_text, parse_dofs,
                   peak_text, point_data, uplot_harmonics, uplot_time_series)

#: cached orbits / animations per tab (cleared when full)
POINT_CACHE = 64
ANIM_CACHE = 32


def point_label_and_error(branch, along):
    """(label, estimated relative frequency error) of the computed point nearest to ``along``: the
    branch's ``labels`` and ``freq_error`` (None where the branch, e.g. from an older file, has none; inf where a
    harmonic-balance point's truncation does not resolve its orbit, orbits/hb_error.py)."""
    n = len(branch)
    i = nearest_row(along, n)                 # Branch.interpolate's nearer neighbour
    labels = getattr(branch, "labels", None)
    label = str(labels[i]) if labels is not None and len(labels) == n else None
    err = getattr(branch, "freq_error", None)
    value = None
    if err is not None:
        try:
            arr = np.asarray(err, dtype=float).reshape(-1)
            value = float(arr[i]) if len(arr) == n and not np.isnan(arr[i]) else None   # inf: not resolved
        except (TypeError, ValueError):
            value = None
    return label, value


class PointView:
    """The orbit shown by one tab: ``compute`` sets the session's ``current_*``, the draw steps
    show it."""

    def __init__(self, session):
        self.session = session
        self.ui = session.layout
        self._point_cache: dict = {}
        self._anim_cache: dict = {}
        self.charts = {}             # uPlot handles of the Point tab: name -> (handle, n_series)
        self.last_glb = None         # bytes of the last GLB sent (tests, benchmark)
        self.colorbar_peak = None    # peak (m) of the colour bar shown

    def compute(self):
        """Orbit and animation of the selection (None if the branch has no point); True."""
        s = self.session
        v = s.view
        if v.linear_mode is not None:             # a linear mode (Modes tab): no solver needed
            return self.compute_linear(v.linear_mode)
        e = s.selected_entry(v)
        if e is None or not len(e):
            s.set_view(current_point=None, current_anim=None, current_uid=None if e is None else e.uid,
                       current_of=None)
            return True
        # until the branch's integrator is compiled (warmup.py, then the session asks again) the orbit is
        # scipy's (Branch.reference_motion: no compiled kernel), replaced by the solver's own once ready
        reference = not s.shared.orbits_ready.is_set()
        try:
            pd, anim, ratio, along = self.orbit(e, v, reference)
        except RuntimeError:
            if not reference:
                raise
            # too slow or failed: the model at rest until the solver's orbit
            _, old = s.change_view(lambda w: dict(current_point=None, current_anim=None, current_uid=e.uid,
                                                  current_of=None))
            return not (old.current_point is None and self.last_glb is not None)
        s.set_view(current_point=pd, current_anim=anim, current_uid=e.uid, ratio=ratio, current_of=(e.uid, along))
        return True

    def orbit(self, e, v, reference=None):
        """(PointData scaled to view ``v``'s k3 factor, its OrbitAnimation, that factor over the branch's, the
        position along the branch) of the point view ``v`` asks for on entry ``e`` (cached per branch and
        position; the caches are the drawing's: call under its lock).  reference: scipy's orbit (default: while
        the solver's integrator is not compiled yet); RuntimeError if the orbit cannot be integrated."""
        s = self.session
        if reference is None:
            reference = not s.shared.orbits_ready.is_set()
        along = float(np.clip(v.s, 0, len(e) - 1))
        key = (e.uid, len(e), round(along, 4), reference)
        pd = self._point_cache.get(key)
        if pd is None:
            pd = point_data(e.branch, along, reference=reference)
            if len(self._point_cache) > POINT_CACHE:
                self._point_cache.clear()
            self._point_cache[key] = pd
        anim = self._anim_cache.get(key)
        if anim is None:
            anim = orbit_animation(s.mesh.vertices, s.mesh.faces, s.shared.mapper, pd.t, pd.x, pd.period)
            if len(self._anim_cache) > ANIM_CACHE:
                self._anim_cache.clear()
            self._anim_cache[key] = anim
        ratio = s.view_factor(e, v) / e.k3_factor        # 1 unless the scaling law applies
        return pd.scaled(ratio), anim, ratio, along

    def compute_linear(self, k):
        """Linear mode ``k`` as the point shown; True (see ``linear_orbit``)."""
        pd, anim = self.linear_orbit(k)
        self.session.set_view(current_point=pd, current_anim=anim, current_uid=None, ratio=1.0,
                              current_of=("linear", int(k)))
        return True

    def linear_orbit(self, k):
        """(PointData, OrbitAnimation) of linear mode ``k``: its amplitude a is chosen so that its peak vertex
        displacement is the auto amplification's (scene.AUTO_PEAK_FRACTION of the model size), so that it looks
        the same with a manual amplification of 1 (cached; call under the drawing's lock)."""
        s = self.session
        key = ("linear", int(k))
        cached = self._anim_cache.get(key)
        if cached is None:
            freqs, shapes = s.shared.linear_freqs, s.shared.linear_shapes
            verts, faces, mapper = s.mesh.vertices, s.mesh.faces, s.shared.mapper
            unit = linear_mode_point(s.model, k, freqs, shapes, 1.0)
            peak = orbit_animation(verts, faces, mapper, unit.t, unit.x, unit.period).peak_max
            a = sc.auto_amplification(s.geom, peak)
            pd = linear_mode_point(s.model, k, freqs, shapes, a)
            cached = (pd, orbit_animation(verts, faces, mapper, pd.t, pd.x, pd.period))
            if len(self._anim_cache) > ANIM_CACHE:
                self._anim_cache.clear()
            self._anim_cache[key] = cached
        return cached

    def draw_glb(self):
        """The model: animated over one orbit, or at rest if no point is shown."""
        s, ui = self.session, self.ui
        v = s.view
        anim = v.current_anim
        if anim is None:
            glb = sc.static_glb(s.mesh)
            ui.set(ui.h_peak, content="")
            ui.set(ui.h_colorbar, visible=False)
        else:
            amp, peak = s.amplification(v)
            shown = 1.0 / max(v.speed, 1e-3)
            glb = anim.glb(amp * cubic_scaling(v.ratio).amplitude, display_period=shown, playing=v.playing,
                           phase=v.phase)
            if v.auto_amp:
                self.show_auto_amplification(amp)
            lin = v.linear_mode
            ui.set(ui.h_peak, content=(f"**{linear_mode_title(s.model, s.shared.linear_freqs, lin, freq=False)}** "
                                       "(amplitude chosen for display)  \n" if lin is not None else "")
                   + peak_text(peak, amp, v.auto_amp)
                   + f"  \nreal period {anim.period:.4g} s, shown in {shown:.3g} s")
        s.scene.add_glb("/model", glb, cast_shadow=False, receive_shadow=False)
        self.last_glb = glb
        if anim is not None:             # after the animation, which the user waits for
            self.draw_colorbar(s.amplification(v)[1])

    def show_auto_amplification(self, amp):
        """Auto amplification ``amp`` on the Amplification log10 slider and in the view's ``amp_log`` (the stored
        value), together under the session's lock and only while Auto is still on: the slider always shows the
        stored value, so unticking Auto keeps the factor the slider shows (docs/viewer.md: 'Off: the
        Amplification log10 slider sets a fixed factor')."""
        s, ui = self.session, self.ui
        shown = float(np.clip(round(float(np.log10(amp)), 2), -1.0, 6.0))
        with s.lock:
            if s.view.auto_amp:               # unticked meanwhile: the slider keeps the value it shows
                s.set_view(amp_log=shown)
                ui.set(ui.h_amp, value=shown)

    def draw_colorbar(self, peak):
        """The colour bar of the displacement colours, 0 .. the true peak displacement (redrawn when
        the peak changes)."""
        ui = self.ui
        if self.colorbar_peak is None or abs(peak - self.colorbar_peak) > 1e-9 * max(peak, 1e-300):
            ui.h_colorbar.image = colorbar_image(peak)
            self.colorbar_peak = peak
        ui.set(ui.h_colorbar, visible=True)

    def draw_info(self):
        """The Point tab: numbers, MAC table, time series and Fourier amplitudes of chosen DOFs."""
        s, ui = self.session, self.ui
        v = s.view
        pd = v.current_point
        if pd is None:
            ui.set(ui.h_info, content="no point selected" if s.shared.solver_ready.is_set() else
                   "preparing the solver (compiling its kernels): the orbit is shown as soon as it is ready")
            return
        lin = v.linear_mode
        if lin is not None:
            ui.set(ui.h_info, content=info_markdown(pd, s.model, s.shared.linear_freqs, None,
                                                    where=linear_mode_title(s.model, s.shared.linear_freqs, lin)))
        else:
            idx = s.shared.index_of(v.sel_uid)
            e = s.selected_entry(v)
            if e is None or idx is None:          # the branch went away meanwhile: the next draw shows another
                return
            where = f"Branch {idx + 1} ({e.label}), {point_words(v.s, len(e))}"
            label, err = point_label_and_error(e.branch, v.s)
            ui.set(ui.h_info, content=info_markdown(pd, s.model, s.shared.linear_freqs, s.view_factor(e, v),
                                                    where=where, label=label, freq_error=err,
                                                    method=method_text(e.branch)))
        try:
            dofs = parse_dofs(v.dofs_text, s.model.n, auto_dofs(s.model, pd.x))
        except ValueError as exc:
            s.show_error(str(exc))
            dofs = auto_dofs(s.model, pd.x)
        self._chart("time", "Time series over one period (vs t/T)", *uplot_time_series(pd, s.model, dofs),
                    order=1000.0)
        self._chart("harm", "Fourier coefficients: log10 amplitude (m) vs harmonic k",
                    *uplot_harmonics(pd, s.model, dofs), order=1001.0)

    def _chart(self, key, title, data, series, order):
        """Create or update a uPlot chart of the Point tab (re-created if the series change)."""
        from viser import uplot

        h, n = self.charts.get(key, (None, 0))
        if h is not None and n == len(series):
            h.series = series
            h.data = data
            return
        if h is not None:
            h.remove()
        scales = {"x": uplot.Scale(time=False, auto=True), "y": uplot.Scale(auto=True)}
        axes = (uplot.Axis(), uplot.Axis(size=64))
        with self.ui.tab_point:
            h = self.ui.gui.add_uplot(data, series, title=title, scales=scales, axes=axes, aspect=1.6,
                                      legend=uplot.Legend(show=True), order=order)
        self.charts[key] = (h, len(series))
