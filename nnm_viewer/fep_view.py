"""Draw steps of a tab's selection: the branch list, the clickable FEP in the scene, the FEP image
of the panel and the selection sliders (state read from the ``Session``)."""
from __future__ import annotations

import numpy as np

from nnm_solver.sweeps import parse_branch_name

from . import scene as sc
from .fep import Y_LABELS, FepRenderer, branch_color, energy_at, interp_at
from .info import linear_mode_title
from .numbering import point_number, point_words, slider_value

#: size (px) of the FEP image of the panel (the plot, and its legend below)
PANEL_FEP_SIZE = (480, 470)
from .worker import one_line


#: how a branch ended (Branch.status, nnm_solver/stops.py), as said in the branch dropdown
STATUS_WORDS = {"failed": "failed", "escape": "escape", "closed_loop": "closed loop", "max_points": "max points",
                "tongue": "ends in a tongue", "cancelled": "stopped", "stopped": "stopped"}
#: ... and in the branch information under the selection
STATUS_TEXT = {"done": "done", "max_points": "stopped at max_points", "escape": "escape: the NNM family ends",
               "closed_loop": "closed loop", "tongue": "the backbone ends inside an internal-resonance tongue",
               "failed": "**failed**", "cancelled": "stopped by the user",
               "stopped": "stopped", "running": "running"}
#: events by kind, in words (singular)
EVENT_NAMES = {"fold": "fold", "branch_point": "branch point", "period_doubling": "period doubling",
               "torus": "torus bifurcation"}
#: event indices listed per kind at most
EVENTS_LISTED = 6


def branch_status(e):
    """Branch.status of an entry ('' if unknown)."""
    return str(getattr(e.branch, "status", "") or "")


def entry_option(i, e, label=None):
    """Label of branch entry ``e`` (position ``i``) in the branch dropdown, with how it ended unless
    it reached its end normally or is still running (``label``: instead of ``e.label``)."""
    label = e.label if label is None else label
    word = STATUS_WORDS.get(branch_status(e), "")
    tag = f", {word}" if word and f"[{word}]" not in label else ""
    return f"{i + 1}: {label} ({len(e)} pts{tag})"


def sweep_key(e):
    """(variant, mode) of an entry whose branch is named ``<variant>:mode<N>`` (a sweep's, see
    nnm_solver.sweeps.parse_branch_name), or None."""
    return parse_branch_name(str(getattr(e.branch, "name", "") or ""))


def branch_options(entries):
    """[(position in ``entries``, dropdown option)] in the order of the branch list: the branches
    that are not a sweep's as they come, then the sweep branches grouped by variant (ordered by
    variant, then mode), each option prefixed with its variant: 'stiff › 3: NNM 5 (40 pts)'.
    The number is the branch's position (its colour), as in the FEP legend."""
    plain, swept = [], []
    for i, e in enumerate(entries):
        key = sweep_key(e)
        if key is None:
            plain.append((i, entry_option(i, e)))
        else:
            variant, mode = key
            label = e.label.replace(f" \u00b7 variant {variant}", "", 1)     # the variant leads the option
            swept.append(((variant, mode, i), (i, f"{variant} \u203a {entry_option(i, e, label)}")))
    return plain + [opt for _, opt in sorted(swept, key=lambda t: t[0])]


def sweep_markdown(e):
    """'**Sweep:** variant ..., mode N' for a sweep's branch, else ''."""
    key = sweep_key(e)
    return "" if key is None else f"**Sweep:** variant {key[0]}, mode {key[1]}  \n"


def branch_markdown(e):
    """How the branch of entry ``e`` ended (status and the solver's message) and its events by kind
    with the points next to them (markdown; the points numbered from 1, as everywhere users see them: an
    event located between rows i and i+1 is 'near point i+1')."""
    from .fep import EVENT_LABELS, event_kind

    st = branch_status(e)
    msg = str(getattr(e.branch, "message", "") or "").strip()
    text = f"**Branch:** {STATUS_TEXT.get(st, st or 'unknown status')}" + (f" — {msg}" if msg else "")
    by_kind = {}
    for ev in getattr(e.branch, "events", None) or []:
        by_kind.setdefault(event_kind(ev), []).append(int(ev.get("index", -1)))
    if not by_kind:
        return text + "  \n**Events:** none (no fold, no stability change)" if len(e) > 2 else text
    parts = []
    for kind in list(EVENT_LABELS) + sorted(k for k in by_kind if k not in EVENT_LABELS):
        idx = by_kind.get(kind)
        if idx:
            shown = ", ".join(point_number(i) for i in idx[:EVENTS_LISTED]) + (", …" if len(idx) > EVENTS_LISTED else "")
            name = EVENT_NAMES.get(kind, kind.replace("_", " "))
            parts.append(f"{len(idx)} {name}{'s' if len(idx) > 1 else ''} (near point{'s' if len(idx) > 1 else ''} "
                         f"{shown})")
    return text + "  \n**Events:** " + "; ".join(parts) + " — marked on the FEP"


