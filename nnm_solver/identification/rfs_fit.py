r"""Force laws fitted to a restoring force surface by linear least squares, and handed to a model.

Every law is elastic + viscous + offset:  f_r(x, v) = g(x) + c v + f0,  with x the connection's relative
displacement (m), v its velocity (m/s), c (N s/m) and f0 (N) absorbing the damping and any force offset
of the sensors (the paper's eq. 22 is the elastic part of the cubic law).  The elastic parts:

* ``"linear"``     g = k x;
* ``"cubic"``      g = k x + k3 x^3  (seed eq. 22; k3 < 0: softening);
* ``"polynomial"`` g = sum_p k_p x^p over ``powers`` (default 1, 2, 3);
* ``"piecewise_linear"``  g = k0 x + sum_j (k_j - k_{j-1}) sign(x) max(|x| - d_j, 0): slopes k0, k1, ...
  (N/m) past the breakpoints 0 < d1 < d2 < ... (m), the exact law of ``PiecewiseLinearSpring``.  Given
  ``breakpoints``, the fit is linear; otherwise ``n_breakpoints`` (default 1) are found by minimising the
  residual over them (bounded scalar search for one, Nelder-Mead over the gaps for more) with the slopes
  solved for at each trial (variable projection).

The residual is the relative RMS misfit ||f - f_fit|| / ||f - mean f||; the standard errors assume
independent samples (noisy, oversampled data make them optimistic: they are a scale, not a bound).

``FittedLaw.spring(dof, other)`` is the model element of the nonlinear part (the linear stiffness k belongs
in K); ``FittedLaw.add_to(model, dof, other)`` returns the model with the connection added: K + k b^T b
(b = e_dof - e_other) and the element.  DOF indices are 0-based, as everywhere in the model layer.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..errors import NNMInputError

__all__ = ["FittedLaw", "fit_law", "LAWS"]

LAWS = ("cubic", "linear", "polynomial", "piecewise_linear")


@dataclass(frozen=True)
class FittedLaw:
    """A force law fitted to a restoring force surface (module doc).

    kind : one of LAWS.  k : linear stiffness (N/m; k0 of a piecewise-linear law).  k3 : cubic coefficient
    (N/m^3; None unless the law has an x^3 term).  c : viscous coefficient (N s/m).  offset : f0 (N).
    coefficients : {power: k_p} of the polynomial part (SI).  stiffnesses, breakpoints : the piecewise-linear
    law (N/m, m).  residual : relative RMS misfit.  stderr : {name: standard error} of the fitted
    coefficients.  samples : number of samples fitted.
    """

    kind: str
    k: float
    c: float
    offset: float
    residual: float
    samples: int
    k3: float | None = None
    coefficients: dict = field(default_factory=dict)
    stiffnesses: tuple = ()
    breakpoints: tuple = ()
    stderr: dict = field(default_factory=dict)

    def elastic_force(self, x):
        """g(x) (N) at relative displacements x (m), without damping or offset."""
        x = np.asarray(x, dtype=float)
        if self.kind == "piecewise_linear":
            return _pwl_columns(x, self.breakpoints) @ _pwl_slope_jumps(self.stiffnesses)
        return sum(c * x ** p for p, c in self.coefficients.items()) + 0.0 * x

    def force(self, x, v=0.0):
        """The fitted restoring force g(x) + c v + f0 (N)."""
        return self.elastic_force(x) + self.c * np.asarray(v, dtype=float) + self.offset

    def spring(self, dof, other=None):
        """The model element of the law's nonlinear part, g(d) - k d: a CubicSpring (cubic), PolynomialSpring
        (powers >= 2) or PiecewiseLinearSpring with slope 0 at d = 0 and the fitted slope changes.  dof, other:
        0-based DOF indices (other None: grounded).  The linear stiffness k goes into K (``add_to``)."""
        from ..model import CubicSpring, PiecewiseLinearSpring, PolynomialSpring

        if self.kind == "piecewise_linear":
            k0 = self.stiffnesses[0]
            return PiecewiseLinearSpring(dof=dof, other=other, stiffnesses=[k - k0 for k in self.stiffnesses],
                                         breakpoints=list(self.breakpoints))
        nl = {p: c for p, c in self.coefficients.items() if p >= 2}
        if not nl:
            raise NNMInputError(f"the {self.kind} law has no nonlinear term; add its k = {self.k:.6g} N/m to K instead")
        if set(nl) == {3}:
            return CubicSpring(dof=dof, other=other, k3=nl[3])
        return PolynomialSpring(dof=dof, other=other, coefficients=nl)

    def add_to(self, model, dof, other=None, linear=True):
        """``model`` with this connection between DOFs ``dof`` and ``other`` (0-based; None: grounded): the
        element of ``spring`` appended and, if ``linear``, K + k b^T b with b = e_dof - e_other (leave
        ``linear=False`` when K already holds the connection's linear stiffness)."""
        import scipy.sparse as sp

        from ..model import Model

        element = self.spring(dof, other)
        K = model.K
        if linear and self.k != 0.0:
            b = np.zeros(model.n)
            b[dof] = 1.0
            if other is not None:
                b[other] = -1.0
            nz = np.flatnonzero(b)
            delta = sp.coo_matrix((self.k * np.outer(b[nz], b[nz]).ravel(), (np.repeat(nz, len(nz)), np.tile(nz, len(nz)))),
                                  shape=K.shape)
            K = (K + delta).tocsr() if sp.issparse(K) else K + delta.toarray()
        return Model(model.M, K, list(model.springs) + [element], dof_labels=model.dof_labels,
                     mode_labels=model.mode_labels, mesh=model.mesh, name=model.name, info=model.info)


def _pwl_columns(x, breakpoints):
    """[x, sign(x) max(|x| - d_j, 0) ...] (N, 1 + n_b)."""
    cols = [x] + [np.sign(x) * np.maximum(np.abs(x) - d, 0.0) for d in breakpoints]
    return np.stack(cols, axis=-1)


def _pwl_slope_jumps(stiffnesses):
    k = np.asarray(stiffnesses, dtype=float)
    return np.concatenate([k[:1], np.diff(k)])


def _solve(A, f):
    """Least squares with column scaling: (coefficients, residual vector, standard errors)."""
    scale = np.linalg.norm(A, axis=0)
    if np.any(scale == 0):
        raise NNMInputError("rfs fit: a column of the law is zero on the data (no motion, or the breakpoints lie "
                            "beyond the largest displacement)")
    As = A / scale
    coef, *_ = np.linalg.lstsq(As, f, rcond=None)
    r = f - As @ coef
    dof = max(len(f) - A.shape[1], 1)
    sigma2 = float(r @ r) / dof
    try:
        cov = np.linalg.inv(As.T @ As) * sigma2
        se = np.sqrt(np.maximum(np.diag(cov), 0.0)) / scale
    except np.linalg.LinAlgError:
        se = np.full(A.shape[1], np.inf)
    return coef / scale, r, se


def _relative(r, f):
    return float(np.linalg.norm(r) / max(np.linalg.norm(f - np.mean(f)), 1e-300))


def _powers(powers):
    try:
        p = sorted({int(q) for q in powers})
    except (TypeError, ValueError):
        raise NNMInputError(f"rfs fit: powers must be integers >= 1, got {powers!r}") from None
    if not p or p[0] < 1:
        raise NNMInputError(f"rfs fit: powers must be integers >= 1, got {powers!r}")
    return p


def _fit_polynomial(kind, powers, x, v, f):
    A = np.column_stack([x ** p for p in powers] + [v, np.ones_like(x)])
    coef, r, se = _solve(A, f)
    coefficients = {p: float(c) for p, c in zip(powers, coef)}
    names = [f"k{p}" if p != 1 else "k" for p in powers] + ["c", "offset"]
    return FittedLaw(kind=kind, k=coefficients.get(1, 0.0), c=float(coef[-2]), offset=float(coef[-1]),
                     residual=_relative(r, f), samples=len(f), k3=coefficients.get(3), coefficients=coefficients,
                     stderr=dict(zip(names, map(float, se))))


def _fit_pwl_at(breakpoints, x, v, f):
    A = np.column_stack([_pwl_columns(x, breakpoints), v, np.ones_like(x)])
    return _solve(A, f)


def _fit_pwl(x, v, f, breakpoints=None, n_breakpoints=1):
    xmax = float(np.max(np.abs(x)))
    if breakpoints is None:
        if isinstance(n_breakpoints, bool) or not isinstance(n_breakpoints, (int, np.integer)) or n_breakpoints < 1:
            raise NNMInputError(f"rfs fit: n_breakpoints must be an integer >= 1, got {n_breakpoints!r}")
        breakpoints = _find_breakpoints(x, v, f, int(n_breakpoints), xmax)
    try:
        b = [float(d) for d in breakpoints]
    except (TypeError, ValueError):
        raise NNMInputError(f"rfs fit: breakpoints must be a list of numbers (m), got {breakpoints!r}") from None
    if not b or b[0] <= 0 or any(b2 <= b1 for b1, b2 in zip(b, b[1:])) or b[-1] >= xmax:
        raise NNMInputError(f"rfs fit: breakpoints {b} must be increasing in (0, {xmax:.6g}) m, the largest "
                            f"measured displacement")
    coef, r, se = _fit_pwl_at(b, x, v, f)
    nb = len(b)
    stiff = tuple(float(s) for s in np.cumsum(coef[:nb + 1]))
    names = ["k"] + [f"dk{j + 1}" for j in range(nb)] + ["c", "offset"]
    return FittedLaw(kind="piecewise_linear", k=stiff[0], c=float(coef[-2]), offset=float(coef[-1]),
                     residual=_relative(r, f), samples=len(f), stiffnesses=stiff, breakpoints=tuple(b),
                     stderr=dict(zip(names, map(float, se))))


def _find_breakpoints(x, v, f, nb, xmax):
    """Breakpoints minimising the residual, searched in (0.02, 0.95) xmax (variable projection)."""
    from scipy.optimize import minimize, minimize_scalar

    lo, hi = 0.02 * xmax, 0.95 * xmax

    def cost(b):
        return float(np.sum(_fit_pwl_at(b, x, v, f)[1] ** 2))

    if nb == 1:
        grid = np.linspace(lo, hi, 40)
        j = int(np.argmin([cost([d]) for d in grid]))
        a, c = grid[max(j - 1, 0)], grid[min(j + 1, len(grid) - 1)]
        res = minimize_scalar(lambda d: cost([d]), bounds=(a, c), method="bounded", options={"xatol": 1e-6 * xmax})
        return [float(res.x)]

    def unpack(z):                                 # gaps as softplus of z: increasing breakpoints in (0, inf)
        return np.cumsum(np.logaddexp(0.0, z)) * (hi / (nb + 1))

    res = minimize(lambda z: cost(unpack(z)) if unpack(z)[-1] < xmax else np.inf,
                   np.full(nb, np.log(np.e - 1.0)), method="Nelder-Mead", options={"xatol": 1e-8, "fatol": 1e-14})
    return [float(d) for d in unpack(res.x)]


def fit_law(law, x, v, f, **options):
    """Fit ``law`` (one of LAWS) to samples x (m), v (m/s), f (N); see the module doc."""
    if law not in LAWS:
        raise NNMInputError(f"rfs fit: law {law!r} is not one of {', '.join(LAWS)}")
    if len(x) < 16:
        raise NNMInputError(f"rfs fit: only {len(x)} valid samples; measure a longer record")
    allowed = {"polynomial": {"powers"}, "piecewise_linear": {"breakpoints", "n_breakpoints"}}.get(law, set())
    extra = set(options) - allowed
    if extra:
        raise NNMInputError(f"rfs fit: unknown option(s) {sorted(extra)} for law {law!r}"
                            + (f" (it takes {sorted(allowed)})" if allowed else ""))
    if law == "piecewise_linear":
        return _fit_pwl(x, v, f, **options)
    powers = {"linear": [1], "cubic": [1, 3]}.get(law) or _powers(options.get("powers", (1, 2, 3)))
    return _fit_polynomial(law, powers, x, v, f)
