"""State shared by all browser tabs: the model, its branches, the running job.

Each tab (a ``Session``) has its own selection and view settings; the branches and the
background computation are shared, so points computed from one tab appear in all.
Everything here is plain Python, usable and testable without a browser.
"""
from __future__ import annotations

import itertools
import re
import threading
from dataclasses import dataclass, field

import numpy as np

import nnm_solver
from nnm_solver import cubic_scaling

from .fep import FepSeries, event_kind

_uids = itertools.count(1)


@dataclass
class BranchEntry:
    """A branch known to the viewer.

    branch : nnm_solver Branch (for a running job: the latest snapshot).
    k3_factor : the branch's k3 relative to the file's model (1 for branches in the file).
    source : "file", "running", "stopped", "computed", "failed" or "saved" (saved from this
    session).  saved : stored in the file.
    """

    branch: object
    label: str
    k3_factor: float = 1.0
    source: str = "file"
    saved: bool = True
    status: str = ""
    uid: int = field(default_factory=lambda: next(_uids))

    def __len__(self):
        return 0 if self.branch is None else len(self.branch)

    @property
    def mode(self):
        return getattr(self.branch, "mode", None)

    def linear_frequency(self, fallback=None):
        """Linear frequency (Hz) of the branch's mode in the branch's own model (a sweep variant's, a
        scaled model's), cached; ``fallback`` (the file model's linear frequencies) if it has none."""
        model = getattr(self.branch, "model", None)
        cache = self.__dict__.setdefault("_flin", {})
        key = id(model)
        if key not in cache:
            f = None
            try:
                if model is not None:
                    f = float(model.linear_modes()[0][int(self.mode) - 1])
            except Exception:
                f = None
            if f is None and fallback is not None and self.mode is not None and 1 <= int(self.mode) <= len(fallback):
                f = float(fallback[int(self.mode) - 1])
            cache.clear()
            cache[key] = f
        return cache[key]

    @property
    def scalable(self):
        """Whether the exact k3 scaling law applies to this branch (its model's elements are all pure
        cubic springs, or it has none)."""
        return scaling_law_holds(getattr(self.branch, "model", None))

    def series(self, factor=1.0, label=None):
        """FEP arrays when every k3 is ``factor`` x the file's: exact scaling law
        (frequency unchanged, energy / ratio), ratio = factor / k3_factor.  A branch whose elements
        are not all cubic is only shown at its own factor (ValueError otherwise: no law holds)."""
        b = self.branch
        if b is None or len(b) == 0:
            z = np.zeros(0)
            return FepSeries(z, z, np.zeros(0, bool), label or legend_label(self.label))
        ratio = factor / self.k3_factor
        if abs(ratio - 1.0) > 1e-12 and not self.scalable:
            raise ValueError("the scaling law holds for cubic springs only: this branch is shown as computed")
        law = cubic_scaling(ratio)
        events = [(event_kind(e), float(e["energy"]) * law.energy, float(e["frequency_hz"]))
                  for e in (getattr(b, "events", None) or []) if "energy" in e and "frequency_hz" in e]
        label = label or legend_label(self.label)
        floquet = getattr(b, "floquet", None)
        if floquet is not None and np.size(floquet) and np.all(np.isnan(np.asarray(floquet))):
            label += " (stability not computed)"          # its points are drawn filled, not known to be stable
        return FepSeries(np.asarray(b.energy, dtype=float) * law.energy, np.asarray(b.frequency_hz, dtype=float),
                         np.asarray(b.stable, dtype=bool), label, events=events,
                         status=str(getattr(b, "status", "") or ""))


#: linear modes shown for a model too large for the dense eigensolution (nnm_solver.model.MAX_DENSE_DOF)
LARGE_MODEL_MODES = 48


def view_linear_modes(model):
    """(freqs Hz, shapes (n, k)): every linear mode of the model (``Model.linear_modes``), or for a model above
    nnm_solver.model.MAX_DENSE_DOF DOFs (a full FE model) its lowest LARGE_MODEL_MODES by sparse Lanczos
    (``nnm_solver.model.sparse_modes``): the Modes tab and the Compute tab's mode list then stop there."""
    from nnm_solver.model import MAX_DENSE_DOF, sparse_modes
    if model.n > MAX_DENSE_DOF:
        return sparse_modes(model, LARGE_MODEL_MODES)
    return model.linear_modes()


