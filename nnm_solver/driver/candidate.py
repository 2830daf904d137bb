"""A converged orbit of the continuation while the branch iterator decides about it (iterator.py).

The public ``Point`` says what the orbit is; what the iterator needs about it meanwhile (the solve for its error
estimate, its harmonic content, the Krein locator's coordinates, the background multipliers) is held here, beside
it, and dropped when the point is kept (``release``): nothing private is hung on the Point.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from ..analysis.hb_series import series_restoring_ratio
from ..backbone.content import content_of
from ..backbone.settings import LabelSettings
from ..orbits import condensed_kernels as kernels
from ..orbits.spring_kernels import restoring_bound
from ..results.point import ModalState, Point
from ..results.settings import RESULTS
from ..results.stops import restoring_ratio
from ..stability.floquet import is_stable, sort_multipliers
from ..stability.settings import STABILITY

__all__ = ["Candidate", "record_candidate"]

#: the harmonics a point's content is measured on (content_of's default)
LABEL_HARMONICS = LabelSettings().label_harmonics


@dataclass
class Candidate:
    """A Point and the iterator's working data about it.

    solution : (problem, u, J, tangent, factor) of its converged solve, for its error estimate (None once kept);
    observed : (HarmonicContent, modal orbit Q) for its label and the tongue policy (None once kept);
    restoring : the smallest restoring-force ratio along the orbit (stops.py: the escape tests), or a lower bound
        of it where that bound is above both escape thresholds (``restoring_lower_bound``);
    restoring_bound : restoring is that lower bound, taken over samples that include the orbit's state at t = 0
        (a harmonic-balance orbit's): then the ratio at its turning point is above both thresholds too, and the
        iterator's escape test needs no ratio of its own there;
    collision : the Krein locator's coordinates at it (stability/krein.py), or None;
    spectrum : the background job computing its multipliers (problem.multipliers_later), or None once settled;
    disc_error : the time discretisation's part of point.freq_error (what finer steps reduce; NaN: none or not
        estimated);
    distance : (dev, tolerance) of its label's Verdict (backbone/labels.py: its relative frequency distance from the
        skeleton's family, dev None where no skeleton covers its energy), None where no label was judged (the
        mid-step check's policy, stability/locator.mid_step_check)."""

    point: Point
    solution: tuple | None = None
    observed: tuple | None = None
    restoring: float = 1.0
    restoring_bound: bool = False
    collision: Any = None
    spectrum: Callable | None = None
    disc_error: float = math.nan
    distance: tuple | None = None

    def release(self):
        """Drop the large working data (a solve's Jacobian and factorisation, O(n^2) each, and the orbit)."""
        self.solution = self.observed = self.spectrum = None


def record_candidate(cp, prob, system, model, mode, floquet, known=None, later=False):
    """The Candidate (the Point and the iterator's data about it) of a converged ContinuationPoint of the problem
    prob (modal system ``system`` of ``model``, 1-based ``mode``; multipliers when ``floquet``) and its modal state
    (q0, v0, T).  known : optional (sorted
    multipliers, collision coordinates) already computed at it (e.g. by event location).  later : the
    multipliers are computed in the worker threads (problem.multipliers_later, started by the engine driver);
    _settle waits for them."""
    sys_ = system
    q0, vq0, T = prob.state(cp.u)
    collision = job = None
    if floquet and later:     # started when the engine gave the point (EngineDriver.launch)
        job = getattr(cp, "spectrum", None) or prob.multipliers_later(cp.u, cp.tangent)
        mu, stable = np.full(2 * model.n, np.nan, dtype=complex), True
    elif floquet and known is not None:
        mu, collision = known
        stable = is_stable(mu, STABILITY.stability_tol)
    elif floquet:
        mu = sort_multipliers(prob.multipliers(cp.u, cp.tangent))
        stable = is_stable(mu, STABILITY.stability_tol)
        collision = getattr(prob, "collision", None)
    else:
        mu, stable = np.full(2 * model.n, np.nan, dtype=complex), True
    A = prob.coefficients(cp.u)
    Q = prob.modal_orbit(cp.u) if hasattr(prob, "modal_orbit") else None
    series = A is not None and getattr(prob, "basis", None) is not None   # harmonic balance: from its coefficients
    content = content_of(Q, mode - 1, LABEL_HARMONICS, series=(prob.basis, A) if series else None)
    restoring = 1.0 if Q is None else restoring_lower_bound(sys_, Q)
    bound = series and Q is not None    # Q's first sample is the state at t = 0 (basis.E's first row)
    if restoring <= max(RESULTS.escape_ratio, RESULTS.escape_ratio_failed):    # the escape tests need the ratio
        restoring = series_restoring_ratio(sys_, prob.basis, A, len(Q)) if series else restoring_ratio(sys_, Q)
        bound = False
    # the energy of the modal state (x = Phi q, Phi M-orthonormal, Phi^T K Phi = diag(omega2): the physical energy
    # to round-off) and the physical state only when it is read (results/point.py): nothing O(n^2) per point
    point = Point(energy=sys_.energy(q0, vq0), frequency_hz=float(1.0 / T), period=float(T), x0=None, v0=None,
                  floquet=mu, stable=stable, iterations=cp.iterations, label=content.label,
                  modal=ModalState(sys_.Phi, q0, vq0, A))
    point.steps = int(getattr(prob, "spp", 0))
    point.fundamental_share = content.share
    cand = Candidate(point, solution=(prob, cp.u, cp.jacobian, cp.tangent, cp.factor), observed=(content, Q),
                     restoring=restoring, restoring_bound=bound, collision=collision,
                     spectrum=job)
    return cand, (q0, vq0, T)


def restoring_lower_bound(system, Q):
    """A lower bound of the smallest restoring-force ratio of the modal orbit Q (samples, n) (stops.restoring_ratio):
    the ratio is at least q . res / q . lin = 1 + d . g(d) / q^T Omega^2 q at each sample (res = Omega^2 q + Bq^T
    g(Bq q), d = Bq q), so at least the smallest of these over the samples (at least 1 where the elements do
    non-negative work, d . g(d) >= 0: hardening springs); 0 where some q^T Omega^2 q is not positive.  O(S n n_s)
    for S samples: where it is above the escape thresholds (RESULTS.escape_ratio, escape_ratio_failed) the ratio
    itself (its Gram matrices and sample-wise sums, several times the cost) is not needed."""
    if kernels.AVAILABLE and not system.elements.coupled:      # springs: one compiled pass per sample
        return float(restoring_bound(np.ascontiguousarray(Q, dtype=float), system.Bq, system.omega2,
                                             system.powers, system.coefficients, system.kinks))
    d = Q @ system.Bq.T
    qlin = (Q * Q) @ system.omega2
    if not np.all(qlin > 0.0):
        return 0.0
    return float(np.min(1.0 + np.einsum("ts,ts->t", d, system.force(d)) / qlin))
