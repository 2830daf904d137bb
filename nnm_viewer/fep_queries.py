"""What a tab's frequency-energy plot shows (a mixin of ``controls.Session``): each branch's series at the k3
factor it is shown at, on the frequency axis chosen (Hz or % of the linear frequency), and the axis ranges (all
branches, or zoomed on the selected one)."""
from __future__ import annotations

from .fep import Y_LABELS, axis_ranges, should_zoom

__all__ = ["FepQueries"]


class FepQueries:
    """The FEP's series and ranges of a Session (its state: factor, scaling_law, relative, zoom, zoom_auto,
    sel_uid, shared)."""

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
