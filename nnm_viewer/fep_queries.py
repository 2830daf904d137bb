"""What a tab's frequency-energy plot shows (a mixin of ``controls.Session``): each branch's series at the k3
factor it is shown at, on the frequency axis chosen (Hz or % of the linear frequency), and the axis ranges (all
branches, or zoomed on the selected one)."""
from __future__ import annotations

from .fep import Y_LABELS, axis_ranges, should_zoom

__all__ = ["FepQueries"]


class FepQueries:
    """The FEP's series and ranges of a Session (its state: factor, scaling_law, relative, zoom, zoom_auto,
    sel_uid, shared)."""

    def view_factor(self, e, v=None):
        """The k3 factor entry ``e`` is shown at in view ``v`` (default: the tab's current view): the slider's
        (exact scaling law) when its springs are all pure cubic, else its own (nothing is scaled; the slider
        recomputes instead)."""
        return (v or self.view).factor if self.scaling_law and e.scalable else e.k3_factor

    def fep_series(self, e, factor=None, v=None):
        """FEP series of entry ``e`` at the k3 factor ``factor`` (default: the one it is shown at,
        ``view_factor``), on the frequency axis chosen in view ``v`` (Hz, or relative to the branch's linear
        frequency, %)."""
        v = v or self.view
        ser = e.series(self.view_factor(e, v) if factor is None else factor)
        if v.relative:
            f_lin = e.linear_frequency(self.shared.linear_freqs)
            if f_lin:
                ser = ser.relative(f_lin)
        return ser

    @property
    def ylabel(self):
        return Y_LABELS[bool(self.view.relative)]

    def _series(self, v=None):
        """(entries, their FEP series at view ``v``'s k3, on its frequency axis)."""
        v = v or self.view
        entries = self.shared.snapshot()
        return entries, [self.fep_series(e, v=v) for e in entries]

    def zoomed(self, entries, series, v=None):
        """Whether the FEP is zoomed on the selected branch: the user's choice once made, else by
        default when the selected branch spans a small part of the frequency range (fep.should_zoom)."""
        v = v or self.view
        if not v.zoom_auto:
            return v.zoom
        sel = next((k for k, e in enumerate(entries) if e.uid == v.sel_uid), None)
        return should_zoom(series, sel)

    def _view_ranges(self, entries, series, v=None):
        """FEP axis ranges: all branches, or the selected one when zoomed."""
        v = v or self.view
        if self.zoomed(entries, series, v):
            sel = [s for e, s in zip(entries, series) if e.uid == v.sel_uid and len(s)]
            if sel:
                return axis_ranges(sel)
        return axis_ranges(series)
