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

import functools
import math

import numpy as np

from dataclasses import fields, replace

from ..backbone.labels import FamilyLabels
from ..backbone.policy import policy_for
from ..backbone.settings import TONGUE_MODES, Follow, Skip
from ..backbone.skeleton import skeleton_of
from ..continuation.engine import ContinuationSettings, pseudo_arclength
from ..errors import NNMInputError
from ..threads import blas_limited
from .iterator import NNMIterator
from ..model.modal import modal_system
from ..model.ritz import ritz_system
from ..model.model import Model
from .problems import METHODS, check_positive, hb_problem, modal_basis, shooting_problem, start_amplitude
from .settings import SIZES, Continuation, HarmonicBalance, Shooting, method_of

__all__ = ["iter_nnm", "continue_nnm", "NNMIterator", "METHODS", "from_keywords"]


def _tongues_of(tongues):
    if isinstance(tongues, (Follow, Skip)):
        return tongues
    if tongues is None:
        return Follow()
    if tongues in TONGUE_MODES:
        return TONGUE_MODES[tongues]()
    raise NNMInputError(f"tongues must be Follow(), Skip() or one of {', '.join(map(repr, TONGUE_MODES))}, got "
                        f"{tongues!r}")


def from_keywords(method=None, continuation=None, tongues=None, keywords=None):
    """(method, continuation, tongues) settings objects from typed objects and/or the keywords of earlier
    releases (``integrator=``, ``steps_per_period=``, ``harmonics=``, ``tol=``, ``max_points=``, ``step=``, ...),
    each keyword replacing the field of that name.  NNMInputError for a keyword no object knows or that belongs
    to the other method."""
    keywords = dict(keywords or {})
    m = method_of(method)
    c = Continuation() if continuation is None else continuation
    if not isinstance(c, Continuation):
        raise NNMInputError(f"continuation must be a Continuation(...), got {type(c).__name__}")
    t = _tongues_of(tongues)
    own = {f.name for f in fields(m)} - set(m.record_fields)        # (the branch's record: not asked for)
    other = {f.name for f in fields(HarmonicBalance if isinstance(m, Shooting) else Shooting)} - own
    cont = {f.name for f in fields(Continuation)}
    mk, ck = {}, {}
    for key, value in keywords.items():
        if key in own:
            if value is not None or key in ("steps_per_period", "symmetric", "reversible", "samples", "basis",
                                            "modal_basis", "freq_tol"):
                mk[key] = value
        elif key in cont:
            if value is not None:
                ck[key] = value
        else:
            where = f"; it belongs to method={'hb' if m.name == 'shooting' else 'shooting'!r}" if key in other else ""
            raise NNMInputError(f"unknown option {key!r} for method={m.name!r}{where}")
    return replace(m, **mk), replace(c, **ck), t


def check_limits(energy_max, tol):
    """NNMInputError (one line) unless energy_max (J) and tol are positive numbers: limits every continuation shares
    (continue_nnm, switch_branch, continue_tongue; with check_max_points)."""
    check_positive("energy_max", energy_max)
    check_positive("tol", tol)


def check_max_points(max_points):
    """NNMInputError (one line) unless max_points is a positive integer (every continuation's, as check_limits)."""
    check_positive("max_points", max_points, integer=True)


def check_family_start(energy_max, start_energy, start):
    """NNMInputError (one line) unless energy_max (J) lies above ``start_energy`` (J), the energy of the orbit a family
    starts from (``start``: what that orbit is, for the message).  A family may head down in energy from its start
    (either side of a branch point, a tongue that dips below its entry), but energy_max is the continuation's ceiling
    whichever way it goes: it stops at the first orbit at or above it (stop_rules.stop_after_point), so a ceiling at or
    below the start would end the family at its first orbit."""
    if not energy_max > start_energy:
        raise NNMInputError(f"energy_max = {energy_max:g} J is not above the family's start, {start} at E = "
                            f"{start_energy:.6g} J; energy_max caps the continuation whichever way in energy the "
                            f"family goes: give one above {start_energy:.6g} J")


def check_branch_arguments(model, mode, energy_max, tol, max_points, energy_min, modes_known=True):
    """Validate the arguments every branch computation shares; returns the 0-based mode index.
    modes_known=False: the mode number is only checked against the DOF count (the Ritz basis checks the rest)."""
    if not isinstance(model, Model):
        raise NNMInputError(f"model must be an nnm_solver.Model, got {type(model).__name__}")
    check_limits(energy_max, tol)
    check_max_points(max_points)
    if energy_min is not None:
        check_positive("energy_min", energy_min)
        if energy_min >= energy_max:
            raise NNMInputError(f"energy_min ({energy_min:g} J) must be below energy_max ({energy_max:g} J)")
    if not modes_known:
        if not isinstance(mode, (int, np.integer)) or isinstance(mode, bool) or not 1 <= mode <= model.n:
            raise NNMInputError(f"mode must be an integer in 1..{model.n} (1-based), got {mode!r}")
        return int(mode) - 1
    return model.check_mode(mode)


