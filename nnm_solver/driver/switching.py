r"""Branch switching: the family of periodic orbits that bifurcates from a located event.

At a ``branch_point`` a non-trivial pair of Floquet multipliers passes through +1: the shooting
Jacobian of the *general* formulation (full period, free velocities, phase condition; unknowns
u = [q0; v0 / w_r; T / T_r]) loses one rank, and its null space holds, besides the tangent of the
parent family, the direction of the bifurcating one.  The reversible half-period formulation used for
backbones cannot see it when the new family breaks the half-wave symmetry (even harmonics appear) or
the time reversibility; the general one can.  At a ``period_doubling`` a multiplier passes through -1:
the same construction over two periods (the orbit repeated, 2 N steps of the same size) gives the
doubled-period family.

The new direction d is the unit null vector of the scaled Jacobian orthogonal to the parent's tangent
(estimated from the parent's points around the event); the new branch starts at u_event + step d and
is continued by the same engine and driver as any branch, in the general formulation.  It ends at
energy_max, when it returns to low energy, closes a loop, escapes, or meets the parent family again at
another of its branch points (then its message says which).
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import ContinuationSettings, pseudo_arclength
from .api import NNMIterator, check_family_start, check_limits, check_max_points
from .problems import check_positive
from ..errors import NNMInputError
from ..model.modal import modal_system
from ..orbits.shooting import ShootingProblem
from ..integrators.registry import get_integrator
from ..results.settings import Shooting, ShootingSettings

__all__ = ["switch_branch", "switch_arguments"]

SWITCHABLE = ("branch_point", "period_doubling")


def _event(branch, event):
    event = branch.pick("events", event)
    if "kind" not in event:
        raise NNMInputError("event must be one of branch.events (a dict) or its index")
    if event["kind"] not in SWITCHABLE:
        raise NNMInputError(f"cannot switch branches at a {event['kind']!r} event; only at {', '.join(SWITCHABLE)}")
    if "x0" not in event:
        raise NNMInputError("the event was not located (no orbit stored); recompute the branch with this version "
                            "of nnm (continue_nnm locates events)")
    return event


def _parent_tangent(branch, event, system, problem, period_factor):
    """Direction of the parent family at the event (u units), from its two bracketing points."""
    i = int(np.clip(event["index"], 1, len(branch) - 1))
    us = []
    for j in (i - 1, i):
        q0, v0 = system.to_modal(branch.x0[j]), system.to_modal(branch.v0[j])
        us.append(problem.pack(q0, v0, branch.period[j] * period_factor))
    return us[1] - us[0]


def switch_arguments(branch, event, energy_max, *, max_points=None, tol=None):
    """The located event (a dict) and the corrector tolerance (relative) of the family ``switch_branch`` starts at
    ``event`` of ``branch`` (a record of branch.events or its index); tol None: the parent's own (a shooting parent),
    else 1e-6; max_points None: switch_branch's default.  NNMInputError (one line), before any computation, for an
    event no family can start from, energy_max, tol or max_points that continue_nnm refuses (api.check_limits,
    api.check_max_points), or energy_max (J) not above the event's energy (api.check_family_start: the family may go
    down in energy from there, but energy_max is its ceiling)."""
    event = _event(branch, event)
    s = branch.settings
    tol = (s.tol if s.method == "shooting" else 1e-6) if tol is None else tol
    check_limits(energy_max, tol)
    if max_points is not None:                 # (None: not given, switch_branch's default)
        check_max_points(max_points)
    check_family_start(energy_max, float(event["energy"]), f"the {event['kind'].replace('_', ' ')}")
    return event, float(tol)


def switch_branch(branch, event, energy_max, *, step=0.05, direction=1, max_points=300, tol=None, floquet=True,
                  max_angle=0.35, max_correction=0.5, max_rel_step=0.4, max_period_step=0.005):
    """Continue the family that bifurcates from ``event`` of ``branch`` (a located ``branch_point`` or
    ``period_doubling`` of ``branch.events``, or its index), up to ``energy_max`` (J).

    step : first step, relative to the orbit; direction : +1 or -1, which side of the null direction.
    Other options as ``continue_nnm``.  Returns a Branch (general full-period shooting: v0 free,
    symmetric=False, reversible=False; doubled period for period doubling) whose message says how it
    ended.  energy_max must lie above the event's energy (the family may head down in energy from there, but
    the continuation stops at its first orbit at or above energy_max); it, tol and max_points are checked as
    ``continue_nnm`` checks them, before any computation (``switch_arguments``).
    """
    check_max_points(max_points)               # (None refused here: switch_arguments reads it as not given)
    event, tol = switch_arguments(branch, event, energy_max, max_points=max_points, tol=tol)
    check_positive("step", step)
    if direction not in (1, -1):
        raise NNMInputError(f"direction must be +1 or -1, got {direction!r}")
    s = branch.settings
    # a shooting parent's own integrator and steps; a harmonic-balance parent's family is shot with the defaults
    # (Shooting(): gauss6 at its registry's steps), not the first release's Newmark at 200
    integrator = getattr(s, "integrator", None) or Shooting().integrator
    spp = int(getattr(s, "steps_per_period", None) or get_integrator(integrator).steps)
    factor = 2 if event["kind"] == "period_doubling" else 1
    model = branch.model
    system = modal_system(model)
    k = branch.mode - 1
    problem = ShootingProblem(system, k, spp * factor, symmetric=False, reversible=False, max_rel_step=max_rel_step,
                              max_rel_period_step=max_period_step, integrator=integrator)
    q0 = system.to_modal(np.asarray(event["x0"], dtype=float))
    v0 = system.to_modal(np.asarray(event["v0"], dtype=float))
    problem.q_ref = q0 / np.linalg.norm(q0)
    problem.set_section(q0, v0)
    u_e = problem.pack(q0, v0, event["period"] * factor)
    _, J = problem.jacobian(u_e)
    w = problem.scale(u_e)
    _, sv, Vt = np.linalg.svd(J / w[None, :])
    null = Vt[-2:].T                                           # scaled units
    parent = w * _parent_tangent(branch, event, system, problem, factor)
    c = null.T @ parent
    d = null @ np.array([-c[1], c[0]]) if np.linalg.norm(c) > 0 else null[:, -1]
    d = direction * d / np.linalg.norm(d) / w                  # back to u units, |w d| = 1
    cs = ContinuationSettings(step=float(step), step_min=1e-8, step_max=np.inf, max_angle=max_angle,
                              max_correction=max_correction)
    settings = ShootingSettings(steps_per_period=spp * factor, tol=tol, symmetric=False, reversible=False,
                                energy_max=float(energy_max), floquet=bool(floquet), integrator=integrator, freq_tol=None)
    engine = pseudo_arclength(problem, u_e + step * d, d, cs, tol)
    it = NNMIterator(model, branch.mode, problem, system, engine, settings, energy_max, max_points, cs, tol)
    others = [e for e in branch.events if e["kind"] in SWITCHABLE and "x0" in e]
    met, left, seen = None, False, 0
    for p in it:
        left = left or abs(p.energy / event["energy"] - 1) > 0.05
        # the new points and the folds located since the last point, against the parent's branch points
        near = [(p.energy, p.frequency_hz)] + [(e["energy"], e["frequency_hz"]) for e in it.events[seen:]]
        seen = len(it.events)
        if len(it.points) > 3:
            met = next((e for e in others for E, f in near if (e is not event or left)
                        and abs(E / e["energy"] - 1) < 2e-3 and abs(f / e["frequency_hz"] - 1) < 2e-4), None)
            if met is not None:
                it.cancel()
                break
    out = it.branch()
    where = f"{event['kind']} at E = {event['energy']:.6g} J, f = {event['frequency_hz']:.6g} Hz"
    out.name = f"{branch.name or f'NNM {branch.mode}'}: switched at {where}"
    if met is not None:
        out.status = "done"
        out.message = ("returns to the branch point it started from (a loop through the mirrored family)"
                       if met is event else
                       f"meets the parent family again at its {met['kind']} at E = {met['energy']:.6g} J, "
                       f"f = {met['frequency_hz']:.6g} Hz")
    out.message = f"family from the {where}: {out.message}"
    out.null_singular_values = sv[-3:].tolist()
    return out
