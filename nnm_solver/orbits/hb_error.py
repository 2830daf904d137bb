r"""The truncation error estimate of a converged harmonic-balance orbit (``Branch.freq_error`` of an HB branch).

A harmonic-balance orbit with harmonics up to H solves the equations of motion projected on those harmonics; the
forces' harmonics above H are dropped.  Its frequency differs from the exact orbit's by the truncation error, which
decays with H as fast as the orbit's harmonics do (spectrally for smooth laws).  The estimate is the change of the
frequency when two more harmonics are added (H + 2), at the same energy:

* the orbit u is embedded in the problem with harmonics up to H + 2 (the new coefficients zero): its residual there
  is, to round-off, the element forces' harmonics H + 1, H + 2 that the H-problem left out (and the corrector's
  leftover on the others);
* Newton steps of the larger problem with the energy held at the point's (the frequency error at a fixed energy,
  what the FEP shows); one where it is short (below).  Next to an energy fold, where the frequency at a fixed energy
  is not defined (fep_slope.py: the branch's slope in the FEP plane), one step orthogonal to the branch tangent, as
  the corrector takes it (as for shooting, shooting_error.py).  The steps are continuation/newton.py's, on the larger problem bordered by the energy row
  (``_AtTheEnergy``), with this estimate's own stopping rule (``_AtTheEnergy.settled``).

The frequency moved by the steps estimates |f_H - f_(H+2)| / f, the error of f_H wherever the harmonics decay
(f_(H+2) being much nearer the exact one).  Against the frequency with 3H harmonics at the same energy (an
independent fixed-energy Newton solve) the estimate is 0.97-1.0 of the error on a 2-DOF backbone (H = 5), 1.01-1.03
on a 6-DOF chain (H = 7), and on NLvib's examples 0.92-1.0 (04, the 2-DOF, H = 7) and 0.98-1.1 (09, the beam, H = 5)
except where the error changes sign along the branch (tests/test_hb_error.py, benchmarks/README.md).  Where the
harmonics decay slowly f_(H+2) is not much nearer and the estimate falls short: 0.7-0.8 of the error against
Gauss-6 shooting on a 3-DOF chain at H = 9 whose frequency has risen 2.2-fold.  For non-smooth laws (a clearance)
it is unreliable both ways (0.3-4 of the error against 31 harmonics).

One Newton step is enough where it is short (ORBITS.error_one_step; a second one moves the estimate by 0.07 % of itself
at the median on the ECL beam, at most 9 %); next to a new harmonic near a mode's frequency the larger problem is far
from linear and the steps go on until the frequency settles (the ECL beam at H = 5: a first step gives 0.24 of the
converged H + 2 change).  Where they do not settle, or end away from the point's energy, the larger problem has no
solution near the orbit (inside a tongue the truncation does not resolve) and the estimate is inf.  What the
estimate cannot see: a k:1 internal resonance with k above H + 2, whose narrow tongue the truncated orbit steps over
(the beam near 0.04 J: the frequency with 15 harmonics differs by 2.6e-4 where H + 2 says 6e-6).  Cost: one Jacobian
and one factorisation of the larger problem per point (a few next to a resonant harmonic); the corrector reuses its
factorisation, so this is about 2x a corrector's factorisation at H = 7 ((N_b + 1)^3 / N_b^3 of it).
"""
from __future__ import annotations

import math

import numpy as np

from ..continuation.engine import LeastSquares, stacked
from ..continuation.newton import NOT_FINITE, SINGULAR, NewtonSettings, newton_solve
from .fep_slope import at_energy_fold
from .hb_basis import HBBasis, harmonics_in
from .settings import ORBITS

__all__ = ["HBTruncationError", "EXTRA_HARMONICS"]

#: an alias of settings.py's ORBITS.error_extra_harmonics (the code reads that)
EXTRA_HARMONICS = ORBITS.error_extra_harmonics


