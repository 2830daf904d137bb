"""The FEP's colours and markers: stable / unstable points, the branches' colours (kept clear of the
off-backbone orange and the event markers' colours), the events' and the branch ends' markers."""
from __future__ import annotations

import colorsys

STABLE_RGB = (40, 100, 220)
UNSTABLE_RGB = (225, 70, 40)
MARKER_RGB = (255, 200, 0)
#: colours of the first branches (no red: failures, branch points; no orange: the points off the backbone,
#: OFF_BACKBONE_COLOR; no yellow: the picked orbit; no grey: the file's branches behind a scaled FEP); the next
#: ones get golden-angle hues outside that red-orange-yellow band (branch_color), never a repeat
BRANCH_COLORS = ["#1f77b4", "#2ca02c", "#9467bd", "#393b79", "#17becf", "#8c564b", "#e377c2", "#bcbd22"]
#: the hues (0..1) the golden-angle colours keep to: red (0), orange (0.08) and yellow (0.14) mean something else
BRANCH_HUES = (0.22, 0.92)
#: how much of white an unstable point's colour is mixed with on the 3D board
UNSTABLE_PALE = 0.6
#: events (Branch.events) by kind: legend text
EVENT_LABELS = {"fold": "fold (energy turns back)", "branch_point": "branch point (multiplier +1)",
                "period_doubling": "period doubling (multiplier -1)", "torus": "torus (complex multipliers)"}
#: how a branch ended (Branch.status), marked at its last point: (marker, colour, legend text)
END_MARKERS = {"failed": ("X", "#d62728", "end: solver failed"), "escape": ("X", "#e7298a", "end: escape"),
               "closed_loop": ("P", "#9467bd", "end: closed loop"), "tongue": ("X", "#8c564b", "end: inside a tongue")}


def branch_color(k):
    """Colour (hex) of the branch at position k (0-based) of the list: BRANCH_COLORS, then hues
    spaced by the golden angle within BRANCH_HUES (distinct for every k; never the orange of the points off the
    backbone, the red of failures or the yellow of the picked orbit)."""
    if k < len(BRANCH_COLORS):
        return BRANCH_COLORS[k]
    j = k - len(BRANCH_COLORS)
    lo, hi = BRANCH_HUES
    h = lo + (hi - lo) * ((0.05 + 0.6180339887498949 * j) % 1.0)
    sat, val = ((0.8, 0.7), (0.55, 0.85), (0.9, 0.5))[j % 3]
    return "#{:02x}{:02x}{:02x}".format(*(int(round(255 * c)) for c in colorsys.hsv_to_rgb(h, sat, val)))


def rgb(color):
    """(r, g, b) 0..255 of a '#rrggbb' colour."""
    return tuple(int(color[i:i + 2], 16) for i in (1, 3, 5))


def pale(color, amount=UNSTABLE_PALE):
    """'#rrggbb' mixed with white (amount 0: unchanged, 1: white)."""
    return "#{:02x}{:02x}{:02x}".format(*(int(round(c + amount * (255 - c))) for c in rgb(color)))


def event_kind(event):
    """Kind of an event dict: 'fold', 'branch_point', 'period_doubling', 'torus' (older files say
    'bifurcation' and name the critical multiplier in the detail)."""
    kind = str(event.get("kind", ""))
    if kind == "bifurcation":
        detail = str(event.get("detail", ""))
        return "period_doubling" if "through -1" in detail else "torus" if "complex" in detail else "branch_point"
    return kind


def event_style(kind):
    """(matplotlib marker, colour) of an event kind, as in the solver's FEP plots."""
    try:
        from nnm_solver.results import EVENT_MARKERS
    except ImportError:  # pragma: no cover
        EVENT_MARKERS = {}
    return EVENT_MARKERS.get(kind, ("o", "k"))


def off_backbone_style():
    """(markers, colour) of the points off the backbone, as in the solver's plots (results/plotting.py)."""
    from nnm_solver.results.plotting import OFF_BACKBONE_COLOR, OFF_BACKBONE_MARKERS
    import matplotlib.colors as mcolors

    return OFF_BACKBONE_MARKERS, mcolors.to_hex(OFF_BACKBONE_COLOR)
