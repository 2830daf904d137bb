"""A tongue as its own branch: ``continue_tongue`` restarts the shooting continuation at the entry orbit that a
``tongues="skip"`` backbone recorded (``branch.tongues``), follows the internal-resonance tongue through its
turning points and stops where it is back on the backbone (above the entry, or below it when the tongue is a loop
off the backbone), closes a loop, or reaches its energy limit.
"""
from __future__ import annotations

import numpy as np

from ..backbone.settings import Follow, TongueBranchSettings
from ..errors import NNMInputError
from ..results.branch import Point
from .api import check_family_start, check_limits, check_max_points, iter_nnm
from .problems import integrator_and_steps

__all__ = ["continue_tongue", "tongue_arguments"]


def _on_backbone(branch, p, rtol):
    """Does point ``p`` lie on the backbone ``branch``'s frequency-energy curve (within rtol, relative), inside
    the backbone's energy range?"""
    E, f = np.asarray(branch.energy, float), np.asarray(branch.frequency_hz, float)
    order = np.argsort(E)
    E, f = E[order], f[order]
    if not (E[0] <= p.energy <= E[-1]) or np.any(np.diff(E) <= 0):
        return False
    f_b = np.interp(np.log(p.energy), np.log(E), f)
    return abs(p.frequency_hz - f_b) <= rtol * f_b


def tongue_arguments(branch, tongue, energy_max=None, *, max_points=None, tol=None, steps_per_period=None,
                     integrator=None):
    """(the tongue record, energy_max J, tol) of the branch ``continue_tongue`` starts at ``tongue`` of ``branch``
    (one of branch.tongues or its index): energy_max None is 100 x the entry energy, tol None the backbone's own,
    max_points None continue_tongue's default.  NNMInputError (one line), before any computation, for a record no
    tongue branch starts from, a backbone not computed by shooting, energy_max, tol or max_points that continue_nnm
    refuses (api.check_limits, api.check_max_points), or energy_max (J) not above the tongue's entry energy
    (api.check_family_start: the tongue may dip below its entry, but energy_max is the continuation's ceiling), or
    an integrator or steps_per_period shooting refuses (problems.integrator_and_steps)."""
    tongue = branch.pick("tongues", tongue)
    if tongue.get("family_end"):
        raise NNMInputError(f"this record marks where the backbone family ends ({tongue.get('note', '')}): there is "
                            f"no tongue branch to start from it")
    if "entry_x0" not in tongue:
        raise NNMInputError("tongue must be one of branch.tongues (from continue_nnm(..., tongues='skip'))")
    s = branch.settings
    if s.method != "shooting":
        raise NNMInputError("continue_tongue needs a shooting branch (tongues are passed by shooting backbones)")
    E_in = float(tongue["entry_energy"])
    energy_max = 100 * E_in if energy_max is None else energy_max
    tol = s.tol if tol is None else tol
    check_limits(energy_max, tol)
    if max_points is not None:                 # (None: not given, continue_tongue's default)
        check_max_points(max_points)
    check_family_start(energy_max, E_in, f"the {tongue.get('label', 'tongue')}'s entry orbit")
    if steps_per_period is not None or integrator is not None:      # (None: the backbone's own)
        integrator_and_steps(integrator if integrator is not None else s.integrator,
                             steps_per_period if steps_per_period is not None else s.steps_per_period)
    return tongue, energy_max, tol


def continue_tongue(branch, tongue, energy_max=None, max_points=500, *, settings=TongueBranchSettings(), **options):
    """The internal-resonance tongue ``tongue`` (one of ``branch.tongues``, or its index) as its own branch.

    branch : a backbone computed with ``continue_nnm(..., tongues="skip")`` (shooting).  The
    continuation restarts at the tongue's entry orbit, heads into the tongue and follows it through
    its turning points until it is back on the backbone above the entry energy (message: where), back on
    it below the entry (settings.back_on_backbone points descending: the tongue is a loop off the backbone), closes
    a loop, or reaches energy_max (default: 100 x the entry energy).  Points are labelled by their
    harmonic content; the branch is named after the tongue.  Options as ``continue_nnm`` (the
    branch's own steps_per_period, symmetric and tol are the defaults); settings : TongueBranchSettings
    (backbone/settings.py).  energy_max must lie above the entry energy (the tongue may dip below its entry, but
    the continuation stops at its first orbit at or above energy_max); it, tol and max_points are checked as
    ``continue_nnm`` checks them, before any computation (``tongue_arguments``).
    """
    tongue, energy_max, tol = tongue_arguments(branch, tongue, energy_max, max_points=max_points,
                                               tol=options.pop("tol", None))
    s = branch.settings
    for key in ("steps_per_period", "symmetric", "integrator"):
        options.setdefault(key, getattr(s, key))
    E_in = float(tongue["entry_energy"])
    start = ((np.asarray(tongue["entry_x0"]), np.asarray(tongue["entry_v0"]), tongue["entry_period"]),
             (np.asarray(tongue["inside_x0"]), np.asarray(tongue["inside_v0"]), tongue["inside_period"]))
    # the tongue is followed whatever its order (Follow's max_order applies to departures from a backbone)
    it = iter_nnm(branch.model, branch.mode, energy_max, "shooting", tol=tol, max_points=max_points,
                  tongues=Follow(max_order=None), _start=start, **options)
    last, inside, in_tongue, below = E_in, False, False, 0
    for p in it:
        inside = inside or p.label != "backbone" or p.energy < 0.99 * E_in
        in_tongue = in_tongue or p.label != "backbone"
        if inside and p.energy > E_in and p.energy > last and p.label == "backbone":
            it.cancel(f"back on the backbone at E = {p.energy:.6g} J, f = {p.frequency_hz:.6g} Hz, above the "
                      f"tongue's entry at {E_in:.6g} J")
            break
        # a tongue that closes back onto the backbone below its entry: the continuation would retrace the backbone
        # down to the linear mode; stop after settings.back_on_backbone such points
        below = below + 1 if (in_tongue and p.label == "backbone" and p.energy < E_in and p.energy < last
                              and _on_backbone(branch, p, settings.on_backbone_rtol)) else 0
        if below >= settings.back_on_backbone:
            it.cancel(f"the tongue closes back onto the backbone below its entry (at E = {p.energy:.6g} J, "
                      f"f = {p.frequency_hz:.6g} Hz; entry {E_in:.6g} J): a loop off the backbone")
            break
        last = p.energy
    out = it.branch()
    if out.status == "cancelled":
        out.status = "done"
    ratio = f"{tongue['order']}:1"
    out.name = f"{branch.name or f'NNM {branch.mode}'}: {ratio} tongue at {tongue['entry_frequency_hz']:.6g} Hz"
    return out
