"""Shapes of orbits and the MAC between them (seed eq. 19).

``mass_mac(model, a, b)`` is the one MAC to compare shapes of a model: mass-weighted, so that two
distinct linear modes give exactly 0 whatever the coordinates (Craig-Bampton coordinates mix physical
boundary DOFs with fixed-interface modal amplitudes, and the plain dot product of such vectors is
meaningless: on assets/paris.h5 the mass-orthogonal linear modes 19 and 513 have a raw MAC of 0.96).
"""
from __future__ import annotations

import numpy as np

from ..errors import NNMInputError
from ..model.modal import modal_system
from ..model.reduction import mac, mass_mac  # noqa: F401  (mass_mac: this module's public name too)
from .harmonics import check_branch, harmonic_shape, orbit_samples

def orbit_shape(branch, i, kind="peak", samples=None):
    """Shape (n_dof,) of the orbit of point i.

    kind : "x0" the initial displacement (the paper's convention: at zero velocity for synchronous
    orbits); "peak" the configuration of largest mass-weighted norm over the period (equal to x0
    for the synchronous orbits that start at rest, robust when the continuation's phase condition put
    t = 0 elsewhere); "harmonic1" the real shape of the fundamental harmonic.
    """
    i = check_branch(branch, i)
    if kind == "x0":
        return branch.x0[i].copy()
    if kind == "harmonic1":
        return harmonic_shape(branch, i, 1)
    if kind == "peak":
        try:
            _, x = branch.motion(i, samples or orbit_samples(branch))
        except RuntimeError:  # the orbit cannot be integrated again (strongly unstable): its x0
            return branch.x0[i].copy()
        q = modal_system(branch.model).to_modal(np.asarray(x, dtype=float))
        return np.asarray(x[int(np.argmax(np.sum(q * q, axis=1)))], dtype=float)
    raise NNMInputError(f"kind must be 'x0', 'peak' or 'harmonic1', got {kind!r}")


def mac_orbits(branch_a, i, branch_b=None, j=None, kind="peak"):
    """Mass-weighted MAC (``mass_mac``) between the shapes of orbit i of branch_a and orbit j of
    branch_b (default: the same branch; both of the same model size).  kind: see ``orbit_shape``.
    Returns a float in 0..1."""
    if branch_b is None:
        branch_b = branch_a
    if j is None:
        raise NNMInputError("give the index j of the second orbit")
    if branch_a.model.n != branch_b.model.n:
        raise NNMInputError(f"the branches have {branch_a.model.n} and {branch_b.model.n} DOFs; "
                            f"MAC needs shapes of the same size")
    return mass_mac(branch_a.model, orbit_shape(branch_a, i, kind), orbit_shape(branch_b, j, kind))