def point_facts(e, along):
    """Words about point ``along`` (fractional index; the nearest computed point) of entry ``e``:
    [stability, label ('backbone', 'tongue 3:1'; if the branch has labels), estimated frequency
    error (if the branch has ``freq_error``: the solver's per-point relative error estimate)]."""
    from .point_view import point_label_and_error

    b = e.branch
    i = int(np.clip(round(float(along)), 0, len(b) - 1))
    facts = ["stable" if bool(np.asarray(b.stable)[i]) else "unstable"]
    label, err = point_label_and_error(b, along)
    if label:
        facts.append(label)
    if err is not None:
        facts.append(f"estimated frequency error {err:.1e} (relative)" if np.isfinite(err) else
                     "frequency not resolved by the harmonics (no orbit with two more near it)")
    return facts


def readout_markdown(s, e, v=None):
    """The picked point's readout under the panel FEP (session ``s``, its view ``v``): branch, point (1-based),
    energy, frequency (and relative to the branch's linear frequency), stability, label and accuracy
    estimate."""
    v = v or s.view
    ser = e.series(s.view_factor(e, v))
    n = len(ser)
    along = float(np.clip(v.s, 0, n - 1))
    energy = energy_at(ser.energy, along)
    f = interp_at(ser.frequency, along)
    f_lin = e.linear_frequency(s.shared.linear_freqs)
    rel = f" ({100 * (f / f_lin - 1):+.3g} % from its linear {f_lin:.5g} Hz)" if f_lin else ""
    idx = s.shared.index_of(e.uid)
    return (f"**Picked:** branch {(idx or 0) + 1}, {e.label}, {point_words(along, n)}  \n"
            f"E = {energy:.4g} J, f = {f:.6g} Hz{rel}  \n" + " · ".join(point_facts(e, along)))


