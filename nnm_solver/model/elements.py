r"""Nonlinear elements: the forces f_nl(x) of  M x'' + K x + f_nl(x) = 0, each defined once.

Every element acts on one scalar deformation d = x[dof] (grounded) or d = x[dof] - x[other]
(relative), i.e. d = B x with one row of B, and returns a restoring force g(d) (N) along that
deformation; the model force is  f_nl(x) = B^T g(B x)  and the potential  V(x) = sum_s P_s(d_s),
P' = g.  The time integrators, harmonic balance, Hill's method and the model's energy all evaluate
the elements through ``element_set.ElementSet``, built from each element's ``law()``, ``kinks()`` and
``linear_stiffness``, so a new element is added here and nowhere else.

Two law families, summed per element (an element uses one of them, the table holds both):

* polynomial, g(d) = sum_p c_p d^p with integer powers p >= 2 (the cubic spring is c_3 = k3);
* regularised kinks, g(d) = sum_j dk_j [r_w(d - b_j) - r_w(-d - b_j)]  (odd), with the smooth ramp
  r_w(x) = w log(1 + exp(x / w))  (softplus; r_w -> max(x, 0) as w -> 0).  A
  ``PiecewiseLinearSpring`` with slopes k0, k1, ... and breakpoints d1 < d2 < ... has one kink per
  breakpoint, dk_j = k_j - k_{j-1}, b_j = d_j, width w = eps * d1: its exact force
  f(d) = k0 d + sum_j dk_j sign(d) max(|d| - d_j, 0) is split into the linear slope k0, which
  belongs to the linear model (``Model.K_linear`` = K + sum k0 b^T b, used by the linear modes and
  the energy), and the nonlinear part g(d) = f(d) - k0 d, regularised, which vanishes below d1 (up
  to ~dk exp(-1 / eps)).  The element's potential is the exact integral of the regularised g,
  P(d) = sum_j dk_j [R(d - b_j) + R(-d - b_j) - 2 R(-b_j)],  R(x) = -w^2 Li2(-exp(x / w)),
  so the model's energy is conserved exactly by the regularised dynamics.  The regularisation
  error of periods is O(eps^2) (tests/test_elements.py: single-DOF bilinear oscillator against the
  closed-form period) once the amplitude is a few widths w past the breakpoint; at grazing (|d| within
  ~w of d1) the smoothed kink already acts where the exact one does not, an error of order (dk / k) eps
  (docs/elements.md: 1e-2 for a contact 1000x stiffer than the structure at eps = 1e-3).

The table of the laws that the kernels evaluate is ``element_set.ElementSet``.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

import math

from ..errors import NNMInputError, finite_number
from .settings import MODEL

__all__ = ["CubicSpring", "PolynomialSpring", "PiecewiseLinearSpring", "element_law", "check_element", "PWL_EPS"]

#: default regularisation of PiecewiseLinearSpring: kink width eps * d1 (an alias of settings.py's MODEL.pwl_eps)
PWL_EPS = MODEL.pwl_eps


@dataclass(frozen=True)
class CubicSpring:
    """Cubic spring with force k3 * d**3 (N) on the deformation d (m).

    Grounded (``other=None``): d = x[dof].  Relative: d = x[dof] - x[other].
    k3 in N/m^3 (negative: softening).  DOF indices are 0-based.
    """

    dof: int
    k3: float
    other: int | None = None

    def __post_init__(self):
        try:
            k3 = float(self.k3)
        except (TypeError, ValueError):
            raise NNMInputError(f"CubicSpring k3={self.k3!r} is not a number (N/m^3)") from None
        object.__setattr__(self, "k3", k3)           # finiteness is checked by the Model (one line)

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
        if not hasattr(self.coefficients, "items"):
            raise NNMInputError(f"PolynomialSpring coefficients must be a dict {{power: coefficient}}, e.g. "
                                f"{{2: k2, 3: k3}}; got {self.coefficients!r}")
        clean = {}
        for p, c in dict(self.coefficients).items():
            if isinstance(p, bool) or not isinstance(p, (int, np.integer)) and not (isinstance(p, str) and p.isdigit()):
                raise NNMInputError(f"PolynomialSpring power {p!r} is not an integer; use powers >= 2")
            p = int(p)
            if p < 2:
                raise NNMInputError(f"PolynomialSpring power {p} < 2; the linear stiffness belongs in K")
            clean[p] = finite_number(c, f"PolynomialSpring coefficient of d^{p}")
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

def _numbers(name, values):
    try:
        out = tuple(float(v) for v in values)
    except (TypeError, ValueError):
        raise NNMInputError(f"PiecewiseLinearSpring {name} must be a list of numbers, got {values!r}") from None
    if not all(math.isfinite(v) for v in out):
        raise NNMInputError(f"PiecewiseLinearSpring {name} {list(out)} contains NaN or infinite values")
    return out


def _side(k, b, suffix="", linear_ok=False):
    """Check one side's law (stiffnesses k, breakpoints b); ``suffix`` names the arguments.  linear_ok:
    the side may have no breakpoint (stiffnesses = [k0]: linear on that side of an asymmetric law)."""
    if not k:
        raise NNMInputError(f"PiecewiseLinearSpring needs stiffnesses{suffix} = [k0, ...] (N/m)")
    if not b and not linear_ok:
        raise NNMInputError(f"PiecewiseLinearSpring needs at least one breakpoint{suffix} (stiffnesses{suffix}=[k0, k1], "
                            f"breakpoints{suffix}=[d1])")
    if len(k) != len(b) + 1:
        raise NNMInputError(f"PiecewiseLinearSpring has {len(k)} stiffnesses{suffix} for {len(b)} breakpoints{suffix}; "
                            f"it needs one more stiffness than breakpoints")
    if b and b[0] <= 0:
        raise NNMInputError(f"PiecewiseLinearSpring breakpoint{suffix} {b[0]} is not positive; breakpoints are "
                            f"distances |d| > 0 from the rest position")
    if any(b2 <= b1 for b1, b2 in zip(b, b[1:])):
        raise NNMInputError(f"PiecewiseLinearSpring breakpoints{suffix} {list(b)} are not strictly increasing")


def _kink_rows(k, b, w, side=None):
    """(dk_j, b_j, w[, side]) rows of one side's law: slope jumps k_j - k_{j-1} at b_j."""
    tail = () if side is None else (float(side),)
    return [(k1 - k0, bj, w) + tail for k0, k1, bj in zip(k, k[1:], b)]