def scaling_law_holds(model):
    """True when the exact k3 scaling law (nnm_solver.cubic_scaling) applies to ``model``: every
    nonlinear element is a pure cubic spring (or there is none).  Otherwise a stiffness factor must
    be computed (Model.scaled, a job), never scaled."""
    if model is None:
        return True
    el = model.elements
    return len(el) == 0 or bool(el.cubic_only)


def mode_name(model, mode):
    """The model's label of linear mode ``mode`` (1-based), or ''."""
    labels = getattr(model, "mode_labels", None) or []
    try:
        k = int(mode)
    except (TypeError, ValueError):
        return ""
    return str(labels[k - 1]).strip() if 1 <= k <= len(labels) else ""


def name_remainder(name, mode):
    """What a branch's stored ``name`` adds to 'NNM <mode>': '' for 'NNM1', 'mode 14', a sweep's
    'variant <variant>' for a sweep's '<variant>:mode<N>'; 'paper mode 13' for
    'mode14 (paper mode 13)'; 'harmonic balance H15' for 'NNM1 harmonic balance H15'; 'run 2' for
    'mode1_2' (save_branch's name of a second branch of mode 1 in the same file)."""
    from nnm_solver.sweeps import parse_branch_name

    name = str(name or "").strip()
    swept = parse_branch_name(name)
    if swept is not None:
        return f"variant {swept[0]}"
    if not name:
        return ""
    m = re.match(rf"^\s*(?:nnm|mode)\s*{re.escape(str(mode))}(?![0-9])\s*(.*)$", name, flags=re.IGNORECASE)
    rest = m.group(1) if m else name
    run = re.match(r"^_(\d+)\b\s*(.*)$", rest) if m else None
    if run:                                       # 'mode1_2': the second branch of mode 1 saved to the file
        rest = f"run {run.group(1)}" + (f" {run.group(2)}" if run.group(2) else "")
    rest = rest.strip().strip(":,-;").strip()
    if rest.startswith("("):                      # '(paper mode 13): tongue 1 (5:1)' -> 'paper mode 13: ...'
        depth = 0
        for k, ch in enumerate(rest):
            depth += {"(": 1, ")": -1}.get(ch, 0)
            if depth == 0:
                rest = (rest[1:k] + rest[k + 1:]).strip()
                break
    return rest


def legend_label(label, width=42):
    """A branch label for the FEP legends: without the mode's label ('NNM 14 (fin bending 1) · paper
    mode 13' -> 'NNM 14 · paper mode 13'; the lists and the readout give it), at most ``width``
    characters."""
    text = str(label)
    m = re.match(r"^(NNM \S+) \(", text)
    if m:
        depth, start = 0, m.end() - 1
        for k in range(start, len(text)):
            depth += {"(": 1, ")": -1}.get(text[k], 0)
            if depth == 0:
                text = m.group(1) + text[k + 1:]
                break
    return text if len(text) <= width else text[:width - 1].rstrip() + "\u2026"


def branch_label(branch, k3_factor=1.0, source="file", model=None):
    """The branch's name in every list and legend: 'NNM <k> (<the model's label of mode k>)', then
    what its stored name adds (' · harmonic balance H15'), the k3 factor if not 1 and, for a branch
    of this session, its state: 'NNM 2 (out-of-phase mode) (k3 x 10) [running]'.  ``model``: whose
    mode labels to use when the branch carries no model of its own."""
    mode = getattr(branch, "mode", "?")
    label = mode_name(getattr(branch, "model", None) or model, mode) or mode_name(model, mode)
    text = f"NNM {mode}" + (f" ({label})" if label else "")
    extra = name_remainder(getattr(branch, "name", ""), mode)
    if extra:
        text += f" \u00b7 {extra}"
    if abs(k3_factor - 1.0) > 1e-12:
        text += f" (k3 x {k3_factor:.3g})"
    if source in ("running", "stopped", "failed"):
        text += f" [{source}]"
    elif source == "computed":
        text += " [new]"
    elif source == "saved":
        text += " [saved]"
    return text