class FepView:
    """The FEP of one tab: dropdown, board of clickable spheres, panel image, sliders."""

    def __init__(self, session):
        self.session = session
        self.ui = session.layout
        self.board_handles = {}      # uid -> batched-sphere handle (None: hidden)
        self.board_points = {}       # uid -> world positions (N, 3) of its spheres on the board
        self.board_group = None      # scene name of the spheres' group (scene.sphere_group)
        self.ranges = None           # axis ranges of the board
        self.renderer = FepRenderer(size=PANEL_FEP_SIZE)

    def check_selection(self):
        """Select the first branch if the selection vanished.  Returns True if the point shown
        must be (re)computed: it is missing or of another branch (a new branch selected, a
        streaming branch that got its first points)."""
        s = self.session
        entries = s.shared.snapshot()
        if not entries:
            return False
        first = next((e for e in entries if len(e)), entries[0])
        live = {e.uid for e in entries}
        v, old = s.change_view(lambda w: {} if w.sel_uid in live else dict(sel_uid=first.uid, s=0.0))
        vanished = old.sel_uid not in live
        e = s.selected_entry(v)
        if e is None:                     # removed meanwhile: the next 'branches' request selects again
            return False
        return vanished or (bool(len(e)) and v.linear_mode is None
                            and (v.current_point is None or v.current_uid != e.uid))

    def draw_branch_list(self):
        """The branch dropdown, showing the selected branch."""
        s, ui = self.session, self.ui
        entries = s.shared.snapshot()
        if not entries:
            ui.set(ui.h_branch, options=("(none)",), value="(none)")
            ui.set(ui.h_branch_info, content="")
            return
        listed = branch_options(entries)
        options = tuple(opt for _, opt in listed)
        sel_uid = s.view.sel_uid
        sel = next((i for i, e in enumerate(entries) if e.uid == sel_uid), 0)
        ui.set(ui.h_branch, options=options)
        ui.set(ui.h_branch, value=dict(listed)[sel])
        ui.set(ui.h_branch_info, content=sweep_markdown(entries[sel]) + branch_markdown(entries[sel]))

    def draw_board(self):
        s = self.session
        v = s.view
        entries, series = s._series(v)
        ranges = s._view_ranges(entries, series, v)
        self.ranges = ranges
        board = s.geom.board
        if not v.show_board:
            self.ui.set(self.ui.h_zoom, value=bool(s.zoomed(entries, series, v)))
            s.scene.remove_by_name("/fep")
            self.board_handles, self.board_points, self.board_group = {}, {}, None
            return
        group, old_group = sc.sphere_group(v.canvas), self.board_group
        if group != old_group:                        # a new canvas size: every sphere is added anew
            self.board_handles, self.board_group = {}, group
        zoomed = s.zoomed(entries, series, v)
        self.ui.set(self.ui.h_zoom, value=bool(zoomed))
        sc.draw_board_frame(s.scene, board, ranges, series, ylabel=Y_LABELS[bool(v.relative)])
        live = set()
        for k, (e, ser) in enumerate(zip(entries, series)):
            uid = e.uid
            if zoomed and uid != v.sel_uid:            # zoomed: only the selected branch
                ser = ser.__class__(ser.energy[:0], ser.frequency[:0], ser.stable[:0], ser.label)
            live.add(uid)
            self.board_points[uid] = board.to_world(ser.energy, ser.frequency, ranges) if len(ser) else None
            self.board_handles[uid] = sc.draw_board_points(s.scene, board, ranges, ser, uid,
                                                           on_click=self._click_handler(uid), name=group,
                                                           emphasized=(uid == v.sel_uid), color=branch_color(k))
        for uid in list(self.board_handles):
            if uid not in live:
                s.scene.remove_by_name(f"{group}/b{uid}")
                del self.board_handles[uid]
                self.board_points.pop(uid, None)
        if old_group is not None and old_group != group:
            s.scene.remove_by_name(old_group)

    def nearest_point(self, origin, direction):
        """(uid, index) of the board point seen nearest to the ray (origin, direction) of a click,
        i.e. nearest on the screen (smallest angle from the ray), or None."""
        o = np.asarray(origin, dtype=float)
        d = np.asarray(direction, dtype=float)
        d = d / max(np.linalg.norm(d), 1e-300)
        best, best_angle = None, np.inf
        for uid, pos in list(self.board_points.items()):
            if pos is None or not len(pos):
                continue
            v = pos - o
            along = v @ d
            perp = np.linalg.norm(v - along[:, None] * d, axis=1)
            angle = np.where(along > 0, np.arctan2(perp, along), np.inf)
            i = int(np.argmin(angle))
            if angle[i] < best_angle:
                best, best_angle = (uid, i), float(angle[i])
        return best

    def _click_handler(self, uid):
        """A click on a sphere of branch ``uid``: the point whose centre is nearest to the click on
        the screen is picked (overlapping spheres: not necessarily the one the ray hit first)."""
        def on_click(event):
            try:
                hit = None
                if getattr(event, "ray_origin", None) is not None and getattr(event, "ray_direction", None) is not None:
                    hit = self.nearest_point(event.ray_origin, event.ray_direction)
                self.session.pick(*(hit or (uid, event.instance_index)))
            except Exception as exc:
                self.session.show_error(one_line(exc))
        return on_click

    def draw_series(self):
        """The branches of the panel image (redrawn when branches or the k3 factor change)."""
        s = self.session
        v = s.view
        entries, series = s._series(v)
        # the branches as computed, in grey, behind their scaled FEP (scaling law only)
        ghost = ([s.fep_series(e, e.k3_factor, v) for e in entries if e.scalable]
                 if s.scaling_law and abs(v.factor_log) > 1e-9 else [])
        zoomed = s.zoomed(entries, series, v)
        title = ("Frequency-energy plot" + (f" (k3 x {v.factor:.3g})" if s.scaling_law else "")
                 + (", zoomed on the selected branch" if zoomed else ""))
        sel = next((i for i, e in enumerate(entries) if e.uid == v.sel_uid), None)
        self.renderer.set_series(series, sel, ghosts=ghost, title=title,
                                 ranges=s._view_ranges(entries, series, v) if zoomed else None,
                                 ylabel=Y_LABELS[bool(v.relative)],
                                 measured=self.measured_points(entries[sel], v) if sel is not None else None)

    def measured_points(self, e, v):
        """(energy J, frequency on the view's axis, label) of the measured backbone placed on entry ``e``'s
        branch at the view's k3 factor (nnm_viewer/measured.py), or None."""
        from .measured import on_fep

        s = self.session
        m = s.shared.measured
        if m is None or not len(e):
            return None
        pts = on_fep(m, e.branch, e.series(s.view_factor(e, v)).energy, e.branch.energy)
        if pts is None:
            return None
        f = pts[1]
        if v.relative:
            f_lin = e.linear_frequency(s.shared.linear_freqs)
            f = 100.0 * (f / f_lin - 1.0) if f_lin else f
        return pts[0], f, m.label

    def selected_point(self, v=None):
        """(energy J, frequency on the FEP's axis: Hz or %) of the selection of view ``v`` at its k3 factor,
        or None (the energy of the orbit shown, fep.energy_at: linear in energy, as Branch.interpolate)."""
        s = self.session
        v = v or s.view
        e = s.selected_entry(v)
        if e is None or not len(e):
            return None
        ser = s.fep_series(e, v=v)
        return energy_at(ser.energy, v.s), interp_at(ser.frequency, v.s)

    def draw_image(self):
        """The panel image with the selection marker, and the marker on the board."""
        s, ui = self.session, self.ui
        v = s.view
        sel = self.selected_point(v)
        ui.h_fep.image = self.renderer.image(sel)
        self.draw_readout(v)
        board = s.geom.board
        if v.show_board and self.ranges is not None and sel is not None:
            pos = board.to_world([sel[0]], [sel[1]], self.ranges)[0]
            sc.draw_marker(s.scene, pos + 0.5 * board.point_radius() * board.normal, 1.6 * board.point_radius())
        elif sel is None:
            s.scene.remove_by_name("/fep/marker")

    def draw_readout(self, v=None):
        """The picked point's readout under the panel image; while a linear mode is animated instead
        (Modes tab) it says so first, so that it never names as shown a point that is not."""
        s, ui = self.session, self.ui
        v = v or s.view
        e = s.selected_entry(v)
        text = readout_markdown(s, e, v) if e is not None and len(e) else "no point picked"
        k = v.linear_mode
        if k is not None:
            text = (f"**Shown:** {linear_mode_title(s.model, s.shared.linear_freqs, k)} (Modes tab); pick a "
                    "point or move a slider to animate the picked point again  \n" + text)
        ui.set(ui.h_readout, content=text)

    def draw_sliders(self, skip=None):
        """Energy and along-branch sliders (``skip``: the one being dragged), selection text.  The
        Along-branch slider gives the point's number, 1 .. n, as the texts do."""
        s, ui = self.session, self.ui
        v = s.view
        e = s.selected_entry(v)
        if e is None or not len(e):
            ui.set(ui.h_energy, disabled=True)
            ui.set(ui.h_along, disabled=True)
            ui.set(ui.h_sel, content="no point selected: compute a branch in the Compute tab")
            return
        ser = e.series(s.view_factor(e, v))
        n = len(ser)
        uid = e.uid
        v, _ = s.change_view(lambda w: dict(s=float(np.clip(w.s, 0, n - 1))) if w.sel_uid == uid else {})
        along = float(np.clip(v.s, 0, n - 1))
        le = np.log10(ser.energy)
        lo, hi = float(np.floor(le.min() * 100) / 100), float(np.ceil(le.max() * 100) / 100)
        if hi - lo < 0.02:
            lo, hi = lo - 0.01, hi + 0.01
        energy = energy_at(ser.energy, along)
        cur_le = float(np.log10(energy))
        if skip != "energy":
            ui.set(ui.h_energy, min=lo, max=hi, disabled=False)
            ui.set(ui.h_energy, value=float(np.clip(round(cur_le, 2), lo, hi)))
        if skip != "along":
            ui.set(ui.h_along, min=1.0, max=float(max(n, 1.01)), disabled=n < 2)
            ui.set(ui.h_along, value=float(round(slider_value(along), 2)))
        f = interp_at(ser.frequency, along)
        st = ", ".join(point_facts(e, along)[:2])
        entries = s.shared.snapshot()
        idx = next((i for i, x in enumerate(entries) if x.uid == uid), None)
        if idx is None:                   # removed meanwhile: the next draw shows the new selection
            return
        option = dict(branch_options(entries)).get(idx)
        if option is not None and option in ui.h_branch.options:
            ui.set(ui.h_branch, value=option)
        ui.set(ui.h_sel, content=f"**Selected:** branch {idx + 1}, {point_words(along, n)}  \n"
                                 f"E = {energy:.4g} J, f = {f:.5g} Hz, {st}")
        ui.set(ui.h_recompute, disabled=abs(v.factor / e.k3_factor - 1.0) < 1e-9)
        ui.set(ui.h_save, disabled=e.saved or e.source == "running")
