"""Exports of the Point tab offered to the browser as downloads (teaching, reports): the selected
branch's FEP (``nnm_solver.export_csv``) and the picked orbit over one period, as CSV bytes."""
from __future__ import annotations

import csv
import io
import re
import tempfile
from pathlib import Path

import numpy as np

import nnm_solver
from nnm_solver import cubic_scaling

from .numbering import point_number, point_words


def fep_csv(branch):
    """Bytes of ``nnm_solver.export_csv`` for ``branch`` (energy, frequency, period, stable, label)."""
    with tempfile.TemporaryDirectory(prefix="nnm-view-") as tmp:
        path = Path(tmp) / "fep.csv"
        nnm_solver.export_csv(path, branch)
        return path.read_bytes()


def orbit_columns(model):
    """Column names of the orbit CSV: t_s, then the model's DOF labels (x0..x{n-1} without them)."""
    labels = getattr(model, "dof_labels", None)
    if not labels or len(labels) != model.n:
        labels = [f"x{k}" for k in range(model.n)]
    return ["t_s", *labels]


def orbit_csv(point, model):
    """Bytes of the orbit ``point`` (info.PointData) as CSV: one row per time sample over one
    period, time (s) then the displacement (m or rad) of every DOF."""
    t = np.asarray(point.t, dtype=float)
    x = np.asarray(point.x, dtype=float).reshape(len(t), -1)
    if x.shape[1] != model.n:
        raise ValueError(f"the orbit has {x.shape[1]} DOFs, the model {model.n}")
    buf = io.StringIO(newline="")
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(orbit_columns(model))
    for ti, xi in zip(t, x):
        w.writerow([repr(float(ti)), *(repr(float(v)) for v in xi)])
    return buf.getvalue().encode("utf-8")


def file_stem(text):
    """``text`` made safe as (part of) a file name."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", str(text)).strip("._") or "nnm"


class DownloadActions:
    """The Point tab's downloads of one Session (a mixin of ``controls.Session``): the FEP and the orbit as
    CSV, the animation as GIF, sent to the browser."""

    def download(self, filename, content):
        """Offer ``content`` (bytes) to the browser as file ``filename`` (kept as ``last_download``)."""
        with self.lock:
            self.last_download = (filename, content)
        send = getattr(self.api, "send_file_download", None)
        if send is not None:
            send(filename, content, save_immediately=True)
        self.show_status(f"download: {filename} ({len(content)} bytes)")

    def _download_stem(self, e, v=None):
        """The file stem of entry ``e`` at view ``v``'s k3 factor (default: the current view)."""
        idx = self.shared.index_of(e.uid)
        factor = self.view_factor(e, v)
        k3 = f"_k3x{factor:.3g}" if abs(factor - 1.0) > 1e-9 else ""
        return file_stem(f"{self.model.name or 'model'}_branch{(idx or 0) + 1}_{e.label}{k3}")

    def fep_csv(self):
        """(file name, CSV bytes) of the selected branch's FEP, at the current k3 factor."""
        v = self.view
        e = self.selected_entry(v)
        if e is None or not len(e):
            raise ValueError("select a branch with points first")
        ratio = self.view_factor(e, v) / e.k3_factor
        branch = e.branch if abs(ratio - 1.0) < 1e-12 else e.branch.scaled(ratio)
        return f"{self._download_stem(e, v)}_fep.csv", fep_csv(branch)

    def _linear_stem(self, k):
        return file_stem(f"{self.model.name or 'model'}_linear_mode{k}")

    def download_orbit(self):
        """(view, entry or None for a linear mode, along) of the orbit the tab's view asks for: one view, taken
        once, whose ``current_point``, ``current_anim``, ``ratio`` are exactly that orbit (the linear mode shown,
        or the selected branch's point at the view's position and k3 factor), so that a download's name and
        content agree.  The orbit shown is used when it is that one; otherwise (the drawing has not caught up
        with the sliders yet) it is built for the view, under the drawing's lock (lock order: the drawing's, then
        the session's; the orbit caches are the drawing's), without changing the view.  ValueError when no orbit
        is shown (pick a point) or the one asked for cannot be computed yet."""
        from dataclasses import replace

        with self.drawing._draw_lock:
            v = self.view
            if v.current_point is None or v.current_anim is None:
                raise ValueError("no orbit shown: pick a point of the FEP first")
            point = self.drawing.point
            lin = v.linear_mode
            if lin is not None:
                if v.current_of != ("linear", int(lin)):
                    pd, anim = point.linear_orbit(lin)
                    v = replace(v, current_point=pd, current_anim=anim, current_uid=None, ratio=1.0,
                                current_of=("linear", int(lin)))
                return v, None, None
            e = self.selected_entry(v)
            if e is None or not len(e):
                raise ValueError("no orbit shown: pick a point of the FEP first")
            along = float(np.clip(v.s, 0, len(e) - 1))
            ratio = self.view_factor(e, v) / e.k3_factor
            if (v.current_uid == e.uid and v.current_of == (e.uid, along)
                    and abs(v.ratio - ratio) <= 1e-12 * abs(ratio)):
                return v, e, along                 # the orbit shown is the one asked for
            try:
                pd, anim, ratio, along = point.orbit(e, v)
            except RuntimeError as exc:
                raise ValueError(f"the orbit of {point_words(along, len(e))} is not computed yet ({exc}): "
                                 "download it once it is shown") from exc
            v = replace(v, current_point=pd, current_anim=anim, current_uid=e.uid, ratio=ratio,
                        current_of=(e.uid, along))
            return v, e, along

    def orbit_csv(self):
        """(file name, CSV bytes) of the orbit the view shows (the picked point at the view's position and k3
        factor, ``download_orbit``), or of the linear mode shown."""
        v, e, along = self.download_orbit()
        if e is None:
            return f"{self._linear_stem(v.linear_mode)}_orbit.csv", orbit_csv(v.current_point, self.model)
        return (f"{self._download_stem(e, v)}_point{point_number(along)}_orbit.csv",
                orbit_csv(v.current_point, self.model))

    def animation_gif(self):
        """(file name, GIF bytes) of the orbit the view shows (``download_orbit``) over one period, as shown
        (amplification, k3 factor), seen along the tab's camera direction."""
        from .gif import gif_title, orbit_gif

        from .info import linear_mode_title

        v, e, along = self.download_orbit()
        pd, anim = v.current_point, v.current_anim
        amp, peak = self.amplification(v)
        if e is None:
            lin = v.linear_mode
            title = gif_title("L" + linear_mode_title(self.model, self.shared.linear_freqs, lin, freq=False)[1:], pd, peak)
            return f"{self._linear_stem(lin)}.gif", orbit_gif(anim, amp, self.view_direction(), title=title)
        idx = self.shared.index_of(e.uid)
        title = gif_title(f"Branch {(idx or 0) + 1}: {e.label}, {point_words(along, len(e))}", pd, peak)
        data = orbit_gif(anim, amp * cubic_scaling(v.ratio).amplitude, self.view_direction(), title=title)
        return f"{self._download_stem(e, v)}_point{point_number(along)}.gif", data

    def _on_gif(self, _):
        self.show_status("drawing the animation (GIF) …")
        self.download(*self.animation_gif())

    def _on_csv_fep(self, _):
        self.download(*self.fep_csv())

    def _on_csv_orbit(self, _):
        self.download(*self.orbit_csv())
