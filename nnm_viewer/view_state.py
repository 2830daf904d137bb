"""The view state of one tab as one immutable record (issue 53, finding 10).

A tab's callbacks (viser's threads), its draw thread and the job threads all read and change it; each
change builds a new ``ViewState`` and swaps it in under the tab's lock (``ViewHolder.set_view`` /
``change_view``), so a reader takes ``session.view`` once and sees one consistent state (the selection
with its point, the point shown with its branch), never half of a change.
"""
from __future__ import annotations

from dataclasses import dataclass, fields, replace

__all__ = ["ViewState", "ViewHolder"]


@dataclass(frozen=True)
class ViewState:
    """What one tab shows.

    sel_uid : uid of the selected BranchEntry (None: none).  s : fractional 0-based index along it (the
    texts and the Along-branch slider show s + 1).  factor_log : log10 of the k3 factor on the file's
    springs.  playing, phase (fraction of a period, paused), auto_amp, amp_log (log10 of the manual
    amplification), speed (displayed cycles per second): the animation.  show_board, zoom, zoom_auto (zoom
    chosen by fep.should_zoom until the user ticks the box), relative (frequency axis in % of the linear
    frequency): the FEP.  dofs_text : the Point tab's DOFs.  show_ghost : the undeformed shape.
    camera_preset : the last view preset.  canvas : (width, height) px of the tab's 3D canvas, as its last
    camera message said (None before one; the board's spheres are drawn again when it changes).  linear_mode : k (1-based) when linear mode k is shown instead of
    the selected point.  message : the tab's last status line.  current_point, current_anim, current_uid,
    ratio, current_of : the point shown (PointData scaled to the view's k3, its OrbitAnimation, its branch's uid, the
    view's k3 factor over the branch's, and which orbit it is: (uid, position along the branch) or ('linear', k)),
    written by the drawing.
    """

    sel_uid: object = None
    s: float = 0.0
    factor_log: float = 0.0
    playing: bool = True
    phase: float = 0.0
    auto_amp: bool = True
    amp_log: float = 0.0
    speed: float = 0.5
    show_board: bool = True
    zoom: bool = False
    zoom_auto: bool = True
    relative: bool = False
    dofs_text: str = "auto"
    show_ghost: bool = False
    camera_preset: str = "Iso"
    canvas: object = None
    linear_mode: object = None
    message: str = ""
    current_point: object = None
    current_anim: object = None
    current_uid: object = None
    ratio: float = 1.0
    current_of: object = None

    @property
    def factor(self):
        """The k3 factor on the file's springs."""
        return float(10.0 ** self.factor_log)


VIEW_FIELDS = tuple(f.name for f in fields(ViewState))


class ViewHolder:
    """A tab's ``view`` (a ViewState) swapped under its ``lock`` (an RLock of the class using this mixin);
    each field also reads as an attribute (``session.s``) and an attribute write is a ``set_view``."""

    @property
    def view(self):
        """The current ViewState (one consistent record; take it once per step)."""
        return self.__dict__["_view"]

    def set_view(self, **changes):
        """Swap in the view with ``changes``, atomically; returns it."""
        with self.lock:
            new = replace(self.__dict__["_view"], **changes)
            self.__dict__["_view"] = new
        return new

    def change_view(self, fn):
        """Read-modify-write: ``fn(view)`` returns the changes (a dict) made from the view it is given, under
        the lock, so that no other change comes in between; returns (the new view, the old one)."""
        with self.lock:
            old = self.__dict__["_view"]
            new = replace(old, **(fn(old) or {}))
            self.__dict__["_view"] = new
        return new, old


def _field_property(name):
    def get(self):
        return getattr(self.__dict__["_view"], name)

    def put(self, value):
        self.set_view(**{name: value})
    return property(get, put, doc=f"ViewState.{name} of the current view")


for _name in VIEW_FIELDS:
    setattr(ViewHolder, _name, _field_property(_name))
