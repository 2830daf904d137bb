r"""The nonlinear elements of a model as one table, evaluated together on their deformations d = B x.

``ElementSet`` stores the laws as a table (powers (P,), coefficients (n_s, P), kinks (n_s, J, 3 or 4)),
kinks[s, j] = (dk, b, w[, side]) (dk = 0: unused row; J = 0 when no element has kinks, so the polynomial
path costs what it did; the fourth column only when some kink is one-sided, laws.py) that the numba-compiled kernels ``law_force`` / ``law_force_tangent``
evaluate; numpy callers use ``ElementSet.force``, ``tangent`` and ``potential``.  A set whose
powers are all odd and no one-sided kink gives an odd f_nl (f_nl(-x) = -f_nl(x)): its NNMs are
half-wave symmetric, which the shooting exploits.  An asymmetric ``PiecewiseLinearSpring`` (tension
!= compression) has one-sided kinks, kinks[s, j] = (dk, b, w, +1) for d > 0 and (dk, b, w, -1) for
d < 0: each side's law is that of an odd spring restricted to that side.

Coupled elements (``coupled.PolynomialStiffness``: one force on m deformations at once) follow the springs in the
deformation vector: rows n_springs.. of B are their m rows each (zero rows of the scalar table).  ``force`` and
``potential`` include them (an element's potential sits on its first row), ``tangent`` is the diagonal part g'
of the springs only (0 on coupled rows) and ``coupled_tangents`` the coupled blocks; ``coupled`` says whether
there are any (then the time integrators take their general kernels, integrators/general.py).
"""
from __future__ import annotations

import numpy as np

from .coupled import PolynomialStiffness, coupled_groups, coupled_table
from .elements import element_law
from .laws import ramp_integral, sigmoid, softplus

__all__ = ["ElementSet"]