class HBTruncationError:
    """``frequency_error`` for the harmonic-balance problems (HBProblem, CondensedHBProblem), whose unknowns are
    [coefficients (N_b, width) ; tail] with the frequency omega / w_r last.  Attributes used: basis, nb, scale,
    jacobian, energy, energy_gradient, ``with_basis(basis)`` (the same problem with another basis) and ``_width``
    (columns of the coefficient block)."""

    def _larger(self):
        """The same problem with ORBITS.error_extra_harmonics more harmonics (made once), sampled at least as densely
        per harmonic as this one (a user's ``samples`` against aliasing of non-polynomial laws)."""
        big = getattr(self, "_larger_problem", None)
        if big is None:
            H, N = self.basis.harmonics, self.basis.samples
            H2 = H + ORBITS.error_extra_harmonics
            big = self.with_basis(HBBasis(H2, self.basis.kind, max(4 * H2 + 4, math.ceil(N * H2 / H))))
            self._larger_problem = big
        return big

    def with_harmonics(self, harmonics):
        """The same problem with ``harmonics`` harmonics, sampled at least as densely per harmonic as this one (the
        branch's refinement to its freq_tol, driver/refinement.py), with this one's phase reference."""
        H, N = self.basis.harmonics, self.basis.samples
        finer = self.with_basis(HBBasis(harmonics, self.basis.kind, max(4 * harmonics + 4, math.ceil(N * harmonics / H))))
        if getattr(self, "q_ref", None) is not None:
            finer.q_ref = self.q_ref
        return finer

    def embedded(self, other, u):
        """u (or a direction) of this problem as a vector of ``other`` (the same problem with more harmonics)."""
        return self._embed(other, u)

    def _embed(self, big, u):
        """u (or a direction) of this problem as a vector of the larger problem ``big``: the coefficients on the
        harmonics both have, zero on the new ones, the tail unchanged (the rows of a 2-D u: several vectors at once)."""
        u = np.asarray(u)
        target, source, n2 = self._embedding(big, u.shape[-1])
        out = np.zeros(u.shape[:-1] + (n2,))
        out[..., target] = u[..., source]
        return out

    def _embedding(self, big, n):
        """(target, source, n2): u2[target] = u[source] embeds a vector u (length n) of this problem in ``big``'s
        (length n2), its other entries zero: ``harmonics_in``'s rows of the coefficient block, then the tail.  Made once
        per larger problem (the truncation estimate embeds two vectors a point)."""
        kept = getattr(self, "_embedding_in", None)
        if kept is not None and kept[0] is big and kept[1] == n:
            return kept[2]
        width, k = self._width, self.nb * self._width
        # the source row of each of big's rows (-1: a function this basis has not)
        rows = harmonics_in(big.basis, self.basis, np.arange(1.0, self.nb + 1)[:, None])[:, 0].astype(int) - 1
        j2 = np.flatnonzero(rows >= 0)
        target = (j2[:, None] * width + np.arange(width)).ravel()
        source = (rows[j2][:, None] * width + np.arange(width)).ravel()
        k2 = len(big.basis) * width
        made = (np.concatenate([target, k2 + np.arange(n - k)]), np.concatenate([source, np.arange(k, n)]),
                k2 + n - k)
        self._embedding_in = (big, n, made)
        return made

    def frequency_error(self, u, J, tangent, factor=None):
        """Estimated relative error of the frequency of the converged orbit u from the truncation of the harmonics:
        (error, NaN), the second item being the time discretisation's part of shooting's estimate, which harmonic
        balance has not (the driver then locates events to its finest tolerance, as without an estimate).  J and
        factor (the corrector's) are not needed (module docstring).  The error is inf where the larger problem has
        no solution near the orbit (its Newton steps do not settle: the truncation does not resolve the orbit, e.g.
        inside an internal-resonance tongue at too few harmonics), NaN where a step cannot be solved."""
        big = self._larger()
        if getattr(self, "q_ref", None) is not None:
            big.q_ref = self.q_ref      # the phase condition's reference (full basis): the engine's accept() has set
                                        # it to this orbit's own shape, which the larger orbit keeps
        u2, t2 = self._embed(big, np.stack([u, tangent]))
        E0 = self.energy(u)        # the point's (a condensed problem's energy of u2 is not it: its eliminated
                                   # amplitudes see the new harmonics' forces)
        bordered = _AtTheEnergy(big, E0, t2)
        try:
            with np.errstate(all="ignore"):
                res = newton_solve(bordered, u2,
                                   NewtonSettings(tol=0.0, max_iter=ORBITS.error_max_steps, positive_last=False),
                                   stop=bordered.settled(u2), linear=_least_squares)
        except (np.linalg.LinAlgError, ValueError):      # (from the problem's own evaluations)
            return float("nan"), float("nan")
        if res.reason in (SINGULAR, NOT_FINITE):
            return float("nan"), float("nan")
        err = abs(res.u[-1] / u2[-1] - 1.0)
        if not np.isfinite(err):
            return float("nan"), float("nan")
        if not res.converged or (not bordered.fold
                                 and abs(big.energy(res.u) / E0 - 1.0) > ORBITS.error_unsettled_energy):
            return float("inf"), float("nan")
        return float(err), float("nan")


def _norm(x):
    """|x| of a 1-D float array: sqrt(x . x), np.linalg.norm's number without its dispatch."""
    return math.sqrt(float(x.dot(x)))


def _least_squares(J, b):
    """The engine's least-squares solve (QR, or LU when square) of the bordered system."""
    return LeastSquares(np.asfortranarray(J)).solve(b)


class _AtTheEnergy:
    """The larger problem ``big`` bordered by one row, for continuation.newton: Newton on [equations; energy - E0]
    (the frequency error at the point's energy), or next to an energy fold (the energy's rate along the embedded
    branch tangent t2 within fep_slope.FOLD_SLOPE of vertical in the FEP plane) the step orthogonal to t2 in the
    balanced norm.  ``fold`` : the last
    iterate's choice; ``settled(u2)`` : the stopping rule (module docstring)."""

    def __init__(self, big, E0, t2):
        self.big, self.E0, self.t2 = big, E0, t2
        self.fold = False
        self.w = None

    def jacobian(self, v):
        big = self.big
        r2, J2 = big.jacobian(v)
        self.w = w = big.scale(v)
        both = getattr(big, "energy_and_gradient", None)
        E, g = both(v) if both is not None else (None, big.energy_gradient(v))
        self.fold = at_energy_fold(g @ self.t2 / self.E0, self.t2[-1] / v[-1])
        if self.fold:          # the step orthogonal to the branch tangent (the hyperplane through v)
            return np.append(r2, 0.0), stacked(J2, w * w * self.t2)
        return np.append(r2, (big.energy(v) if E is None else E) - self.E0), stacked(J2, g)

    def residual(self, v):
        return self.jacobian(v)[0]

    def error(self, v, r):
        return self.big.error(v, r)

    def settled(self, u2):
        """The stopping rule: after a step next to a fold (taken once), or a first step shorter than
        ORBITS.error_one_step (its own error is of the order of its square), or a later step that moved the frequency by
        at most ORBITS.error_settled of its change from u2."""
        def stop(k, v, du, v_new):
            if self.fold:
                return "next to an energy fold: one step orthogonal to the branch"
            if k == 0 and _norm(self.w * du) < ORBITS.error_one_step:
                return "a short first step"
            if k > 0 and abs(v_new[-1] - v[-1]) <= ORBITS.error_settled * abs(v_new[-1] - u2[-1]):
                return "the frequency settled"
            return ""
        return stop
