"""The words of a tab's FEP selection: branch statuses and list entries, the branch's and the sweep's facts, the
picked point's readout (markdown, 1-based point numbers)."""
from __future__ import annotations

import numpy as np

from nnm_solver.sweeps import parse_branch_name

from .fep import energy_at, interp_at
from .numbering import nearest_row, point_number, point_words


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


#: what the texts say of a point whose Floquet multipliers were not computed (floquet off: ``stable`` is True for
#: want of a test, not a finding; Branch.stability_known)
STABILITY_UNKNOWN = "stability not computed"


def stability_known(branch, i):
    """Whether the stability of row ``i`` of ``branch`` was computed (``Branch.stability_known``; True for a
    branch object without it)."""
    known = getattr(branch, "stability_known", None)
    if known is None:
        return True
    known = np.asarray(known, dtype=bool).reshape(-1)
    return bool(known[i]) if i < len(known) else True


def stability_word(branch, i):
    """'stable', 'unstable' or STABILITY_UNKNOWN for row ``i`` of ``branch``."""
    if not stability_known(branch, i):
        return STABILITY_UNKNOWN
    return "stable" if bool(np.asarray(branch.stable)[i]) else "unstable"


def point_facts(e, along):
    """Words about point ``along`` (fractional index; the nearest computed point, ``numbering.nearest_row``) of
    entry ``e``: [stability ('stable', 'unstable', or 'stability not computed' when its multipliers were not),
    label ('backbone', 'tongue 3:1'; if the branch has labels), estimated frequency error (if the branch has ``freq_error``: the solver's per-point relative error estimate)]."""
    from .point_view import point_label_and_error

    b = e.branch
    i = nearest_row(along, len(b))           # Branch.interpolate's nearer neighbour, as the Point tab's
    facts = [stability_word(b, i)]
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
