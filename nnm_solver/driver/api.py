r"""The NNM driver: one branch from a linear mode at low energy up to a target energy, for any method.

    iter_nnm(model, mode, energy_max, method="shooting" | "hb", ...)   an iterator of converged Points
    continue_nnm(...)                                                  the Branch: a loop over iter_nnm

The driver checks the arguments, builds the method's periodic-orbit problem (orbits/) on the modal
system (modal.py) from a nearly linear first orbit, and hands it to an ``NNMIterator`` (iterator.py),
which runs the generic pseudo-arclength engine (continuation.py) and turns each converged point into a
``Point`` (energy J, frequency Hz, period s, initial state, Floquet multipliers and stability).  A user's own stopping rule is a
``break`` out of the loop; ``iterator.branch()`` then holds every point seen.
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.engine import ContinuationSettings, pseudo_arclength
from ..errors import NNMInputError
from .iterator import NNMIterator
from .labels import FamilyLabels
from .skeleton import FOLLOW_REACH, REACH, SKELETON_HARMONICS, skeleton
from ..model.modal import modal_system
from ..model.ritz import ritz_system
from ..model.model import Model
from .problems import (METHODS, RITZ_MIN_DOF, check_positive, hb_problem, modal_basis, shooting_problem,
                       start_amplitude)
from .problems import method_options as split_options

__all__ = ["iter_nnm", "continue_nnm", "NNMIterator", "METHODS"]

#: default largest relative change of the period in one step (max_period_step=None), by method: 0.005.  Shooting's
#: orbits meet internal-resonance tongues of every order, whose entrances are narrow in period.  For harmonic
#: balance a 2 % cap takes about NLvib's points (issue 30: 23 instead of 70 on NLvib's example 04, 87 instead of
#: 190 on 09, the same folds) but straight lines between its points then miss the curve by up to 2.4e-3 across a
#: piecewise-linear kink and the energy-balance peak prediction by 1.3e-3 (tests/test_elements.py,
#: tests/test_forced.py), so it is the user's choice (``max_period_step=0.02``); at 5 % a step of the 3-DOF
#: combination-resonance branch (tests/test_bifurcation.py) stepped over its whole unstable interval between two
#: Krein collisions (1.71-2.37 J; stable at both ends, so nothing to locate)
MAX_PERIOD_STEP = {"shooting": 0.005, "hb": 0.005}

def check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min, modes_known=True):
    """Validate the arguments every branch computation shares; returns the 0-based mode index.
    modes_known=False: the mode number is only checked against the DOF count (the Ritz basis checks the rest)."""
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    check_positive("energy_max", energy_max)
    check_positive("tol", tol)
    check_positive("max_points", max_points, integer=True)
    if energy_min is not None:
        check_positive("energy_min", energy_min)
        if energy_min >= energy_max:
            raise NNMInputError(f"energy_min ({energy_min:g} J) must be below energy_max ({energy_max:g} J)")
    if not modes_known:
        if not isinstance(mode, (int, np.integer)) or isinstance(mode, bool) or not 1 <= mode <= model.n:
            raise NNMInputError(f"mode must be an integer in 1..{model.n} (1-based), got {mode!r}")
        return int(mode) - 1
    return model.check_mode(mode)


def iter_nnm(model, mode, energy_max, method="shooting", *, tol=None, max_points=500, energy_min=None,
             floquet=None, step=None, max_angle=0.35, max_correction=0.5, max_rel_step=0.4, max_period_step=None,
             locate_events=True, tongues="follow", error_estimate=True, freq_tol=None, _start=None, **method_options):
    """Iterator over the converged orbits of the NNM branch of linear mode ``mode`` (1-based).

    Starts from a nearly linear orbit and continues in energy up to ``energy_max`` (J).  Yields
    ``Point`` objects (energy J, frequency_hz Hz, period s, x0, v0, floquet, stable, ...); returns an
    NNMIterator, whose ``branch()`` collects them (see ``continue_nnm`` for the arguments)::

        it = nnm.iter_nnm(model, 1, 1e3)
        for p in it:
            if p.frequency_hz > 1.2 * it.points[0].frequency_hz:
                break                       # a stopping rule of one's own
        branch = it.branch()                # status 'stopped'

    tongues : "follow" (the continuation follows the internal-resonance tongues it meets) or "skip"
    (it jumps over them and returns the backbone; each tongue passed is listed in branch.tongues and
    can be computed with ``continue_tongue``); see tongue_skip.py.  locate_events : locate folds and
    stability changes between points (events.py).

    Bad arguments raise NNMInputError here, before any computation.
    """
    if tongues not in ("follow", "skip"):
        raise NNMInputError(f"tongues must be 'follow' or 'skip', got {tongues!r}")
    method, opts = split_options(method, method_options)
    if max_period_step is None:
        max_period_step = MAX_PERIOD_STEP[method]
    if tol is None:
        tol = 1e-6 if method == "shooting" else 1e-8
    ritz = method == "hb" and modal_basis(model, opts) == "ritz"
    k = check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min, modes_known=not ritz)
    for name, value in (("max_angle", max_angle), ("max_correction", max_correction), ("max_rel_step", max_rel_step),
                        ("max_period_step", max_period_step)):
        check_positive(name, value)
    if step is not None:
        check_positive("step", step)
    if freq_tol is not None:
        check_positive("freq_tol", freq_tol)
        if method != "shooting":
            raise NNMInputError("freq_tol refines the time step of shooting; harmonic balance has none "
                                "(raise harmonics instead)")
    if ritz:                                   # the modes below a cutoff + residual flexibility (model/ritz.py)
        check_positive("harmonics", opts["harmonics"], integer=True)
        system = ritz_system(model, mode, opts["harmonics"])
    else:
        system = modal_system(model)
    a0 = start_amplitude(system, k, energy_max, energy_min)
    build = shooting_problem if method == "shooting" else hb_problem
    problem, u0, p0, settings = build(system, k, a0, dict(opts, max_rel_step=max_rel_step, max_period_step=max_period_step),
                                      tol, energy_max, floquet)
    f_method = 1.0 / problem.state(u0)[2]      # the linear mode's frequency as the method computes it (labels.py)
    if _start is not None:                     # start at a given orbit, towards another (continue_tongue)
        (xa, va, Ta), (xb, vb, Tb) = _start
        u0 = problem.pack(system.to_modal(xa), system.to_modal(va), Ta)
        p0 = problem.pack(system.to_modal(xb), system.to_modal(vb), Tb) - u0
        problem.accept(u0, None)
    cs = ContinuationSettings(step=0.5 if step is None else float(step), step_min=1e-8, step_max=np.inf,
                              max_angle=max_angle, max_correction=max_correction)
    engine = pseudo_arclength(problem, u0, p0, cs, tol)
    if freq_tol is not None:
        settings = settings.replace(freq_tol=float(freq_tol))
    # the skeleton (driver/skeleton.py) labels the points and guides the jumps over tongues; with harmonic
    # balance it has the branch's harmonics (at most SKELETON_HARMONICS): the same truncation
    sk_h = SKELETON_HARMONICS if method == "shooting" else min(int(opts["harmonics"]), SKELETON_HARMONICS)
    reach = REACH if tongues == "skip" else FOLLOW_REACH
    guide = _skeleton_guide(model, mode, energy_max, sk_h, reach) if model.springs else None
    labels = FamilyLabels(guide, math.sqrt(system.omega2[k]) / (2 * math.pi), f_method,
                          getattr(getattr(problem, "integrator", None), "order", 0))
    it = NNMIterator(model, mode, problem, system, engine, settings, energy_max, max_points, cs, tol,
                     locate=locate_events, tongues=tongues, error_estimate=error_estimate, freq_tol=freq_tol,
                     skeleton=guide, labels=labels)
    it._start_is_low = _start is None
    return it


def _skeleton_system(model, mode, harmonics=SKELETON_HARMONICS):
    """The modal system of the skeleton (driver/skeleton.py) with ``harmonics``: every mode, or for a large model
    the Ritz basis for those harmonics (model/ritz.py; the one a harmonic-balance branch with as many harmonics
    built already, from its cache)."""
    if model.n > RITZ_MIN_DOF:
        return ritz_system(model, mode, harmonics)
    return modal_system(model)


def _skeleton_guide(model, mode, energy_max, harmonics=SKELETON_HARMONICS, reach=REACH):
    """A callable giving the Skeleton of the branch (computed at its first call, when a point leaves the linear
    regime), or None when it cannot be computed (labels then come from the harmonic share, and the jumps
    rescale the backbone's orbits only)."""
    found = []

    def guide():
        if not found:
            try:
                found.append(skeleton(model, mode, energy_max, _skeleton_system, harmonics, reach))
            except (NNMInputError, np.linalg.LinAlgError, ValueError, RuntimeError):
                found.append(None)
        return found[0]
    return guide


def continue_nnm(model, mode, energy_max, steps_per_period=200, tol=None, max_points=500, on_point=None,
                 stop=None, energy_min=None, symmetric=None, floquet=None, step=None, max_angle=0.35,
                 max_correction=0.5, max_rel_step=0.4, reversible=None, max_period_step=None, *,
                 method="shooting", tongues="follow", locate_events=True, integrator="newmark", error_estimate=True,
                 freq_tol=None, **hb_options):
    """Compute the NNM branch of linear mode ``mode`` (1-based) from low energy up to ``energy_max`` (J).

    Parameters
    ----------
    method : "shooting" (Newmark shooting, the seed paper's method; default) or "hb" (harmonic
        balance; options ``harmonics``, ``samples``, ``basis``, ``condensed``, see ``nnm_solver.hb``).
        ``condensed=True`` solves the HB equations condensed exactly onto the nonlinear elements'
        deformations (orbits/condensed_hb.py): n_s (H + 1) / 2 + 2 unknowns whatever the model size, the
        same orbits as the uncondensed HB away from exact internal resonances.
    steps_per_period : time steps per period; shooting.  The frequency error is O(steps^-order) (order 2
        for Newmark), largest for orbits with strong higher harmonics (branch.freq_error estimates it).
        Rounded up to a multiple of 4 for the default quarter-period shooting of symmetric orbits (to an even
        number for half-period shooting); the branch's settings record the number used.
    integrator : the shooting's time integrator, one of ``INTEGRATORS``: "newmark" (default; the seed
        paper's average-acceleration scheme, order 2), "gauss4" / "gauss6" (Gauss-Legendre collocation,
        orders 4 and 6, about 2x / 3x Newmark's cost per step; see integrators.py).
    tol : relative periodicity tolerance ||H|| / ||z0|| (seed eq. 11); default 1e-6 (HB: 1e-8 on
        the relative residual).
    max_points : largest number of points kept.
    on_point : optional callable(point: Point) called after each converged point.
    stop : optional threading.Event-like object; when set, the continuation stops (status 'cancelled').
    energy_min : energy (J) of the first point (default: where the springs hold 1e-5 of the energy).
    symmetric : half-period shooting (valid for odd nonlinear forces; see orbits/shooting.py).  Default:
        True when every element's force is odd, else full-period shooting (then ``reversible``
        defaults to True: orbits start at rest).
    reversible : orbits starting at rest (v0 = 0, default with symmetric) or general orbits with a
        phase condition (False); see orbits.shooting.ShootingProblem.
    floquet : compute Floquet multipliers and stability at every point (default: yes; HB: when
        the Hill matrix has at most HILL_AUTO_SIZE rows).
    step : first step length, relative to the orbit (default 0.5: half the starting amplitude); steps
        are measured in the balanced norm of continuation.py (state relative to its norm, period
        relative to itself).
    max_angle : largest turn (rad) of the branch tangent between two points.
    max_correction : largest corrector displacement, relative to the step length.
    max_rel_step : largest relative change of the orbit's state (amplitude and shape) in one step.
    max_period_step : largest relative change of the period between two points (default: MAX_PERIOD_STEP of
        the method, 0.005 for shooting, 0.02 for harmonic balance; keeps the
        continuation from stepping over the entrance of internal-resonance tongues).
    tongues : "follow" (default) or "skip" (return the backbone; tongues listed in branch.tongues,
        each computable with ``continue_tongue``).
    locate_events : locate folds and stability changes between points (default True).
    error_estimate : estimate each point's relative frequency error (branch.freq_error): shooting, from the time
        discretisation by step doubling (about 2 residual evaluations per point); harmonic balance, from the
        truncation of the harmonics, the frequency's change at the point's energy with two harmonics more (a
        Newton step of that larger problem per point, a few next to a resonant harmonic; orbits/hb_error.py).
    freq_tol : if given (e.g. 1e-6), the steps per period are raised wherever a point's estimated
        frequency error exceeds it, and the point is computed again (branch.steps has each point's).

    Returns a Branch; its ``status`` and ``message`` say why the continuation stopped, and every
    point computed before a failure is kept.
    """
    if method == "shooting":
        opts = dict(steps_per_period=steps_per_period, symmetric=symmetric, reversible=reversible,
                    integrator=integrator, **hb_options)
    elif integrator != "newmark":
        raise NNMInputError("integrator= belongs to method='shooting' (harmonic balance has no time steps)")
    else:
        opts = dict(hb_options)
    it = iter_nnm(model, mode, energy_max, method, tol=tol, max_points=max_points, energy_min=energy_min,
                  floquet=floquet, step=step, max_angle=max_angle, max_correction=max_correction,
                  max_rel_step=max_rel_step, max_period_step=max_period_step, tongues=tongues,
                  locate_events=locate_events, error_estimate=error_estimate, freq_tol=freq_tol, **opts)
    while True:
        if stop is not None and stop.is_set():
            it.cancel()
        try:
            point = next(it)
        except StopIteration:
            return it.branch()
        if on_point is not None:
            on_point(point)
