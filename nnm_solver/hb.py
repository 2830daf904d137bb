r"""NNM branches by harmonic balance (HB): a second method, independent of shooting/Newmark.

Model (SI units): M x'' + K x + B^T g(B x) = 0, x (m), g the element force laws (N), d = B x the spring
deformations (m).  A periodic orbit of angular frequency omega (rad/s, period T = 2 pi / omega s)
is written as a truncated Fourier series in mass-normalised modal coordinates (x = Phi q):

    x(t) = Phi sum_j A[j] c_j(omega t),   c_j = cos(h_j theta) [or sin(h_j theta)],

and the equations of motion are balanced harmonic by harmonic (Galerkin):

    (Omega^2 - h_j^2 omega^2) A[j] + F[j](A) = 0,   F = P [k3 (E A Bq^T)^3] Bq   (AFT)

E / P: sampling of the basis at N equispaced instants / its projector, Bq = B Phi.  The
nonlinear forces are evaluated in the time domain on the n_s spring deformations only; the
Jacobian is analytic (chain rule through E and P).  Details and the Jacobian: ``orbits/harmonic_balance.py``.

Basis (``basis=``):
  * ``"odd"`` (default): cosines of the odd harmonics h = 1, 3, ..., <= ``harmonics``.  The
    NNMs that continue a linear mode of a model with odd (cubic) springs are symmetric,
    x(-t) = x(t) and x(t + T/2) = -x(t), so this basis is exact for them; t = 0 is an instant of
    zero velocity (v0 = 0) and no phase condition is needed.
  * ``"full"``: mean + cosines and sines of h = 1..``harmonics`` for general periodic orbits, with
    the phase condition <q_ref, q'(0)> = 0 (q_ref: shape of the previous point), as in shooting.

Unknowns u = [A (sqrt(kg) m) ; omega / w_r]; no amplitude normalisation: the pseudo-arclength
engine (continuation.py) adds the arclength row.  Convergence: ||R|| / (w_r^2 ||A||) < tol.
HB converges exponentially in the number of harmonics for these analytic orbits; ``branch.freq_error`` estimates
each point's truncation error (the frequency's change at the same energy with two harmonics more, by Newton steps
of that larger problem: ``orbits/hb_error.py``; ``error_estimate=False`` turns it off).

Each point's energy (J) is ``model.energy(x(0), v(0))``.  Floquet multipliers come from Hill's
method (``orbits/hill.py``: the quadratic eigenproblem of the perturbations in the full basis of the
same highest harmonic), stability flags and events as for shooting (``floquet.py``).
"""
from __future__ import annotations

import numpy as np

from .driver.api import continue_nnm
from .driver.problems import HILL_AUTO_SIZE
from .errors import NNMInputError
from .results.settings import HarmonicBalanceSettings

__all__ = ["continue_nnm_hb", "hb_coefficients", "hb_motion", "HILL_AUTO_SIZE"]


def continue_nnm_hb(model, mode, energy_max, harmonics=7, samples=None, tol=1e-8, max_points=500, on_point=None,
                    stop=None, energy_min=None, basis=None, step=None, max_angle=0.35, max_correction=0.5,
                    max_rel_step=0.4, floquet=None, tongues=None):
    """NNM branch of linear mode ``mode`` (1-based) by harmonic balance, from low energy to ``energy_max`` (J).

    The same as ``continue_nnm(..., method="hb")``.

    Parameters
    ----------
    harmonics : highest harmonic order kept (``basis="odd"``: orders 1, 3, ..., <= harmonics).
    samples : time samples per period for AFT (default 4*harmonics + 4: exact for cubic springs).
    tol : relative residual tolerance of the harmonic-balance equations.
    basis : ``"odd"`` (cosines of odd harmonics, symmetric NNMs) or ``"full"`` (see module doc);
        default: "odd" when every element's force is odd, else "full".
    max_points, on_point, stop, energy_min, step, max_angle, max_correction, tongues : as ``continue_nnm``.
    floquet : Floquet multipliers by Hill's method (True), not (False: NaN, all stable), or when the
        Hill matrix 2 n (2 harmonics + 1) has at most HILL_AUTO_SIZE rows (None); cost O(size^3) a point.

    Returns a Branch (settings.method = "harmonic_balance") whose ``coefficients`` column holds
    the Fourier coefficients of each point (also ``hb_coefficients(branch, i)``).
    """
    return continue_nnm(model, mode, energy_max, tol=tol, max_points=max_points, on_point=on_point, stop=stop,
                        energy_min=energy_min, floquet=floquet, step=step, max_angle=max_angle,
                        max_correction=max_correction, max_rel_step=max_rel_step, method="hb",
                        harmonics=harmonics, samples=samples, basis=basis, tongues=tongues)


def _hb_settings(branch):
    s = branch.settings
    if not isinstance(s, HarmonicBalanceSettings):
        raise NNMInputError(f"the branch was computed by {s.method!r}, "
                            f"not by harmonic balance (nnm_solver.hb.continue_nnm_hb)")
    return s


def hb_coefficients(branch, i):
    """Fourier coefficients of point i of an HB branch: (orders (N_b,), sine (N_b,) bool, X (N_b, n) m).

    x(t) = sum_j X[j] * (sin if sine[j] else cos)(orders[j] * 2 pi t / period).  Stored with the
    branch; recomputed for branches of first-release files (see
    orbits.harmonic_balance.recover_coefficients).
    """
    basis = _hb_settings(branch).hb_basis()
    return basis.h.copy(), basis.sine.copy(), np.array(branch.coefficients_at(i))


def hb_motion(branch, i, samples=256):
    """Orbit of point i of an HB branch from its Fourier series: (t (samples,) s, x, v (samples, n) m, m/s)."""
    _hb_settings(branch)
    return branch.orbit(i, samples)
