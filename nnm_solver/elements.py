r"""Nonlinear elements: the forces f_nl(x) of  M x'' + K x + f_nl(x) = 0, each defined once.

Every element acts on one scalar deformation d = x[dof] (grounded) or d = x[dof] - x[other]
(relative), i.e. d = B x with one row of B, and returns a restoring force g(d) (N) along that
deformation; the model force is  f_nl(x) = B^T g(B x)  and the potential  V(x) = sum_s P_s(d_s),
P' = g.  The time integrators, harmonic balance, Hill's method and the model's energy all evaluate
the elements through ``ElementSet``, so a new element is added here and nowhere else.

Force laws are polynomial, g(d) = sum_p c_p d^p with integer powers p >= 2 (the cubic spring is
c_3 = k3).  ``ElementSet`` stores them as a (powers (P,), coefficients (n_s, P)) table that the
numba-compiled kernels ``law_force`` / ``law_force_tangent`` evaluate; numpy callers use
``ElementSet.force``, ``tangent`` and ``potential``.  A set whose powers are all odd gives an odd
f_nl (f_nl(-x) = -f_nl(x)): its NNMs are half-wave symmetric, which the shooting exploits.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .errors import NNMInputError
from .jit import jit_inline

__all__ = ["CubicSpring", "PolynomialSpring", "ElementSet", "element_law", "law_force", "law_force_tangent"]


@dataclass(frozen=True)
class CubicSpring:
    """Cubic spring with force k3 * d**3 (N) on the deformation d (m).

    Grounded (``other=None``): d = x[dof].  Relative: d = x[dof] - x[other].
    k3 in N/m^3 (negative: softening).  DOF indices are 0-based.
    """

    dof: int
    k3: float
    other: int | None = None

    def law(self):
        """Force law as {power: coefficient}: g(d) = sum c_p d^p (SI units)."""
        return {3: float(self.k3)}

    def scaled(self, factor):
        """The same spring with k3 multiplied by ``factor``."""
        return CubicSpring(dof=self.dof, other=self.other, k3=self.k3 * factor)


@dataclass(frozen=True)
class PolynomialSpring:
    """Polynomial spring with force sum_p k_p d**p (N) on the deformation d (m), integer powers p >= 2.

    Grounded (``other=None``): d = x[dof]; relative: d = x[dof] - x[other].  coefficients: {p: k_p}
    in N/m^p, e.g. {2: k2, 3: k3} for a quadratic + cubic joint (geometric nonlinearity of beams and
    plates).  The linear stiffness belongs to K.  Even powers make f_nl not odd: the NNMs then lose the
    half-wave symmetry x(t + T/2) = -x(t), and the solver shoots over the full period.
    """

    dof: int
    other: int | None = None
    coefficients: dict = field(default_factory=dict)

    def __post_init__(self):
        clean = {}
        for p, c in dict(self.coefficients).items():
            if isinstance(p, bool) or not isinstance(p, (int, np.integer)) and not (isinstance(p, str) and p.isdigit()):
                raise NNMInputError(f"PolynomialSpring power {p!r} is not an integer; use powers >= 2")
            p = int(p)
            if p < 2:
                raise NNMInputError(f"PolynomialSpring power {p} < 2; the linear stiffness belongs in K")
            try:
                c = float(c)
            except (TypeError, ValueError):
                raise NNMInputError(f"PolynomialSpring coefficient of d^{p} is {c!r}, not a number") from None
            if not np.isfinite(c):
                raise NNMInputError(f"PolynomialSpring coefficient of d^{p} is {c}, not finite")
            clean[p] = c
        if not clean:
            raise NNMInputError("PolynomialSpring needs at least one coefficient, e.g. coefficients={3: k3}")
        object.__setattr__(self, "coefficients", dict(sorted(clean.items())))

    def law(self):
        """Force law as {power: coefficient} (SI units)."""
        return dict(self.coefficients)

    def scaled(self, factor):
        """The same spring with every coefficient multiplied by ``factor``."""
        return PolynomialSpring(dof=self.dof, other=self.other,
                                coefficients={p: c * factor for p, c in self.coefficients.items()})

#: element types the models accept (the next element types are added here)
ELEMENT_TYPES = (CubicSpring, PolynomialSpring)


def element_law(element):
    """Force law of an element as {power: coefficient} (SI)."""
    return element.law()


def check_element(i, element, n):
    """One-line NNMInputError if ``element`` (index i) is not a valid element of an n-DOF model."""
    if not isinstance(element, ELEMENT_TYPES):
        raise NNMInputError(f"spring {i} is {type(element).__name__}, expected nnm_solver.CubicSpring or "
                            f"nnm_solver.PolynomialSpring")
    for which, d in (("dof", element.dof), ("other", element.other)):
        if d is None and which == "other":
            continue
        if not isinstance(d, (int, np.integer)) or isinstance(d, bool) or not 0 <= d < n:
            raise NNMInputError(f"spring {i}: {which}={d} is not a DOF of this model (valid: 0..{n - 1})")
    if element.other is not None and element.other == element.dof:
        raise NNMInputError(f"spring {i}: dof and other are both {element.dof}; a relative spring needs two DOFs")
    for p, c in element_law(element).items():
        if not np.isfinite(c):
            raise NNMInputError(f"spring {i}: coefficient of d^{p} is {c}, not finite")


class ElementSet:
    """The nonlinear elements of a model, evaluated together on their deformations d = B x.

    B (n_s, n) selection matrix; powers (P,) int64 and coefficients (n_s, P) float of the polynomial
    force laws.  ``force``, ``tangent`` and ``potential`` take d (..., n_s) and return (..., n_s) in
    N, N/m and J.
    """

    def __init__(self, elements, n):
        self.elements = list(elements)
        self.n = int(n)
        ns = len(self.elements)
        self.B = np.zeros((ns, self.n))
        for s, e in enumerate(self.elements):
            self.B[s, e.dof] = 1.0
            if e.other is not None:
                self.B[s, e.other] = -1.0
        laws = [element_law(e) for e in self.elements]
        self.powers = np.array(sorted({p for law in laws for p in law}) or [3], dtype=np.int64)
        self.coefficients = np.zeros((ns, len(self.powers)))
        for s, law in enumerate(laws):
            for p, c in law.items():
                self.coefficients[s, int(np.flatnonzero(self.powers == p)[0])] = c

    def __len__(self):
        return len(self.elements)

    @property
    def odd(self):
        """True when every force law is odd (only odd powers): f_nl(-x) = -f_nl(x)."""
        used = np.any(self.coefficients != 0.0, axis=0)
        return bool(np.all(self.powers[used] % 2 == 1))

    def force(self, d):
        d = np.asarray(d, dtype=float)
        return sum(self.coefficients[:, j] * d ** p for j, p in enumerate(self.powers))

    def tangent(self, d):
        d = np.asarray(d, dtype=float)
        return sum(p * self.coefficients[:, j] * d ** (p - 1) for j, p in enumerate(self.powers))

    def potential(self, d):
        d = np.asarray(d, dtype=float)
        return sum(self.coefficients[:, j] * d ** (p + 1) / (p + 1) for j, p in enumerate(self.powers))

    def in_basis(self, Phi):
        """(B Phi, powers, coefficients): the table for coordinates q with x = Phi q (kernels' input)."""
        return (np.ascontiguousarray(self.B @ Phi), np.ascontiguousarray(self.powers),
                np.ascontiguousarray(self.coefficients))


@jit_inline
def _ipow(x, p):
    """x ** p for an integer p >= 0 by repeated squaring (faster than pow for the small powers here)."""
    r = 1.0
    while p > 0:
        if p & 1:
            r *= x
        x *= x
        p >>= 1
    return r


@jit_inline
def law_force(d, powers, coeffs):
    """g(d) (n_s,) of the polynomial laws (numba kernel; see ElementSet)."""
    ns = d.shape[0]
    g = np.empty(ns)
    for s in range(ns):
        x = d[s]
        acc = 0.0
        for j in range(powers.shape[0]):
            c = coeffs[s, j]
            if c != 0.0:
                acc += c * x ** powers[j]
        g[s] = acc
    return g


@jit_inline
def law_force_tangent(d, powers, coeffs):
    """(g(d), g'(d)) (n_s,) each, of the polynomial laws (numba kernel)."""
    ns = d.shape[0]
    g = np.empty(ns)
    t = np.empty(ns)
    for s in range(ns):
        x = d[s]
        acc = 0.0
        dacc = 0.0
        for j in range(powers.shape[0]):
            c = coeffs[s, j]
            if c != 0.0:
                p = powers[j]
                xp1 = x ** (p - 1)
                acc += c * xp1 * x
                dacc += p * c * xp1
        g[s] = acc
        t[s] = dacc
    return g, t
