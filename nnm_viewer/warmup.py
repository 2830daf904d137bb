"""Preparing the solver in the background at server start.

The solver's kernels are compiled by numba on their first call (about 30 s on a 2-core machine
after installing; a few tenths of a second once numba's disk cache holds them).  The server does
not wait for it: ``SolverWarmUp`` runs a tiny continuation (two points of the 2-DOF benchmark, with
Floquet multipliers, and one orbit integration) in a thread; meanwhile the page is served and
drawn (model at rest, FEP, branch list, sliders), shows "preparing the solver", and the orbits are
computed once it is ready.
"""
from __future__ import annotations

import logging
import threading
import time

import numpy as np

log = logging.getLogger("nnm_viewer")


def warm_kernels(elements=1):
    """Call every compiled kernel the viewer uses (shooting with Floquet multipliers, event
    location, orbit integration) on a 2-DOF model with ``elements`` cubic springs (1, or 2 for
    the kernels of a model with several nonlinear elements: numba compiles the one-element
    kernels apart, newmark_monodromy.one_element), and import the plotting backend."""
    import nnm_solver as nnm

    springs = [nnm.CubicSpring(dof=0, k3=0.5)] + ([nnm.CubicSpring(dof=1, k3=0.25)] if elements > 1 else [])
    model = nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs, name="warm-up")
    branch = nnm.continue_nnm(model, mode=1, energy_max=1.0, max_points=2)
    branch.motion(0, samples=16)
    import matplotlib.backends.backend_agg  # noqa: F401 (the FEP images)


def warm_orbits(elements=1, integrators=("newmark",)):
    """Compile the orbit integration (``record_orbit``) of each of ``integrators`` for a model with ``elements``
    nonlinear elements (1 or several): what showing the stored branches' orbits needs."""
    import nnm_solver as nnm
    from nnm_solver.integrators.registry import record_orbit
    from nnm_solver.model.modal import modal_system

    springs = [nnm.CubicSpring(dof=0, k3=0.5)] + ([nnm.CubicSpring(dof=1, k3=0.25)] if elements > 1 else [])
    system = modal_system(nnm.Model(np.eye(2), np.array([[2.0, -1.0], [-1.0, 2.0]]), springs, name="warm-up"))
    for name in integrators:
        record_orbit(system, np.array([0.1, 0.0]), np.zeros(2), 6.0, 8, name)


def warm_for(model, branches=(), on_orbits=None):
    """The warm-up of the kernels ``model`` needs (those of a model with one nonlinear element or with
    several): first the orbit integration of the integrators of the stored ``branches`` (then
    ``on_orbits()``: their orbits can be shown), then the continuation's kernels (warm_kernels)."""
    n = len(getattr(model, "elements", ()) or ())
    elements = 2 if n > 1 else 1
    used = []
    for b in branches:
        name = getattr(getattr(b, "settings", None), "integrator", None)
        if name and name not in used:
            used.append(name)

    def warm():
        if used:
            warm_orbits(elements, used)
        if on_orbits is not None:
            on_orbits()
        warm_kernels(elements)
    return warm


class SolverWarmUp:
    """``warm`` (default ``warm_kernels``) in a daemon thread; ``done`` is set when it has ended
    (even if it failed: the sessions then meet the real error themselves), then ``on_done(seconds,
    error)`` is called."""

    def __init__(self, on_done=None, warm=None):
        self.on_done = on_done
        self.warm = warm or warm_kernels
        self.done = threading.Event()
        self.seconds = None
        self.error = None

    def start(self):
        threading.Thread(target=self._run, name="nnm-view-solver-warm-up", daemon=True).start()
        return self

    def _run(self):
        t0 = time.perf_counter()
        try:
            self.warm()
        except Exception as exc:   # only a warm-up: a real computation will report the problem
            self.error = exc
            log.info("solver warm-up failed: %s", exc)
        self.seconds = time.perf_counter() - t0
        log.info("solver ready after %.2f s", self.seconds)
        self.done.set()
        if self.on_done is not None:
            self.on_done(self.seconds, self.error)