class ElementSet:
    """The nonlinear elements of a model, evaluated together on their deformations d = B x.

    B (n_s, n) selection matrix; powers (P,) int64 and coefficients (n_s, P) float of the polynomial
    force laws; kinks (n_s, J, 3 or 4) float (dk, b, w[, side]) of the regularised piecewise-linear laws; k0 (n_s,)
    the elements' linear stiffnesses (part of the linear model, not of g).  ``force``, ``tangent`` and
    ``potential`` take d (..., n_s) and return (..., n_s) in N, N/m and J.
    """

    def __init__(self, elements, n):
        self.elements = list(elements)
        self.n = int(n)
        springs = [e for e in self.elements if not isinstance(e, PolynomialStiffness)]
        coupled = [e for e in self.elements if isinstance(e, PolynomialStiffness)]
        self.n_springs = len(springs)
        rows = [np.zeros((0, self.n))] + [e.matrix(self.n) for e in coupled]
        ns = self.n_springs + sum(len(r) for r in rows)          # rows of B: springs, then coupled deformations
        self.B = np.zeros((ns, self.n))
        for s, e in enumerate(springs):
            self.B[s, e.dof] = 1.0
            if e.other is not None:
                self.B[s, e.other] = -1.0
        self.B[self.n_springs:] = np.vstack(rows)
        self.groups = coupled_groups(coupled, self.n_springs)
        self.table = coupled_table(coupled, self.n_springs)
        self.coupled_odd = all(e.odd for e in coupled)
        laws = [element_law(e) for e in springs] + [{}] * (ns - self.n_springs)
        self.powers = np.array(sorted({p for law in laws for p in law}) or [3], dtype=np.int64)
        self.coefficients = np.zeros((ns, len(self.powers)))
        for s, law in enumerate(laws):
            for p, c in law.items():
                self.coefficients[s, int(np.flatnonzero(self.powers == p)[0])] = c
        kinks = [e.kinks() if hasattr(e, "kinks") else [] for e in springs] + [[]] * (ns - self.n_springs)
        cols = 4 if any(len(row) > 3 for ks in kinks for row in ks) else 3     # side column: one-sided kinks only
        self.kinks = np.zeros((ns, max((len(k) for k in kinks), default=0), cols))
        for s, ks in enumerate(kinks):
            for j, row in enumerate(ks):
                self.kinks[s, j, :len(row)] = row
        self.k0 = np.array([getattr(e, "linear_stiffness", 0.0) for e in springs] + [0.0] * (ns - self.n_springs),
                           dtype=float)

    @property
    def coupled(self):
        """True when some element couples several deformations (PolynomialStiffness)."""
        return bool(self.groups)

    @property
    def cubic_only(self):
        """True when every force law is a pure cubic (the exact scaling law applies)."""
        used = np.any(self.coefficients != 0.0, axis=0)
        return not self.coupled and not np.any(self.kinks[..., 0] != 0.0) and set(self.powers[used].tolist()) <= {3}

    def __len__(self):
        return len(self.elements)

    @property
    def odd(self):
        """True when every force law is odd (only odd powers, no one-sided kink): f_nl(-x) = -f_nl(x)."""
        used = np.any(self.coefficients != 0.0, axis=0)
        one_sided = self.kinks.shape[2] > 3 and np.any((self.kinks[..., 0] != 0.0) & (self.kinks[..., 3] != 0.0))
        return bool(np.all(self.powers[used] % 2 == 1)) and not one_sided and self.coupled_odd

    def force(self, d):
        d = np.asarray(d, dtype=float)
        g = sum(self.coefficients[:, j] * d ** p for j, p in enumerate(self.powers))
        for dk, b, w, up, down in self._kink_columns():
            g = g + dk * (up * softplus(d - b, w) - down * softplus(-d - b, w))
        return self._with_coupled(g, d, "force")

    def tangent(self, d):
        d = np.asarray(d, dtype=float)
        t = sum(p * self.coefficients[:, j] * d ** (p - 1) for j, p in enumerate(self.powers))
        for dk, b, w, up, down in self._kink_columns():
            t = t + dk * (up * sigmoid(d - b, w) + down * sigmoid(-d - b, w))
        return t

    def potential(self, d):
        d = np.asarray(d, dtype=float)
        P = sum(self.coefficients[:, j] * d ** (p + 1) / (p + 1) for j, p in enumerate(self.powers))
        for dk, b, w, up, down in self._kink_columns():
            R0 = ramp_integral(-b, w)
            P = P + dk * (up * (ramp_integral(d - b, w) - R0) + down * (ramp_integral(-d - b, w) - R0))
        return self._with_coupled(P, d, "potential")

    def abs_potential(self, d):
        """Bound on |potential| (..., n_s): every coefficient and slope jump taken positive, kinks on both sides."""
        d = np.abs(np.asarray(d, dtype=float))
        P = sum(np.abs(self.coefficients[:, j]) * d ** (p + 1) / (p + 1) for j, p in enumerate(self.powers))
        for dk, b, w, _, _ in self._kink_columns():
            P = P + np.abs(dk) * (ramp_integral(d - b, w) + ramp_integral(-d - b, w) - 2.0 * ramp_integral(-b, w))
        return self._with_coupled(P, d, "abs_potential")

    def _with_coupled(self, out, d, what):
        """``out`` (..., n_d) of the springs with the coupled elements' force (on their rows) or potential (on
        each element's first row) added."""
        if not self.groups:
            return out
        out = np.array(np.broadcast_to(out, d.shape), dtype=float)
        for grp in self.groups:
            if what == "force":
                out[..., grp.rows] = grp.force(d)
            else:
                out[..., grp.rows[:, 0]] = getattr(grp, what)(d)
        return out

    def coupled_tangents(self, d):
        """[(rows (G, m), T (..., G, m, m))] per coupled group: the tangent blocks dg/dd (N/m) at d (..., n_d)."""
        d = np.asarray(d, dtype=float)
        return [(grp.rows, grp.tangent(d)) for grp in self.groups]

    def _kink_columns(self):
        """(dk, b, w, up, down) (n_s,) each, per kink column j: up/down = 1.0 where the kink acts for
        d > 0 / d < 0 (side >= 0 / side <= 0), else 0.0 (unused rows: dk = 0, w = 1)."""
        for j in range(self.kinks.shape[1]):
            dk, b, w = self.kinks[:, j, :3].T
            side = self.kinks[:, j, 3] if self.kinks.shape[2] > 3 else np.zeros_like(dk)
            yield dk, b, np.where(w > 0, w, 1.0), (side >= 0).astype(float), (side <= 0).astype(float)

    def in_basis(self, Phi):
        """(B Phi, powers, coefficients, kinks): the table for coordinates q with x = Phi q (kernels' input)."""
        return (np.ascontiguousarray(self.B @ Phi), np.ascontiguousarray(self.powers),
                np.ascontiguousarray(self.coefficients), np.ascontiguousarray(self.kinks))
