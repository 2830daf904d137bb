"""The frequency error estimate of a converged shooting orbit (step doubling plus the corrector's tolerance).

``ShootingProblem`` inherits ``frequency_error``; the driver stores its result with every point
(``Branch.freq_error``) and refines the time step where it exceeds ``freq_tol`` (iterator.py).
"""
from __future__ import annotations

import numpy as np

from ..continuation.engine import LeastSquares, stacked
from .fep_slope import at_energy_fold

__all__ = ["ShootingError"]


class ShootingError:
    """Frequency error estimate of a ShootingProblem's converged orbit (attributes used: integrator, sys, nsteps,
    T_r, unpack, scale, energy_gradient, _h, _assemble, _last_residual)."""

    def frequency_error(self, u, J, tangent, factor=None):
        """Estimated relative error of the frequency of the converged orbit u: (total, discretisation).

        The discrete orbit's frequency minus the exact one, relative.  Two parts, both from one Newton
        step with the Jacobian J of the converged point:
        - the time discretisation, by step doubling: the shooting residual with half the step (2N steps
          per period) minus the residual with N steps moves the period by dT = T_N/2 - T_N to first order,
          and with the scheme's order p, T_N - T_exact = -dT 2^p / (2^p - 1) (Richardson);
        - the corrector's tolerance: the step that the residual left at convergence would still make.
        The step is taken across the branch (as the corrector does); the discretisation's part is then moved along
        the branch back to the point's energy, so that the estimate is the frequency error at a fixed energy,
        what the FEP shows.  Next to an energy fold (fep_slope.py: the tangent nearly vertical in the FEP
        plane), where the frequency at a fixed energy is not defined, the orthogonal step is kept:
        the distance between the discrete and the exact branch.  Cost: two state sweeps (N and 2N steps)
        and one factorisation of the corrector's size (``factor``: the continuation's factorisation of
        [J; previous tangent], reused away from folds).  NaN if an integration fails.
        """
        q0, v0, T = self.unpack(u)
        q, v, ok = self.integrator.state(self.sys, q0, v0, 0.5 * self._h(T), 2 * self.nsteps)
        if not ok:
            return float("nan"), float("nan")
        r_f = self._assemble(q, v, q0, v0)
        last = getattr(self, "_last_residual", None)
        if last is not None and np.array_equal(last[0], u):
            r_c = last[1]                          # the residual of the Jacobian evaluation at u
        else:
            qc, vc, okc = self.integrator.state(self.sys, q0, v0, self._h(T), self.nsteps)
            if not okc:
                return float("nan"), float("nan")
            r_c = self._assemble(qc, vc, q0, v0)
        w = self.scale(u)
        g = self.energy_gradient(u)
        gp = g @ tangent
        fold = at_energy_fold(gp / self.energy(u), tangent[-1] / u[-1])     # u[-1] = T / T_r
        # the step is taken with a row transversal to the tangent (the continuation's factorisation of [J; previous
        # tangent] where given, else the orthogonal one); the time discretisation's part (an offset of the whole
        # branch) is then moved along the tangent to the point's energy, except at a fold; the corrector's part (a
        # leftover of this point's Newton solve, which its next step would remove across the branch) is not: near a
        # fold the move would magnify it without bound (the 2-DOF's fold at 4681 J: 1e-4 from a 1e-6 tolerance)
        A = factor if factor is not None else LeastSquares(stacked(J, w * w * tangent))

        def period_step(r, to_energy):
            du = A.solve(np.r_[-r, 0.0])
            if to_energy and not fold:           # move along the branch back to the point's energy
                du = du - (g @ du) / gp * tangent
            return du[-1] * self.T_r / T

        p = self.integrator.order
        disc = period_step(r_f - r_c, True) * 2 ** p / (2 ** p - 1)
        conv = period_step(r_c, False)
        return float(abs(disc + conv)), float(abs(disc))
