r"""One orbit of the backbone family at a fixed modal amplitude of the followed mode (condensed harmonic balance,
orbits/condensed_hb.py): its Newton solve, and the shares that tell a partner mode's part of it (the skeleton's
stepping, amplitude_family.py, and its one-harmonic guide, family_guide.py)."""
from __future__ import annotations

import numpy as np

from ..continuation.newton import newton

__all__ = ["solve_at_amplitude", "family_share", "fundamental_shares"]


def solve_at_amplitude(prob, u, tol=1e-10, iterations=30):
    """Solve the condensed HB equations at the fixed modal amplitude held in u (Newton on all the other
    unknowns, continuation/newton.py); the solution or None."""
    nD = prob.nb * prob.ns
    return newton(prob, u, np.r_[0:nD, nD + 1], tol, iterations)


def fundamental_shares(prob, u):
    """The modes' shares of the orbit u's fundamental (h = 1), sum over cos and sin of A^2 normalised: at a
    1:1 internal resonance another mode takes the followed one's."""
    A = prob.amplitudes(u)[0][prob.basis.h == 1]
    W = (A ** 2).sum(axis=0)
    return W / max(W.sum(), 1e-300)


def family_share(prob, u):
    """1 - the share of the other modes' higher harmonics (k >= 2) in the orbit u, velocity-weighted
    (sum (h_j A_jk)^2 over those / over all): what a partner mode takes from the followed one.  A change of
    shape at the fundamental, or the followed mode's own harmonics (an anharmonic orbit near a saddle), are
    the family's own."""
    A = prob.amplitudes(u)[0]
    h = prob.basis.h
    W = (h[:, None] * A) ** 2
    partner = W[h >= 2].sum() - W[h >= 2, prob.r].sum()
    return float(1.0 - partner / max(W.sum(), 1e-300))