def iter_nnm(model, mode, energy_max, method=None, *, continuation=None, tongues=None, energy_min=None,
             floquet=None, locate_events=True, _start=None, **keywords):
    """Iterator over the converged orbits of the NNM branch of linear mode ``mode`` (1-based).

    Starts from a nearly linear orbit and continues in energy up to ``energy_max`` (J).  Yields
    ``Point`` objects (energy J, frequency_hz Hz, period s, x0, v0, floquet, stable, ...); returns an
    NNMIterator, whose ``branch()`` collects them (the arguments: ``continue_nnm``)::

        it = nnm.iter_nnm(model, 1, 1e3)
        for p in it:
            if p.frequency_hz > 1.2 * it.points[0].frequency_hz:
                break                       # a stopping rule of one's own
        branch = it.branch()                # status 'stopped'

    Bad arguments raise NNMInputError here, before any computation.
    """
    method, cont, tongues = from_keywords(method, continuation, tongues, keywords)
    name = method.name
    tol = method.tol
    ritz = name == "hb" and modal_basis(model, method.options()) == "ritz"
    k = check_branch_arguments(model, mode, energy_max, tol, cont.max_points, energy_min, modes_known=not ritz)
    for field_name in ("step", "step_min", "max_angle", "max_correction", "max_rel_step", "max_period_step"):
        check_positive(field_name, getattr(cont, field_name))
    freq_tol = getattr(method, "freq_tol", None)
    if freq_tol is not None:
        check_positive("freq_tol", freq_tol)
    if not method.error_estimate:
        freq_tol = None                        # the accuracy target acts on the estimates: none, no refinement
    if ritz:                                   # the modes below a cutoff + residual flexibility (model/ritz.py)
        check_positive("harmonics", method.harmonics, integer=True)
        system = ritz_system(model, mode, method.harmonics)
    else:
        system = modal_system(model)
    a0 = start_amplitude(system, k, energy_max, energy_min)
    build = shooting_problem if name == "shooting" else hb_problem
    problem, u0, p0, settings = build(system, k, a0, dict(method.options(), max_rel_step=cont.max_rel_step,
                                                           max_period_step=cont.max_period_step),
                                      tol, energy_max, floquet)
    f_method = method_frequency(problem, u0)   # the linear mode's frequency as the method computes it (labels.py)
    if _start is not None:                     # start at a given orbit, towards another (continue_tongue)
        (xa, va, Ta), (xb, vb, Tb) = _start
        u0 = problem.pack(system.to_modal(xa), system.to_modal(va), Ta)
        p0 = problem.pack(system.to_modal(xb), system.to_modal(vb), Tb) - u0
        problem.accept(u0, None)
    cs = ContinuationSettings(step=cont.step, step_min=cont.step_min, step_max=np.inf, max_angle=cont.max_angle,
                              max_correction=cont.max_correction)
    engine = pseudo_arclength(problem, u0, p0, cs, tol)
    # the branch's record: the request's own fields, with what the problem resolved (steps, basis, symmetry, ...)
    settings = replace(method, **{f.name: getattr(settings, f.name) for f in fields(settings)
                                  if f.name not in ("freq_tol", "error_estimate", "max_steps_per_period",
                                                    "max_harmonics")}, freq_tol=freq_tol)
    # the skeleton (backbone/skeleton.py) labels the points and guides the jumps over tongues (its harmonics:
    # skeleton_harmonics)
    sk_h = skeleton_harmonics(method, tongues.skeleton.harmonics, refined=freq_tol is not None and not ritz)
    # (under the branch's BLAS thread limit, as its points are: its dense least-squares Newton steps on a shared
    # machine took 9x longer with OpenBLAS's threads, threads.py)
    with blas_limited():
        sk, failure = (skeleton_of(model, mode, energy_max, _skeleton_system, replace(tongues.skeleton, harmonics=sk_h),
                                   tongues.reach) if model.springs else (None, "the model has no nonlinear element"))
    labels = FamilyLabels(sk, math.sqrt(system.omega2[k]) / (2 * math.pi), f_method,
                          getattr(getattr(problem, "integrator", None), "order", 0), tongues.labels)
    return NNMIterator(model, mode, problem, system, engine, settings, energy_max, cont.max_points, cs, tol,
                       locate=locate_events, error_estimate=method.error_estimate, freq_tol=freq_tol, labels=labels,
                       policy=policy_for(tongues, sk, failure, mode), start_is_low=_start is None,
                       max_refusals=cont.max_refusals,
                       max_steps_per_period=getattr(method, "max_steps_per_period", 0) or 1,
                       max_harmonics=0 if ritz else getattr(method, "max_harmonics", 0))


