"""Frequency-energy plot (FEP): the panel image and the clickable copy in the 3D scene (placed by board.py); its
colours and markers are in fep_style.py, the mapping between an energy and a position along a branch in
fep_along.py.

Axes follow the literature (seed paper Figs. 8-11): x = energy (J, log scale), y =
frequency (Hz).  Stable points are filled, unstable points hollow/red.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .fep_along import energy_at, energy_to_s, interp_at
from .fep_style import (BRANCH_COLORS, BRANCH_HUES, END_MARKERS, EVENT_LABELS, MARKER_RGB, STABLE_RGB, UNSTABLE_PALE,
                        UNSTABLE_RGB, branch_color, event_kind, event_style, off_backbone_style, pale, rgb)

__all__ = ["FepSeries", "FepRenderer", "render_fep", "plot_branches", "set_fep_axes", "axis_ranges", "should_zoom",
           "Y_LABELS", "LEGEND_MAX", "trim_legend", "wrap_title",
           # re-exported from fep_style.py and fep_along.py, where they are written
           "BRANCH_COLORS", "BRANCH_HUES", "END_MARKERS", "EVENT_LABELS", "MARKER_RGB", "STABLE_RGB", "UNSTABLE_PALE",
           "UNSTABLE_RGB", "branch_color", "event_kind", "event_style", "off_backbone_style", "pale", "rgb",
           "energy_at", "energy_to_s", "interp_at"]


@dataclass
class FepSeries:
    """One branch as drawn: energy (N,) J, frequency (N,) Hz, stable (N,) bool, label; events
    [(kind, energy J, frequency Hz)] and status (Branch.status) of the branch; labels (N,) the points' labels
    (Branch.labels: 'backbone', 'tongue 3:1', ...; empty: all on the backbone)."""

    energy: np.ndarray
    frequency: np.ndarray
    stable: np.ndarray
    label: str
    events: list = field(default_factory=list)
    status: str = ""
    labels: tuple = ()

    def __len__(self):
        return len(self.energy)

    def off_backbone(self):
        """[(label, boolean mask)] of the points off the backbone, by label in order of appearance."""
        labels = np.asarray([str(x) for x in self.labels], dtype=object)
        if len(labels) != len(self.energy):
            return []
        return [(lab, labels == lab) for lab in dict.fromkeys(labels) if lab != "backbone"]

    def relative(self, f_linear):
        """The same branch on the relative frequency axis: 100 (f / f_linear - 1) (%), events too."""
        f_linear = float(f_linear)
        if not f_linear > 0:
            raise ValueError(f"relative frequency axis: the linear frequency is {f_linear}")

        def rel(f):
            return 100.0 * (np.asarray(f, dtype=float) / f_linear - 1.0)

        return FepSeries(self.energy, rel(self.frequency), self.stable, self.label,
                         events=[(k, e, float(rel(f))) for k, e, f in self.events], status=self.status,
                         labels=self.labels)


#: y-axis labels of the FEP: absolute (Hz) or relative to the branch's linear frequency (%)
Y_LABELS = {False: "frequency (Hz)", True: "f / f_linear \u2212 1 (%)"}
#: the FEP zooms on the selected branch by default when its frequency span is below this fraction of
#: the span of all branches (and there are other branches)
AUTO_ZOOM_FRACTION = 0.1


def should_zoom(series, selected):
    """True when the FEP should zoom on series ``selected`` (index) by default: it spans less than
    AUTO_ZOOM_FRACTION of the frequency range of all branches (others would flatten it)."""
    if selected is None or not 0 <= selected < len(series) or not len(series[selected]):
        return False
    others = [s for k, s in enumerate(series) if k != selected and len(s)]
    if not others:
        return False
    every = np.concatenate([np.asarray(s.frequency, dtype=float) for s in series if len(s)])
    span_all = float(np.ptp(every))
    return span_all > 0 and float(np.ptp(series[selected].frequency)) < AUTO_ZOOM_FRACTION * span_all


def _inside(le, f, ranges):
    """Mask of the points (log10 E, f) inside ``ranges`` (all when ranges is None)."""
    if ranges is None:
        return np.ones(len(le), dtype=bool)
    (elo, ehi), (flo, fhi) = ranges
    return (le >= elo) & (le <= ehi) & (f >= flo) & (f <= fhi)


def plot_branches(ax, series, selected_branch=None, points=True, lw=1.2, ms=3.5, event_ms=7.0, event_mew=1.5,
                  ranges=None, legend_max=None):
    """Draw the branches on a matplotlib Axes in log10(energy) vs frequency: a line per branch in its
    colour (branch_color of its position), its points (``points``: stable filled, unstable hollow),
    its events by kind and the end of a branch that failed, escaped or closed a loop; the points off the backbone
    (a tongue's) in the solver's style (``off_backbone_style``: marked over the points; without ``points``, the
    board's spheres take that colour and the legend says so).  Returns the legend (handles, labels) of what is seen
    inside ``ranges`` (the axes' ((log10 E lo, hi), (f lo, hi)); everything when None): the branches, the event and
    end kinds, 'unstable', then the labels off the backbone.  With ``legend_max`` entries at most, the branches
    give way first ('… and 3 more branches'): every kind of marker drawn keeps its entry."""
    handles, labels, extra = [], [], {}
    off_handles = {}
    off_markers, off_color = off_backbone_style()
    any_unstable = False
    for k, s in enumerate(series):
        if not len(s):
            continue
        c = branch_color(k)
        le = np.log10(np.maximum(np.asarray(s.energy, dtype=float), 1e-300))
        f = np.asarray(s.frequency, dtype=float)
        (line,) = ax.plot(le, f, "-", color=c, lw=lw * (1.8 if k == selected_branch else 1.0), zorder=2)
        seen = _inside(le, f, ranges)
        if seen.any():                  # a branch outside the axes (zoomed on another) is not in the legend
            handles.append(line)
            labels.append(s.label)
        st = np.asarray(s.stable, dtype=bool)
        any_unstable |= bool((~st & seen).any())
        if points:
            ax.plot(le[st], f[st], "o", ms=ms, color=c, zorder=3)
            if (~st).any():
                ax.plot(le[~st], f[~st], "o", ms=ms * 1.25, mfc="white", mec=c, mew=1.2, zorder=3)
        for j, (lab, mask) in enumerate(s.off_backbone()):
            marker = off_markers[j % len(off_markers)]
            if points:
                for part, fill in ((mask & st, off_color), (mask & ~st, "white")):
                    if part.any():
                        (h,) = ax.plot(le[part], f[part], marker, ms=ms * 2.2, color=off_color, mfc=fill,
                                       mec="k" if fill != "white" else off_color, mew=0.6, zorder=3.5)
                        if (part & seen).any():
                            off_handles.setdefault(lab, h)
            elif lab not in off_handles and (mask & seen).any():
                (off_handles[lab],) = ax.plot([], [], "o", ms=ms * 1.6, color=off_color)
        for kind, energy, freq in s.events:
            marker, colour = event_style(kind)
            x = np.log10(max(energy, 1e-300))
            (h,) = ax.plot([x], [freq], marker, ms=event_ms, mfc="none", mec=colour, color=colour, mew=event_mew,
                           zorder=4)
            if _inside(np.array([x]), np.array([freq]), ranges).all():
                extra.setdefault(("event", kind), h)
        if s.status in END_MARKERS:
            marker, colour, _ = END_MARKERS[s.status]
            (h,) = ax.plot([le[-1]], [f[-1]], marker, ms=event_ms * 1.5, color=colour, mec="white", mew=0.8,
                           zorder=5)
            if seen[-1]:
                extra.setdefault(("end", s.status), h)
    n_branches = len(labels)
    # the markers drawn (events, ends) before the generic entries, so that a full legend never drops them
    order = [("event", k) for k in EVENT_LABELS] + [("end", k) for k in END_MARKERS]
    order += sorted(k for k in extra if k not in order)
    for key in order:
        if key in extra:
            handles.append(extra[key])
            labels.append(EVENT_LABELS.get(key[1], key[1].replace("_", " ")) if key[0] == "event"
                          else END_MARKERS[key[1]][2])
    if any_unstable:
        (h,) = ax.plot([], [], "o", ms=ms * 1.25, mfc="white", mec="#555555", mew=1.2) if points else \
            ax.plot([], [], "o", ms=ms * 1.6, color=pale("#555555"))
        handles.append(h)
        labels.append("unstable" if points else "pale: unstable")
    for lab, h in off_handles.items():
        handles.append(h)
        labels.append(f"{lab} (off the backbone)" if points else f"orange: {lab} (off the backbone)")
    return trim_legend(ax, handles, labels, n_branches, legend_max)


def trim_legend(ax, handles, labels, n_branches, limit):
    """At most ``limit`` legend entries: the first ``n_branches`` entries (the branches) give way to the others
    (the markers' kinds), the last kept line saying how many branches are not listed."""
    if limit is None or len(labels) <= limit:
        return handles, labels
    others = len(labels) - n_branches
    keep = max(limit - others - 1, 0)
    (more,) = ax.plot([], [], " ")
    h = handles[:keep] + [more] + handles[n_branches:]
    lab = labels[:keep] + [f"\u2026 and {n_branches - keep} more branches"] + labels[n_branches:]
    return h[:limit], lab[:limit]


#: padding of the FEP's axis ranges (fraction of the span, each side)
AXIS_PAD = 0.09


def axis_ranges(series):
    """(log10 E min, log10 E max), (f min, f max) over all non-empty series, padded AXIS_PAD of the span on each
    side: room for the largest marker (a branch's end, 10.5 pt) at the edge of the panel's axes."""
    es = [np.log10(np.maximum(s.energy, 1e-300)) for s in series if len(s)]
    fs = [np.asarray(s.frequency, dtype=float) for s in series if len(s)]
    if not es:
        return (-3.0, 3.0), (0.0, 1.0)
    e = np.concatenate(es)
    f = np.concatenate(fs)
    elo, ehi = float(e.min()), float(e.max())
    flo, fhi = float(f.min()), float(f.max())
    if ehi - elo < 1e-9:
        elo, ehi = elo - 0.5, ehi + 0.5
    if fhi - flo < 1e-12 * max(abs(fhi), 1.0):
        pad = max(abs(fhi) * 0.01, 1e-3)
        flo, fhi = flo - pad, fhi + pad
    de, df = AXIS_PAD * (ehi - elo), AXIS_PAD * (fhi - flo)
    return (elo - de, ehi + de), (flo - df, fhi + df)


def _hex(rgb):
    return "#{:02x}{:02x}{:02x}".format(*rgb)


#: legend entries of the panel image at most
LEGEND_MAX = 16


def wrap_title(title, width=44):
    """The panel FEP's title on lines of at most ``width`` characters, broken after a comma or at a
    space ('Frequency-energy plot (k3 x 3.16), zoomed on the selected branch' takes two lines)."""
    import textwrap

    return "\n".join(textwrap.wrap(title, width=width, break_long_words=False)) or title


class FepRenderer:
    """Draws the FEP panel image with matplotlib (Agg).

    ``set_series`` draws the branches once and keeps the picture; ``image(selected)`` only
    restores it and draws the marker of the picked orbit (fast: no full redraw while the
    user drags a slider).  Axes: x = log10 energy (J), y = frequency (Hz).
    """

    def __init__(self, size=(520, 380)):
        from matplotlib.figure import Figure
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        dpi = 100
        # constrained layout: the title, the axis labels and the legend below the axes are fitted inside
        # the image whatever their length (a fixed axes box cut a long title and a long legend off)
        self.fig = Figure(figsize=(size[0] / dpi, size[1] / dpi), dpi=dpi, layout="constrained")
        self.fig.get_layout_engine().set(w_pad=0.06, h_pad=0.06)
        self.canvas = FigureCanvasAgg(self.fig)
        self.ax = self.fig.add_subplot()
        self._background = None
        (self._star,) = self.ax.plot([], [], "*", ms=16, color=_hex(MARKER_RGB), mec="black", mew=0.8,
                                     zorder=5, animated=True)

    def set_series(self, series, selected_branch=None, title=None, ghosts=(), ranges=None, ylabel=Y_LABELS[False],
                   measured=None):
        """Draw all branches (series: list of FepSeries); ghosts in light grey; ranges: axis
        ranges ((log10 E lo, hi), (f lo, hi)), default: fitted to everything drawn; measured: (energy J,
        frequency, legend label) of measured points, drawn as black rings (nnm_viewer/measured.py)."""
        ax = self.ax
        for artist in list(ax.lines) + list(ax.texts):
            if artist is not self._star:
                artist.remove()
        for leg in list(self.fig.legends):
            leg.remove()
        handles, labels = [], []
        if any(len(g) for g in ghosts):
            for g in ghosts:
                if len(g):
                    ax.plot(np.log10(g.energy), g.frequency, "-", color="#c8c8c8", lw=1.0, zorder=1)
            handles += ax.plot([], [], "-", color="#c8c8c8")
            labels.append("as in the file (k3 x 1)")
        if measured is not None and len(measured[0]):
            handles += ax.plot(np.log10(measured[0]), measured[1], "o", mfc="none", color="k", ms=5, mew=1.0,
                               zorder=4)
            labels.append(measured[2])
        ranges = ranges or axis_ranges(list(series) + list(ghosts))
        h, lab = plot_branches(ax, series, selected_branch, ranges=ranges,
                               legend_max=LEGEND_MAX - len(labels))
        set_fep_axes(ax, ranges, ticks_size=8, label_size=9, ylabel=ylabel)
        if h:
            # below the axes, so that it never hides a branch; as many rows as needed (LEGEND_MAX entries)
            handles, labels = (handles + h)[:LEGEND_MAX], (labels + lab)[:LEGEND_MAX]
            self.fig.legend(handles, labels, fontsize=7, loc="outside lower center", ncol=2, frameon=False,
                            handlelength=1.6, columnspacing=1.0)
        else:
            ax.text(0.5, 0.5, "no branch yet:\ncompute one in the Compute tab", ha="center", va="center",
                    transform=ax.transAxes, color="grey")
        ax.set_title(wrap_title(title or "Frequency-energy plot"), fontsize=10)
        self.canvas.draw()
        self._background = self.canvas.copy_from_bbox(self.fig.bbox)

    @property
    def legend(self):
        """The image's legend (below the axes), or None before any branch is drawn."""
        return self.fig.legends[0] if self.fig.legends else None

    def image(self, selected=None):
        """RGB image (H, W, 3) uint8 with the picked orbit (energy J, frequency Hz) marked."""
        if self._background is None:
            self.set_series([])
        self.canvas.restore_region(self._background)
        if selected is not None:
            self._star.set_data([np.log10(max(selected[0], 1e-300))], [selected[1]])
            self.ax.draw_artist(self._star)
        return np.asarray(self.canvas.buffer_rgba())[..., :3].copy()


def render_fep(series, selected=None, selected_branch=None, size=(520, 380), title=None, ghosts=()):
    """The FEP as an RGB image (H, W, 3) uint8 (one-shot use of FepRenderer).

    selected : (energy J, frequency Hz) of the picked orbit, marked with a star;
    selected_branch : index of the branch drawn thicker; ghosts : series drawn in light grey.
    """
    r = FepRenderer(size)
    r.set_series(series, selected_branch, title, ghosts)
    return r.image(selected)


def set_fep_axes(ax, ranges, ticks_size, label_size, grid_alpha=0.25, ylabel=Y_LABELS[False]):
    """Limits, decade ticks of log10(energy) ("1e-2", ...) and labels of a FEP drawn in log10(E)."""
    (elo, ehi), (flo, fhi) = ranges
    ax.set_xlim(elo, ehi)
    ax.set_ylim(flo, fhi)
    ticks = np.arange(np.ceil(elo), np.floor(ehi) + 1)
    if len(ticks) > 8:
        ticks = ticks[:: int(np.ceil(len(ticks) / 8))]
    ax.set_xticks(ticks)
    ax.set_xticklabels([f"1e{int(t)}" for t in ticks], fontsize=ticks_size)
    ax.tick_params(labelsize=ticks_size)
    ax.ticklabel_format(axis="y", useOffset=False)      # the frequencies themselves, never '0.0001 + 1.2345e2'
    ax.set_xlabel("energy (J)", fontsize=label_size)
    ax.set_ylabel(ylabel, fontsize=label_size)
    ax.grid(True, alpha=grid_alpha)
