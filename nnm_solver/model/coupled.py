r"""A polynomial stiffness in several coordinates (NLvib's convention): one force that couples m deformations.

For the m deformations  d = directions @ x[dofs]  (m; default: every DOF, directions = identity, so d = x)

    z_i = prod_j d_j ** exponents[i, j]          (n_z monomials, exponents >= 0 integers)
    g   = coefficients^T z                       (m,) in N (SI: coefficients in N / m^p_i)
    f_nl += W^T g(W x),   W = directions scattered on dofs   (m, n)

The element is conservative when g is a gradient, g = grad V; then V is the sum over the monomials of
z_i (C_i . d) / (p_i + 1), p_i = sum_j exponents[i, j] the degree of monomial i (Euler's identity on each
homogeneous part: d . g_p = (p + 1) V_p).  The construction checks that the tangent T = dg/dd is symmetric at a
few random deformations (relative 1e-8): NNMs need a potential.  Monomials of degree < 2 are refused (the
linear stiffness belongs in K, a constant force would move the equilibrium).  The force is odd (f(-x) = -f(x))
iff every monomial with a non-zero coefficient has an odd degree.

Evaluation (``CoupledGroup``): the elements of a model with the same exponent table are one group whose
deformations are an (..., G, m) array, evaluated by numpy in one vectorised pass (a von Karman beam given as
one element per Gauss point is one group).  The time integrators use the flat table of ``coupled_table`` in
their numba kernel (``coupled_force_tangent``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..errors import NNMInputError
from ..jit import jit_inline
from .laws import _ipow
from .settings import MODEL

__all__ = ["PolynomialStiffness", "CoupledGroup", "coupled_groups", "coupled_table", "coupled_force_tangent"]


def _int_matrix(value, what):
    try:
        a = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise NNMInputError(f"PolynomialStiffness {what} must be a numeric matrix, got {value!r}") from None
    if a.ndim == 1:
        a = a[None, :] if what == "exponents" else a
    if a.ndim != 2 or a.size == 0:
        raise NNMInputError(f"PolynomialStiffness {what} must be a non-empty 2-D array (n_z, m), got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise NNMInputError(f"PolynomialStiffness {what} contains NaN or infinite values")
    return a


def _monomials(d, ex, derivative=True):
    """z (..., n_z) and dz/dd (..., n_z, m) of the monomials z_i = prod_j d_j^ex[i, j] at d (..., m); exact at
    d_j = 0 (the factor j of dz_i/dd_j is ex d_j^(ex - 1), 0 for ex = 0).  The powers d_j^k, k <= max ex, by
    repeated products (a table), then gathered: no pow calls.  derivative=False: dz is None (not computed)."""
    d = np.asarray(d, dtype=float)
    nz, m = ex.shape
    top = int(ex.max(initial=0))
    pw = np.empty(d.shape + (top + 1,))                              # pw[..., j, k] = d_j^k
    pw[..., 0] = 1.0
    for k in range(1, top + 1):
        pw[..., k] = pw[..., k - 1] * d
    cols = np.arange(m)[None, :]
    P = pw[..., cols, ex]                                            # (..., n_z, m) factors d_j^e_ij
    z = np.prod(P, axis=-1)
    if not derivative:
        return z, None
    dz = np.empty(P.shape)
    low = ex * pw[..., cols, np.maximum(ex - 1, 0)]                  # d/dd_j of factor j (0 where e_ij = 0)
    for j in range(m):
        Q = P.copy()
        Q[..., j] = low[..., j]
        dz[..., j] = np.prod(Q, axis=-1)
    return z, dz


@dataclass(frozen=True, eq=False)
class PolynomialStiffness:
    """Polynomial stiffness in several coordinates: g(d) = coefficients^T z(d), z_i = prod_j d_j^exponents[i, j].

    exponents (n_z, m) non-negative integers; coefficients (n_z, m) in SI (N / m^p, p the monomial's degree);
    dofs (k,) 0-based DOF indices and directions (m, k): d = directions @ x[dofs] (defaults: every DOF, the
    identity: then m = n, NLvib's plain case).  The model force is f_nl = W^T g(W x) (module docstring).  The force
    must derive from a potential (checked: its tangent is symmetric).  Passed among a Model's springs.
    """

    exponents: np.ndarray
    coefficients: np.ndarray
    dofs: tuple | None = None
    directions: np.ndarray | None = None

    def __post_init__(self):
        ex = _int_matrix(self.exponents, "exponents")
        if np.any(ex < 0) or np.any(ex != np.round(ex)):
            raise NNMInputError(f"PolynomialStiffness exponents must be non-negative integers, got {ex.tolist()}")
        ex = ex.astype(np.int64)
        C = _int_matrix(self.coefficients, "coefficients")
        if C.shape != ex.shape:
            raise NNMInputError(f"PolynomialStiffness coefficients have shape {C.shape}, exponents {ex.shape}; "
                                f"both must be (n_z monomials, m coordinates)")
        degree = ex.sum(axis=1)
        low = np.flatnonzero((degree < 2) & np.any(C != 0.0, axis=1))
        if low.size:
            raise NNMInputError(f"PolynomialStiffness monomial {int(low[0]) + 1} has degree {int(degree[low[0]])} < 2; "
                                f"the linear stiffness belongs in K (and a constant force moves the equilibrium)")
        m = ex.shape[1]
        dofs = self.dofs
        if dofs is not None:
            try:
                arr = np.asarray(dofs)
                ok = arr.ndim == 1 and arr.size > 0 and all(isinstance(v, (int, np.integer)) and not isinstance(v, bool)
                                                            for v in arr.tolist())
            except (TypeError, ValueError):
                ok = False
            if not ok:
                raise NNMInputError(f"PolynomialStiffness dofs must be a list of 0-based DOF indices, got {dofs!r}")
            dofs = tuple(int(v) for v in arr)
            if min(dofs) < 0 or len(set(dofs)) != len(dofs):
                raise NNMInputError(f"PolynomialStiffness dofs {list(dofs)} must be distinct non-negative indices")
        D = self.directions
        if D is not None:
            D = _int_matrix(D, "directions")
            if D.shape[0] != m:
                raise NNMInputError(f"PolynomialStiffness directions have {D.shape[0]} rows, the exponents {m} "
                                    f"columns: one row per coordinate d_j")
            if dofs is not None and D.shape[1] != len(dofs):
                raise NNMInputError(f"PolynomialStiffness directions have {D.shape[1]} columns for {len(dofs)} dofs")
        elif dofs is not None and len(dofs) != m:
            raise NNMInputError(f"PolynomialStiffness has {len(dofs)} dofs for {m} coordinates; give directions "
                                f"(m, k) or one dof per coordinate")
        for a in (ex, C) + ((D,) if D is not None else ()):
            a.setflags(write=False)
        object.__setattr__(self, "exponents", ex)
        object.__setattr__(self, "coefficients", C)
        object.__setattr__(self, "dofs", dofs)
        object.__setattr__(self, "directions", D)
        asym = self.asymmetry()
        if asym > MODEL.symmetry_tol:
            raise NNMInputError(f"PolynomialStiffness is not conservative: its tangent dg/dd is not symmetric "
                                f"(relative asymmetry {asym:.2g} > {MODEL.symmetry_tol:g}); NNMs need a force "
                                f"with a potential")

    @property
    def m(self):
        """Number of coordinates d_j the element acts on."""
        return self.exponents.shape[1]

    @property
    def degrees(self):
        """Degree p_i of each monomial (n_z,)."""
        return self.exponents.sum(axis=1)

    @property
    def odd(self):
        """True when every monomial with a non-zero coefficient has an odd degree (then g(-d) = -g(d))."""
        used = np.any(self.coefficients != 0.0, axis=1)
        return bool(np.all(self.degrees[used] % 2 == 1))

    def asymmetry(self, points=4, seed=0):
        """max |T - T^T| / max |T| of the tangent T = dg/dd over a few random deformations (0: conservative)."""
        rng = np.random.default_rng(seed)
        d = rng.standard_normal((points, self.m))
        T = _monomials(d, self.exponents)[1].transpose(0, 2, 1) @ self.coefficients     # (points, m_b, m_a) = T^T
        scale = float(np.max(np.abs(T)))
        return float(np.max(np.abs(T - T.transpose(0, 2, 1)))) / scale if scale > 0 else 0.0

    def matrix(self, n):
        """W (m, n): the deformations d = W x of an n-DOF model (NNMInputError for DOFs out of range)."""
        dofs = tuple(range(n)) if self.dofs is None else self.dofs
        D = np.eye(len(dofs)) if self.directions is None else self.directions
        if D.shape != (self.m, len(dofs)):
            raise NNMInputError(f"PolynomialStiffness has {self.m} coordinates and no dofs, the model {n} DOFs; give "
                                f"dofs=[...] or directions of shape ({self.m}, {n})")
        if max(dofs) >= n:
            raise NNMInputError(f"PolynomialStiffness dof {max(dofs)} is not a DOF of this model (valid: 0..{n - 1})")
        W = np.zeros((self.m, n))
        W[:, list(dofs)] = D
        return W

    def force(self, d):
        """g(d) (..., m) in N at the deformations d (..., m) in m."""
        return _monomials(d, self.exponents, False)[0] @ self.coefficients

    def tangent(self, d):
        """T = dg/dd (..., m, m) in N/m: T[a, b] = sum_i C[i, a] dz_i/dd_b."""
        dz = _monomials(d, self.exponents)[1]
        return np.einsum("...ib,ia->...ab", dz, self.coefficients)

    def potential(self, d):
        """V(d) (...) in J: sum_i z_i (C_i . d) / (p_i + 1)."""
        d = np.asarray(d, dtype=float)
        z = _monomials(d, self.exponents, False)[0]
        return np.sum(z * (d @ self.coefficients.T) / (self.degrees + 1.0), axis=-1)

    def law(self):
        """No scalar force law (the element is not a spring on one deformation): {}."""
        return {}

    def scaled(self, factor):
        """The same element with every coefficient multiplied by ``factor``."""
        return PolynomialStiffness(self.exponents, self.coefficients * factor, dofs=self.dofs,
                                   directions=self.directions)


class CoupledGroup:
    """Elements with the same exponent table, evaluated together: rows (G, m) their rows in the deformation vector
    of the ElementSet, exponents (n_z, m), coefficients (G, n_z, m), degrees (n_z,)."""

    def __init__(self, rows, exponents, coefficients):
        self.rows = np.asarray(rows, dtype=np.int64)
        self.exponents = exponents
        self.coefficients = np.asarray(coefficients, dtype=float)
        self.degrees = exponents.sum(axis=1).astype(float)

    def force(self, d):
        """g (..., G, m) at the full deformation vector d (..., n_d)."""
        z = _monomials(d[..., self.rows], self.exponents, False)[0]           # (..., G, n_z)
        return np.einsum("...gi,gia->...ga", z, self.coefficients)

    def tangent(self, d):
        """T (..., G, m, m)."""
        dz = _monomials(d[..., self.rows], self.exponents)[1]                 # (..., G, n_z, m)
        return np.einsum("...gib,gia->...gab", dz, self.coefficients)

    def potential(self, d):
        """V (..., G)."""
        dd = d[..., self.rows]
        z = _monomials(dd, self.exponents, False)[0]
        return np.sum(z * np.einsum("...ga,gia->...gi", dd, self.coefficients) / (self.degrees + 1.0), axis=-1)

    def abs_potential(self, d):
        """Bound on |V| (..., G): every coefficient and deformation taken positive."""
        dd = np.abs(d[..., self.rows])
        z = _monomials(dd, self.exponents, False)[0]
        return np.sum(z * np.einsum("...ga,gia->...gi", dd, np.abs(self.coefficients)) / (self.degrees + 1.0), axis=-1)


def coupled_groups(elements, first_row):
    """CoupledGroups of the PolynomialStiffness ``elements`` whose deformations follow row ``first_row`` of the
    deformation vector in the elements' order."""
    groups = {}
    row = first_row
    for e in elements:
        key = (e.exponents.shape, e.exponents.tobytes())
        groups.setdefault(key, (e.exponents, [], []))
        groups[key][1].append(np.arange(row, row + e.m))
        groups[key][2].append(e.coefficients)
        row += e.m
    return [CoupledGroup(np.array(r), ex, np.array(c)) for ex, r, c in groups.values()]


def coupled_table(elements, first_row):
    """The flat table of the numba kernel: index (E, 4) int64 rows (first row, m, n_z, offset) and exponents,
    coefficients (sum n_z m,) int64 / float, element e's [i, j] entry at offset + i m + j."""
    index = np.zeros((len(elements), 4), dtype=np.int64)
    ex, co = [], []
    row, off = first_row, 0
    for k, e in enumerate(elements):
        nz, m = e.exponents.shape
        index[k] = (row, m, nz, off)
        ex.append(e.exponents.ravel())
        co.append(e.coefficients.ravel())
        row += m
        off += nz * m
    cat = (lambda a, t: np.ascontiguousarray(np.concatenate(a), dtype=t) if a else np.zeros(0, dtype=t))
    return index, cat(ex, np.int64), cat(co, float)


@jit_inline
def coupled_force_tangent(d, index, ex, co, g, T):
    """Adds the coupled elements' forces to g (n_d,) and their tangent blocks to T (n_d, width >= m) (numba kernel),
    the block of the element whose rows start at r0 in its rows, local columns:
    g[r0 + a] += sum_i C[i, a] z_i,  T[r0 + a, b] += sum_i C[i, a] dz_i/dd_b."""
    for e in range(index.shape[0]):
        r0, m, nz, off = index[e, 0], index[e, 1], index[e, 2], index[e, 3]
        for i in range(nz):
            base = off + i * m
            z = 1.0
            for j in range(m):
                z *= _ipow(d[r0 + j], ex[base + j])
            for a in range(m):
                g[r0 + a] += co[base + a] * z
            for b in range(m):
                p = ex[base + b]
                if p == 0:
                    continue
                dzb = p * _ipow(d[r0 + b], p - 1)
                for j in range(m):
                    if j != b:
                        dzb *= _ipow(d[r0 + j], ex[base + j])
                for a in range(m):
                    T[r0 + a, b] += co[base + a] * dzb