def method_frequency(problem, u0):
    """The followed linear mode's frequency (Hz) as the branch's method computes it (labels.FamilyLabels' f_method):
    shooting, a function of a point's time steps per period (the integrator's discrete linear period at that step,
    Integrator.linear_period; Newmark's relative period error (omega h)^2 / 12 changes with the steps the freq_tol
    refinement gives the points, driver/refinement.py); harmonic balance, with no time step, the frequency of its
    first orbit u0 (the linear mode's)."""
    integrator = getattr(problem, "integrator", None)
    if integrator is None:
        return 1.0 / problem.state(u0)[2]
    omega = problem.w_r
    return functools.lru_cache(maxsize=None)(lambda steps: 1.0 / integrator.linear_period(omega, steps))


def skeleton_harmonics(method, default, refined):
    """The skeleton's harmonics for a branch by ``method``: the skeleton's own (``default``, 9) for shooting and for
    harmonic balance whose accuracy target raises its harmonics (``refined``: its truncation is not fixed; measured on
    mode 20 with 3 harmonics asked, raised to 7: against a 3-harmonic skeleton none of 12 landings past the 3:1 at
    3.49 J was accepted); harmonic balance at fixed harmonics has the branch's own, the same truncation (above 9 too:
    13 harmonics against a 9-harmonic skeleton found no landing past the 3:1 at 4.63 J)."""
    if method.name == "shooting":
        return default
    return max(default, int(method.harmonics)) if refined else int(method.harmonics)


def _skeleton_system(model, mode, harmonics):
    """The modal system of the skeleton (backbone/skeleton.py) with ``harmonics``: every mode, or for a large model
    the Ritz basis for those harmonics (model/ritz.py; the one a harmonic-balance branch with as many harmonics
    built already, from its cache)."""
    if model.n > SIZES.ritz_min_dof:
        return ritz_system(model, mode, harmonics)
    return modal_system(model)


def continue_nnm(model, mode, energy_max, method=None, *, continuation=None, tongues=None, energy_min=None,
                 floquet=None, locate_events=True, on_point=None, stop=None, **keywords):
    """Compute the NNM branch of linear mode ``mode`` (1-based) from low energy up to ``energy_max`` (J).

    Parameters
    ----------
    method : ``Shooting(...)`` (default: Gauss-Legendre order 6 at 100 steps a period, with the exact monodromy;
        ``Shooting(integrator="newmark")`` is the seed paper's scheme) or ``HarmonicBalance(...)`` (harmonics,
        samples, basis, ``condensed=True``: the equations condensed onto the nonlinear elements, whatever the model
        size); or their names "shooting" / "hb".  driver/settings.py documents every field and default.
    continuation : ``Continuation(...)``: step control and max_points (driver/settings.py).
    tongues : ``Follow()`` (default: the continuation follows the internal-resonance tongues of order up to 3 it
        meets, points labelled against the backbone family, and jumps those of higher order as Skip does;
        ``Follow(max_order=None)`` follows every tongue) or ``Skip()`` (the backbone: tongues jumped from the
        skeleton, each listed in branch.tongues and computable with ``continue_tongue``); or "follow" / "follow-all"
        / "skip".
        backbone/policy.py describes the algorithm, backbone/settings.py its settings.
    energy_min : energy (J) of the first point (default: where the springs hold 1e-5 of the energy).
    floquet : compute Floquet multipliers and stability at every point (default: yes; HB: when the Hill matrix
        has at most driver/settings.SIZES.hill_auto_size rows, or in a Ritz basis of a large model whose
        multipliers take the monodromy route, driver/problems.hb_floquet_default).
    locate_events : locate folds and stability changes between points (default True).
    on_point : optional callable(point: Point) called after each converged point (inside the branch's BLAS-limited
        region, threads.blas_limited, as in a Job).
    stop : optional threading.Event-like object; when set, the continuation stops (status 'cancelled').
    **keywords : the keywords of earlier releases, each replacing the field of that name of the method or the
        continuation settings (``integrator="gauss6"``, ``steps_per_period=100``, ``harmonics=9``,
        ``condensed=True``, ``tol=1e-8``, ``max_points=200``, ``step=0.1``, ``max_period_step=0.02``,
        ``freq_tol=1e-6``, ``error_estimate=False``, ...).

    Returns a Branch; its ``status`` and ``message`` say why the continuation stopped, and every
    point computed before a failure is kept.
    """
    it = iter_nnm(model, mode, energy_max, method, continuation=continuation, tongues=tongues, energy_min=energy_min,
                  floquet=floquet, locate_events=locate_events, **keywords)
    with blas_limited():        # one region for the whole branch, as a Job's (each point's then only counts itself:
        while True:             # setting and restoring the limit cost 47 us a point, 4.6 % of condensed HB's)
            if stop is not None and stop.is_set():
                it.cancel()
            try:
                point = next(it)
            except StopIteration:
                return it.branch()
            if on_point is not None:
                on_point(point)
