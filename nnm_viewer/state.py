"""State shared by all browser tabs: the model, its branches, the running job.

Each tab (a ``Session``) has its own selection and view settings; the branches and the
background computation are shared, so points computed from one tab appear in all.
Everything here is plain Python, usable and testable without a browser.
"""
from __future__ import annotations

import itertools
import logging
import threading
from dataclasses import dataclass, field

import numpy as np

import nnm_solver
from nnm_solver import cubic_scaling

from .branch_names import branch_label, legend_label, mode_name, name_remainder  # noqa: F401 (re-exported)
from .fep import FepSeries, event_kind

_uids = itertools.count(1)
log = logging.getLogger("nnm_viewer")


class JobBusy(ValueError):
    """Start refused: a job is already running (the viewer runs one job at a time)."""

    def __init__(self):
        super().__init__("a job is already running; stop it first")


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
                         status=str(getattr(b, "status", "") or ""),
                         labels=tuple(str(x) for x in _labels(b)))


def reference_names(path):
    """{mode: name} of the file's /extra/reference/mode_names ({} without a file or names)."""
    from nnm_solver.cli.modes import reference_mode_names
    from nnm_solver.files.importers import is_import_path

    if path is None or is_import_path(path):            # an imported model file (.mat, .toml) has no /extra
        return {}
    return reference_mode_names(nnm_solver.load_extra(path, "reference"))


def _labels(branch):
    """The branch's point labels (Branch.labels), or () when it has none."""
    labels = getattr(branch, "labels", None)
    return () if labels is None else labels


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


class SharedState:
    """Model, branch entries and jobs shared by all sessions (thread-safe).

    ``mesh`` is the model's display mesh (boxes per DOF if it has none), ``mapper`` its
    displacement map ready for fast products.  Listeners (callables taking a kind string:
    "branches", "progress", "error", "solver") are called after every change, outside the lock;
    a listener that raises is logged and the others still run.

    Locks, always taken in this order (never the reverse): a tab's draw lock (drawing.py), the tab's
    ``Session.lock``, then ``SharedState.lock``; ``SharedState.save_lock`` (a branch being written to the file) is
    taken with none of them held, before ``SharedState.lock``.  ``job`` is claimed atomically (``claim_job``): of two
    tabs pressing Start at once, one starts the job and the other is told one is running.
    """

    def __init__(self, model, path=None, branches=(), solver_ready=True, measured=None):
        self.model = model
        self.path = path
        #: a measured backbone drawn on every FEP (measured.MeasuredBackbone), or None; set here only, never
        #: changed: read without the lock
        self.measured = measured
        self.lock = threading.RLock()
        #: held while a branch is written to the file: Saves at once (a second click while a large file is being
        #: written, or two tabs) write one after the other, each appending to what the other wrote, and a branch
        #: already written is refused (a lost or a doubled branch otherwise)
        self.save_lock = threading.Lock()
        #: set once the solver's compiled kernels are ready (app.py warms them in the background);
        #: until then the sessions draw everything but the orbits
        self.solver_ready = threading.Event()
        #: the kernels that integrate the file's orbits are compiled (warm-up's first step): orbits can be shown
        self.orbits_ready = threading.Event()
        if solver_ready:
            self.solver_ready.set()
            self.orbits_ready.set()
        #: {mode: the file's reference name of it} (/extra/reference/mode_names: the paper's names of the Paris
        #: model's modes), said next to the model's labels
        self.reference_names = reference_names(path)
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
        entry = BranchEntry(branch=branch, label=branch_label(branch, k3_factor, source, self.model,
                                                              self.reference_names),
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
            entry.label = branch_label(entry.branch, entry.k3_factor, entry.source, self.model, self.reference_names)
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
            except Exception:  # a broken tab must not break the others: logged, the others still run
                log.exception("a viewer listener failed on %r", kind)

    # ------------------------------------------------------------------ the job (one at a time)
    def claim_job(self, runner):
        """Make ``runner`` the running job, atomically: raises JobBusy if another job is running."""
        with self.lock:
            if self.job is not None and self.job is not runner and self.job.running:
                raise JobBusy()
            self.job = runner
            self.error = ""

    def release_job(self, runner):
        """``runner`` has ended (or never started): the job slot is free again."""
        with self.lock:
            if self.job is runner:
                self.job = None

    def running_job(self):
        """The running JobRunner, or None."""
        with self.lock:
            job = self.job
        return job if job is not None and job.running else None

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
        with self.save_lock:
            with self.lock:
                if entry.saved:
                    raise nnm_solver.NNMInputError("this branch is already in the file")
            target, reason = branch_output(self.path)
            nnm_solver.save_branch(target, branch)
            with self.lock:
                entry.saved = True
            self.update(entry, source="saved", notify=False)
        self.notify("branches")                  # outside save_lock: listeners take the tabs' locks
        return target, reason