class SharedState:
    """Model, branch entries and jobs shared by all sessions (thread-safe).

    ``mesh`` is the model's display mesh (boxes per DOF if it has none), ``mapper`` its
    displacement map ready for fast products.  Listeners (callables taking a kind string:
    "branches", "progress", "error", "solver") are called after every change, outside the lock.
    """

    def __init__(self, model, path=None, branches=(), solver_ready=True):
        self.model = model
        self.path = path
        self.lock = threading.RLock()
        #: set once the solver's compiled kernels are ready (app.py warms them in the background);
        #: until then the sessions draw everything but the orbits
        self.solver_ready = threading.Event()
        #: the kernels that integrate the file's orbits are compiled (warm-up's first step): orbits can be shown
        self.orbits_ready = threading.Event()
        if solver_ready:
            self.solver_ready.set()
            self.orbits_ready.set()
        self.entries: list[BranchEntry] = []
        self.listeners: list = []
        self.job = None                 # worker.JobRunner or None
        self.progress = 0.0
        self.status = ""
        self.error = ""
        from .animation import MeshMapper
        from .scene import fallback_mesh
        self.mesh = model.mesh if model.mesh is not None else fallback_mesh(model.n)
        self.mapper = MeshMapper(self.mesh)
        freqs, shapes = view_linear_modes(model)
        self.linear_freqs = np.asarray(freqs)
        self.linear_shapes = shapes
        for b in branches:
            self.add(b, source="file", saved=True, notify=False)

    # ------------------------------------------------------------------ entries
    def add(self, branch, k3_factor=1.0, source="file", saved=True, notify=True):
        entry = BranchEntry(branch=branch, label=branch_label(branch, k3_factor, source, self.model),
                            k3_factor=k3_factor, source=source, saved=saved)
        with self.lock:
            self.entries.append(entry)
        if notify:
            self.notify("branches")
        return entry

    def remove(self, entry, notify=True):
        """Drop ``entry`` from the list (a superseded recompute of the stiffness slider)."""
        with self.lock:
            self.entries = [e for e in self.entries if e is not entry]
        if notify:
            self.notify("branches")

    def update(self, entry, branch=None, source=None, status=None, notify=True):
        with self.lock:
            if branch is not None:
                entry.branch = branch
            if source is not None:
                entry.source = source
            if status is not None:
                entry.status = status
            entry.label = branch_label(entry.branch, entry.k3_factor, entry.source, self.model)
        if notify:
            self.notify("branches")

    def snapshot(self):
        with self.lock:
            return list(self.entries)

    def index_of(self, uid):
        with self.lock:
            for i, e in enumerate(self.entries):
                if e.uid == uid:
                    return i
        return None

    # ------------------------------------------------------------------ events
    def subscribe(self, fn):
        with self.lock:
            self.listeners.append(fn)

    def unsubscribe(self, fn):
        with self.lock:
            if fn in self.listeners:
                self.listeners.remove(fn)

    def notify(self, kind):
        with self.lock:
            listeners = list(self.listeners)
        for fn in listeners:
            try:
                fn(kind)
            except Exception:  # a broken tab must not break the others
                pass

    def set_error(self, message):
        with self.lock:
            self.error = message
        self.notify("error")

    def set_orbits_ready(self):
        """The kernels integrating the stored branches' orbits are compiled: the sessions show their orbits now
        (the continuation's kernels may still be compiling)."""
        self.orbits_ready.set()
        self.notify("solver")

    def set_solver_ready(self):
        """The solver's kernels are compiled: the sessions compute their orbits now."""
        self.orbits_ready.set()
        self.solver_ready.set()
        self.notify("solver")

    def set_progress(self, value, status=None):
        with self.lock:
            self.progress = float(value)
            if status is not None:
                self.status = status
        self.notify("progress")

    # ------------------------------------------------------------------ saving
    def save(self, entry):
        """Append ``entry``'s branch to the model file (atomic write by the solver); returns
        (the file written, why it is not the opened file or '').

        A shipped example or a file that cannot be written is left alone: the branch goes to
        ``<stem>_branches.h5`` in the current folder (examples.branch_output).  A branch computed
        with scaled springs is mapped back to the file's springs with the exact scaling law before
        saving, so the file stays consistent.
        """
        from .examples import branch_output

        if self.path is None:
            raise nnm_solver.NNMInputError("this viewer has no file to save into")
        if entry.branch is None or len(entry.branch) == 0:
            raise nnm_solver.NNMInputError("the branch has no points yet; nothing to save")
        branch = entry.branch
        if abs(entry.k3_factor - 1.0) > 1e-12:
            if not entry.scalable:
                raise nnm_solver.NNMInputError(
                    f"this branch was computed with every spring force x {entry.k3_factor:.3g}; the scaling law "
                    "that maps it back to the file's springs holds for cubic springs only, so it cannot be saved "
                    "into this file (download its FEP as CSV instead)")
            branch = branch.scaled(1.0 / entry.k3_factor)
        target, reason = branch_output(self.path)
        nnm_solver.save_branch(target, branch)
        with self.lock:
            entry.saved = True
        self.update(entry, source="saved")
        return target, reason