@dataclass(frozen=True)
class PiecewiseLinearSpring:
    """Piecewise-linear spring: slope k0 for |d| < d1, k1 for d1 <= |d| < d2, ... (N/m), d (m).

    Grounded (``other=None``): d = x[dof]; relative: d = x[dof] - x[other].  stiffnesses [k0, k1, ...]
    (one more than breakpoints), breakpoints [d1, d2, ...] > 0 strictly increasing (m).  Bilinear
    joints, softening (k1 < k0) or hardening past a threshold, clearances (k0 = 0).  The element acts
    in addition to K: the linear modes use K plus k0 along d (``Model.K_linear``), the nonlinear force
    is the rest, f(d) - k0 d, with each kink smoothed over a width eps * d1 (module doc).

    By default the law is odd (the same in tension d > 0 and compression d < 0).  An asymmetric joint
    gives the compression side its own law: ``stiffnesses_negative = [k0, k1', ...]`` and
    ``breakpoints_negative = [d1', ...]`` (distances |d| > 0, m), applied for d < 0; the slope k0 at
    d = 0 is shared (the linear modes need one), so stiffnesses_negative[0] must equal k0.  One side
    may be linear (no breakpoints: stiffnesses [k0], breakpoints []), e.g. a contact that engages in
    compression only.  Its kinks
    are smoothed over eps * d1'.  An asymmetric force is not odd: the NNMs lose the half-wave symmetry
    and the solver shoots over the full period, as for even polynomial powers.
    """

    dof: int
    other: int | None = None
    stiffnesses: tuple = ()
    breakpoints: tuple = ()
    eps: float = MODEL.pwl_eps
    stiffnesses_negative: tuple | None = None
    breakpoints_negative: tuple | None = None

    def __post_init__(self):
        k = _numbers("stiffnesses", self.stiffnesses)
        b = _numbers("breakpoints", self.breakpoints)
        kn = bn = None
        if (self.stiffnesses_negative is None) != (self.breakpoints_negative is None):
            raise NNMInputError("PiecewiseLinearSpring: give both stiffnesses_negative and breakpoints_negative "
                                "(the compression side's law) or neither (odd law)")
        if self.stiffnesses_negative is None:
            _side(k, b)
        else:
            kn = _numbers("stiffnesses_negative", self.stiffnesses_negative)
            bn = _numbers("breakpoints_negative", self.breakpoints_negative)
            _side(k, b, linear_ok=True)
            _side(kn, bn, "_negative", linear_ok=True)
            if not b and not bn:
                raise NNMInputError("PiecewiseLinearSpring needs at least one breakpoint (on either side)")
            if kn[0] != k[0]:
                raise NNMInputError(f"PiecewiseLinearSpring stiffnesses_negative[0] = {kn[0]} differs from "
                                    f"stiffnesses[0] = {k[0]}; the slope k0 at d = 0 is shared by both sides")
            if kn == k and bn == b:
                kn = bn = None                          # the odd law, stored as such
        try:
            eps = float(self.eps)
        except (TypeError, ValueError):
            raise NNMInputError(f"PiecewiseLinearSpring eps={self.eps!r} is not a number") from None
        if not 0 < eps < 0.5:
            raise NNMInputError(f"PiecewiseLinearSpring eps={eps} must be in (0, 0.5) (kink width eps * d1)")
        object.__setattr__(self, "stiffnesses", k)
        object.__setattr__(self, "breakpoints", b)
        object.__setattr__(self, "eps", eps)
        object.__setattr__(self, "stiffnesses_negative", kn)
        object.__setattr__(self, "breakpoints_negative", bn)

    def law(self):
        """Polynomial part of the force law: none ({}); the kinks are in ``kinks()``."""
        return {}

    @property
    def linear_stiffness(self):
        """k0 (N/m): the slope at d = 0, which the linear model adds to K."""
        return self.stiffnesses[0]

    @property
    def symmetric(self):
        """True for the odd law (the same in tension and compression)."""
        return self.stiffnesses_negative is None

    def kinks(self):
        """Kink rows of the law table (laws.py): odd law [(dk_j, b_j, w)], slope jumps (N/m), breakpoints
        (m) and smoothing width w = eps * d1 (m); asymmetric law [(dk_j, b_j, w, +1)] for tension
        followed by [(dk'_j, b'_j, w', -1)] for compression (w' = eps * d1')."""
        if self.symmetric:
            return _kink_rows(self.stiffnesses, self.breakpoints, self.eps * self.breakpoints[0])
        rows = []
        for k, b, side in ((self.stiffnesses, self.breakpoints, +1),
                           (self.stiffnesses_negative, self.breakpoints_negative, -1)):
            if b:                                      # a side without breakpoints is linear (slope k0)
                rows += _kink_rows(k, b, self.eps * b[0], side)
        return rows

    def exact_force(self, d):
        """The unregularised force f(d) (N), including k0 d (reference for tests and plots)."""
        d = np.asarray(d, dtype=float)
        f = self.stiffnesses[0] * d
        for dk, b, _, *side in self.kinks():
            side = side[0] if side else 0.0
            reach = np.maximum(np.abs(d) - b, 0.0) * (1.0 if side == 0 else (np.sign(d) == side))
            f = f + dk * np.sign(d) * reach
        return f

    def scaled(self, factor):
        """The same spring with every stiffness multiplied by ``factor``."""
        neg = {} if self.symmetric else dict(stiffnesses_negative=[k * factor for k in self.stiffnesses_negative],
                                             breakpoints_negative=self.breakpoints_negative)
        return PiecewiseLinearSpring(dof=self.dof, other=self.other, stiffnesses=[k * factor for k in self.stiffnesses],
                                     breakpoints=self.breakpoints, eps=self.eps, **neg)


#: element types the models accept (the next element types are added here; PolynomialStiffness: coupled.py)
ELEMENT_TYPES = (CubicSpring, PolynomialSpring, PiecewiseLinearSpring)


def element_law(element):
    """Force law of an element as {power: coefficient} (SI)."""
    return element.law()


def check_element(i, element, n):
    """One-line NNMInputError if ``element`` (index i) is not a valid element of an n-DOF model."""
    from .coupled import PolynomialStiffness

    if isinstance(element, PolynomialStiffness):
        try:
            element.matrix(n)
        except NNMInputError as exc:
            raise NNMInputError(f"spring {i}: {exc}") from None
        return
    if not isinstance(element, ELEMENT_TYPES):
        raise NNMInputError(f"spring {i} is {type(element).__name__}, expected nnm_solver.CubicSpring, "
                            f"nnm_solver.PolynomialSpring, nnm_solver.PiecewiseLinearSpring or "
                            f"nnm_solver.PolynomialStiffness")
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
